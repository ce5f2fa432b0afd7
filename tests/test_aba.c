/* test_aba.c -- the exact solve by the articulated-body algorithm (src/solve/aba.c)
 * against the DCA back-substitution over the assembly tree (an independent
 * algorithm; both are compared with the dense Eigen solver in
 * tests/reference), a closed form, the tree left stale and recomputed, and
 * the errors of aqs_linkage_set/get_exact_solver. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "linkage.h"

/* A random tree of n bodies with every joint type (fixed ones welded),
 * a floating or fixed base, gravity, body forces and joint forces. The same
 * seed gives the same linkage. */
static aqs_linkage *random_tree(uint64_t seed, int32_t n, int floating, int32_t solver)
{
    static const int32_t kinds[] = {AQS_JOINT_REVOLUTE,  AQS_JOINT_PRISMATIC,   AQS_JOINT_SPHERICAL,
                                    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL, AQS_JOINT_PLANAR,
                                    AQS_JOINT_FIXED,     AQS_JOINT_REVOLUTE};
    uint64_t rng = seed;
    aqs_linkage *L = test_new_linkage();
    int32_t i, j, nq;
    double g[3] = {0.3, -9.81, 0.2}, *q;
    assert_int_equal(aqs_linkage_set_exact_solver(L, solver), AQS_OK);
    for (i = 0; i < n; i++)
        test_add_body(L, test_uniform(&rng, 0.2, 3.0), test_uniform(&rng, -0.3, 0.3), test_uniform(&rng, -0.3, 0.3),
                      test_uniform(&rng, -0.3, 0.3), test_uniform(&rng, 0.05, 0.3));
    for (i = 0; i < n; i++) {
        double pos[3], quat[4], axis[3];
        int32_t type, parent;
        for (j = 0; j < 3; j++) {
            pos[j] = test_uniform(&rng, -0.8, 0.8);
            axis[j] = test_uniform(&rng, -1, 1);
        }
        test_random_quat(&rng, quat);
        if (i == 0) {
            parent = AQS_WORLD;
            type = floating ? AQS_JOINT_FREE : AQS_JOINT_REVOLUTE;
        } else {
            parent = (int32_t)test_uniform(&rng, i / 2.0, i); /* a bushy tree, deep too */
            type = kinds[(int)test_uniform(&rng, 0, sizeof kinds / sizeof kinds[0])];
        }
        assert_int_equal(aqs_joint_add(L, type, parent, i, pos, quat, axis, NULL), AQS_OK);
    }
    if (aqs_linkage_finalize(L) != AQS_OK) fail_msg("finalize: %s", aqs_linkage_last_error(L));
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    q = malloc(sizeof(double) * (size_t)(nq + 1));
    assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
    for (j = 0; j < n; j++) {
        int32_t off, m, k;
        assert_int_equal(aqs_joint_get_layout(L, j, &off, &m, NULL, NULL), AQS_OK);
        if (m == 4 || m == 7) {
            test_random_quat(&rng, q + off + (m == 7 ? 3 : 0));
            for (k = 0; k < (m == 7 ? 3 : 0); k++) q[off + k] = test_uniform(&rng, -1, 1);
        } else {
            for (k = 0; k < m; k++) q[off + k] = test_uniform(&rng, -1.2, 1.2);
        }
    }
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
    free(q);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    for (i = 0; i < 1 + n / 4; i++) {
        double f[3], p[3], t[3];
        for (j = 0; j < 3; j++) {
            f[j] = test_uniform(&rng, -4, 4);
            p[j] = test_uniform(&rng, -0.5, 0.5);
            t[j] = test_uniform(&rng, -1, 1);
        }
        assert_int_equal(aqs_body_set_force(L, (int32_t)test_uniform(&rng, 0, n), f, p, t), AQS_OK);
    }
    for (i = 0; i < 1 + n / 5; i++) {
        int32_t jj = (int32_t)test_uniform(&rng, 0, n), nv;
        double tau[6];
        assert_int_equal(aqs_joint_get_layout(L, jj, NULL, NULL, NULL, &nv), AQS_OK);
        for (j = 0; j < 6; j++) tau[j] = test_uniform(&rng, -1, 1);
        assert_int_equal(aqs_joint_set_force(L, jj, nv ? tau : NULL, nv), AQS_OK);
    }
    return L;
}

typedef struct {
    double *qdd, *f, *q;
    int32_t nv, nj, nq;
} outputs;

static void read_outputs(aqs_linkage *L, outputs *o)
{
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, &o->nj, &o->nq, &o->nv), AQS_OK);
    o->qdd = malloc(sizeof(double) * (size_t)(o->nv + 1));
    o->f = malloc(sizeof(double) * 6 * (size_t)(o->nj + 1));
    o->q = malloc(sizeof(double) * (size_t)(o->nq + 1));
    assert_int_equal(aqs_linkage_get_accelerations(L, o->qdd, (size_t)o->nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, o->f, 6 * (size_t)o->nj), AQS_OK);
    assert_int_equal(aqs_linkage_get_positions(L, o->q, (size_t)o->nq), AQS_OK);
}

static void free_outputs(outputs *o)
{
    free(o->qdd);
    free(o->f);
    free(o->q);
}

/* On 200 random trees (2 to 120 bodies, every joint type, fixed joints,
 * floating and fixed bases, gravity, body and joint forces) the two exact
 * solvers agree to 1e-10 relative (2-norm over the whole array: two rounding
 * histories of a well-conditioned problem, masses within a factor 15), and
 * so do the positions after 10 exact steps. */
static void test_aba_equals_dca(void **state)
{
    int c;
    double worst[3] = {0, 0, 0};
    (void)state;
    for (c = 0; c < 200; c++) {
        int32_t n = 2 + (c * 37) % 119, k;
        aqs_linkage *A = random_tree(1000 + (uint64_t)c, n, c % 3 == 0, AQS_EXACT_ABA);
        aqs_linkage *D = random_tree(1000 + (uint64_t)c, n, c % 3 == 0, AQS_EXACT_DCA);
        outputs a, d;
        double e[3];
        assert_int_equal(aqs_linkage_solve(A), AQS_OK);
        assert_int_equal(aqs_linkage_solve(D), AQS_OK);
        for (k = 0; k < 10; k++) {
            assert_int_equal(aqs_linkage_step(A, 0.02), AQS_OK);
            assert_int_equal(aqs_linkage_step(D, 0.02), AQS_OK);
        }
        assert_int_equal(aqs_linkage_solve(A), AQS_OK);
        assert_int_equal(aqs_linkage_solve(D), AQS_OK);
        read_outputs(A, &a);
        read_outputs(D, &d);
        e[0] = test_rel_diff(a.qdd, d.qdd, (size_t)a.nv);
        e[1] = test_rel_diff(a.f, d.f, 6 * (size_t)a.nj);
        e[2] = test_rel_diff(a.q, d.q, (size_t)a.nq);
        for (k = 0; k < 3; k++) {
            if (e[k] > worst[k]) worst[k] = e[k];
            if (!(e[k] <= 1e-10)) fail_msg("case %d (%d bodies): difference %d is %g", c, (int)n, k, e[k]);
        }
        free_outputs(&a);
        free_outputs(&d);
        aqs_linkage_destroy(A);
        aqs_linkage_destroy(D);
    }
    print_message("ABA vs DCA, 200 trees: qdd %.3g, constraint forces %.3g, positions after 10 steps %.3g\n",
                  worst[0], worst[1], worst[2]);
}

/* A pendulum (rod of mass m, centre of mass l out, inertia I_zz about it)
 * under gravity: qdd = -g m l / (I_zz + m l^2), and the pin force holds the
 * rest: f = m (a_com - g) in the body frame, a_com = qdd x (l, 0, 0). */
static void test_pendulum_closed_form(void **state)
{
    aqs_linkage *L = test_new_linkage();
    const double m = 2.0, l = 0.5, izz = 0.1, g[3] = {0, -9.81, 0};
    double qdd, f[6], expect, fy;
    int32_t nodes;
    aqs_solve_stats st;
    (void)state;
    test_add_body(L, m, l, 0, 0, izz);
    test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, &qdd, 1), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6), AQS_OK);
    expect = -9.81 * m * l / (izz + m * l * l);
    assert_true(fabs(qdd - expect) <= 1e-14 * fabs(expect));
    fy = m * (qdd * l + 9.81); /* linear y: m (a_com,y - g_y) */
    assert_true(fabs(f[3]) <= 1e-13 && fabs(f[4] - fy) <= 1e-13 * fabs(fy) && fabs(f[5]) <= 1e-13);
    /* the exact step leaves the tree alone */
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_int_equal(st.nodes_updated, 0);
    assert_int_equal(st.nodes_processed, 0);
    assert_int_equal(aqs_linkage_get_tree_stats(L, &nodes, NULL, NULL, NULL), AQS_OK);
    assert_true(L->t.all_dirty);
    aqs_linkage_destroy(L);
}

/* Exact steps by the articulated-body algorithm, then an adaptive solve: the
 * stale tree is recomputed first and the result equals that of a linkage
 * that took the same steps with the DCA (which kept its tree current). */
static void test_stale_tree_recomputed(void **state)
{
    aqs_linkage *A = random_tree(77, 90, 0, AQS_EXACT_ABA), *D = random_tree(77, 90, 0, AQS_EXACT_DCA);
    aqs_solve_stats sa, sd;
    outputs a, d;
    int k;
    (void)state;
    for (k = 0; k < 8; k++) {
        assert_int_equal(aqs_linkage_step(A, 0.02), AQS_OK);
        assert_int_equal(aqs_linkage_step(D, 0.02), AQS_OK);
    }
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, ldexp(1.0, -8)), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(D, AQS_METRIC_REL_JOINT, ldexp(1.0, -8)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(D), AQS_OK);
    sa.size = sd.size = sizeof sa;
    assert_int_equal(aqs_linkage_get_stats(A, &sa), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(D, &sd), AQS_OK);
    assert_int_equal(sa.nodes_updated, A->t.nnodes); /* the whole stale tree, once */
    assert_int_equal(sa.computed_joints, sd.computed_joints);
    assert_true(sa.computed_joints < sa.counted_joints);
    assert_true(fabs(sa.error_bound - sd.error_bound) <= 1e-9 * sd.error_bound);
    read_outputs(A, &a);
    read_outputs(D, &d);
    assert_true(test_rel_diff(a.qdd, d.qdd, (size_t)a.nv) <= 1e-10);
    free_outputs(&a);
    free_outputs(&d);
    /* back to exact: the articulated-body algorithm again, same answer */
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(D, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(D), AQS_OK);
    read_outputs(A, &a);
    read_outputs(D, &d);
    assert_true(test_rel_diff(a.qdd, d.qdd, (size_t)a.nv) <= 1e-10);
    free_outputs(&a);
    free_outputs(&d);
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(D);
}

static void test_exact_solver_errors(void **state)
{
    aqs_linkage *L = test_new_linkage();
    int32_t solver = -1;
    double qdd0, qdd1;
    (void)state;
    assert_int_equal(aqs_linkage_set_exact_solver(NULL, AQS_EXACT_DCA), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_exact_solver(NULL, &solver), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_exact_solver(L, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "solver is NULL");
    assert_int_equal(aqs_linkage_get_exact_solver(L, &solver), AQS_OK);
    assert_int_equal(solver, AQS_EXACT_ABA); /* the default */
    test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    {
        double g[3] = {0, -9.81, 0};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    }
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, &qdd0, 1), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, 2), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "solver = 2");
    assert_int_equal(aqs_linkage_set_exact_solver(L, -1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_exact_solver(L, &solver), AQS_OK);
    assert_int_equal(solver, AQS_EXACT_ABA); /* unchanged */
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, &qdd1, 1), AQS_OK);
    assert_true(qdd0 == qdd1);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_get_exact_solver(L, &solver), AQS_OK);
    assert_int_equal(solver, AQS_EXACT_DCA);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, &qdd1, 1), AQS_OK);
    assert_true(fabs(qdd1 - qdd0) <= 1e-14 * fabs(qdd0));
    aqs_linkage_destroy(L);
}

/* A linkage solved only exactly never allocates the DCA coefficients; the
 * DCA (or a tolerance) allocates them once, and when that allocation fails
 * the call returns AQS_ENOMEM and changes nothing. */
static void test_dca_coefficients_on_demand(void **state)
{
    counting_state cs = {0, 0, 0, 0, 0};
    aqs_linkage *L = NULL;
    int32_t i, solver;
    long before;
    double qdd0[40], qdd1[40];
    int32_t nv;
    (void)state;
    assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
    for (i = 0; i < 40; i++) {
        test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
        test_add_joint(L, i % 3 == 2 ? AQS_JOINT_FIXED : AQS_JOINT_REVOLUTE, i - 1, i, i ? 1.0 : 0.0, 0, 0, 0, 0, 1);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv), AQS_OK);
    {
        double g[3] = {0, -9.81, 0};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    }
    for (i = 0; i < 5; i++) assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_null(L->t.data); /* exact steps by the articulated-body algorithm only */
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd0, (size_t)nv), AQS_OK);
    /* the next allocation fails: the DCA cannot be chosen, nothing changes */
    before = cs.count;
    cs.fail_at = cs.count + 1;
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_ENOMEM);
    test_assert_contains(aqs_linkage_last_error(L), "out of memory");
    assert_true(cs.count == before + 1);
    cs.fail_at = 0;
    assert_int_equal(aqs_linkage_get_exact_solver(L, &solver), AQS_OK);
    assert_int_equal(solver, AQS_EXACT_ABA);
    assert_null(L->t.data);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd1, (size_t)nv), AQS_OK);
    assert_true(memcmp(qdd0, qdd1, sizeof(double) * (size_t)nv) == 0);
    /* a tolerance allocates them, like the DCA */
    cs.fail_at = cs.count + 1;
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_ENOMEM);
    cs.fail_at = 0;
    assert_null(L->t.data);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_non_null(L->t.data);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd1, (size_t)nv), AQS_OK);
    assert_true(test_rel_diff(qdd1, qdd0, (size_t)nv) <= 1e-13);
    before = cs.allocs;
    for (i = 0; i < 5; i++) assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_true(cs.allocs == before); /* steps allocate nothing */
    aqs_linkage_destroy(L);
    assert_int_equal(cs.live, 0);
}

/* World poses two ways: through the assembly tree (aqs_body_get_pose_world)
 * and by the independent all-bodies walk (aqs_linkage_get_body_poses_world).
 * Largest difference over positions and quaternion entries (sign-fixed). */
static double pose_paths_differ(aqs_linkage *L)
{
    int32_t nb, b, i;
    double *all, worst = 0.0;
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, NULL, NULL, NULL), AQS_OK);
    all = malloc(sizeof(double) * 7 * (size_t)nb);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, all, 7 * (size_t)nb), AQS_OK);
    for (b = 0; b < nb; b++) {
        double pos[3], quat[4], s = 0.0;
        assert_int_equal(aqs_body_get_pose_world(L, b, pos, quat), AQS_OK);
        for (i = 0; i < 4; i++) s += quat[i] * all[7 * b + 3 + i];
        for (i = 0; i < 3; i++) worst = fmax(worst, fabs(pos[i] - all[7 * b + i]));
        for (i = 0; i < 4; i++) worst = fmax(worst, fabs((s < 0 ? -quat[i] : quat[i]) - all[7 * b + 3 + i]));
    }
    free(all);
    return worst;
}

/* set_positions leaves the tree's poses stale (the exact solve does not read
 * them); what reads them recomputes them first: a world-pose query, an
 * adaptive solve (against the DCA linkage, whose tree was always current
 * through its exact solves), a single joint moved while stale. With a
 * collision shape the poses follow every move. */
static void test_lazy_tree_poses(void **state)
{
    aqs_linkage *A = random_tree(91, 70, 1, AQS_EXACT_ABA), *D = random_tree(91, 70, 1, AQS_EXACT_DCA);
    outputs a, d;
    double q1[1] = {0.4}, size[3] = {0.1, 0, 0}, zero[3] = {0, 0, 0}, id[4] = {1, 0, 0, 0};
    int32_t j;
    int k;
    (void)state;
    assert_true(A->t.poses_stale); /* random_tree set every position */
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(D), AQS_OK);
    assert_true(A->t.poses_stale);
    assert_false(D->t.poses_stale); /* the DCA's update recomputed them */
    read_outputs(A, &a);
    read_outputs(D, &d);
    assert_true(test_rel_diff(a.qdd, d.qdd, (size_t)a.nv) <= 1e-10);
    assert_true(test_rel_diff(a.f, d.f, 6 * (size_t)a.nj) <= 1e-10);
    free_outputs(&a);
    free_outputs(&d);
    assert_true(pose_paths_differ(A) <= 1e-12); /* the query recomputed them */
    assert_false(A->t.poses_stale);
    for (k = 0; k < 3; k++) {
        assert_int_equal(aqs_linkage_step(A, 0.02), AQS_OK);
        assert_int_equal(aqs_linkage_step(D, 0.02), AQS_OK);
    }
    assert_true(A->t.poses_stale);
    /* a revolute joint moved while every pose is stale */
    for (j = 1; j < 70; j++) {
        int32_t nq, nv;
        assert_int_equal(aqs_joint_get_layout(A, j, NULL, &nq, NULL, &nv), AQS_OK);
        if (nq == 1 && A->joints[j].type == AQS_JOINT_REVOLUTE) break;
    }
    assert_true(j < 70);
    assert_int_equal(aqs_joint_set_position(A, j, q1, 1), AQS_OK);
    assert_int_equal(aqs_joint_set_position(D, j, q1, 1), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, ldexp(1.0, -30)), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(D, AQS_METRIC_REL_JOINT, ldexp(1.0, -30)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(D), AQS_OK);
    assert_false(A->t.poses_stale);
    read_outputs(A, &a);
    read_outputs(D, &d);
    assert_true(test_rel_diff(a.q, d.q, (size_t)a.nq) <= 1e-12);
    assert_true(test_rel_diff(a.qdd, d.qdd, (size_t)a.nv) <= 1e-8);
    free_outputs(&a);
    free_outputs(&d);
    assert_true(pose_paths_differ(A) <= 1e-12);
    /* a shape: from then on set_positions moves the poses at once */
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_step(A, 0.02), AQS_OK);
    assert_true(A->t.poses_stale);
    assert_int_equal(aqs_shape_add(A, 3, AQS_SHAPE_SPHERE, size, zero, id, NULL), AQS_OK);
    assert_false(A->t.poses_stale);
    assert_int_equal(aqs_linkage_step(A, 0.02), AQS_OK);
    assert_false(A->t.poses_stale);
    assert_true(pose_paths_differ(A) <= 1e-12);
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(D);
}

/* Without welded bodies, shapes, a tolerance or the DCA the tree never holds
 * poses: a world-pose query walks up the kinematic tree and agrees, at
 * random positions, with the tree's answer on a twin linkage that has a
 * tolerance (its poses through the assembly tree), and with the all-bodies
 * pass. */
static void test_no_tree_poses(void **state)
{
    aqs_linkage *L[2];
    int s, i, n = 40;
    uint64_t rng = 5;
    double worst = 0.0;
    (void)state;
    for (s = 0; s < 2; s++) {
        uint64_t r = rng;
        L[s] = test_new_linkage();
        for (i = 0; i < n; i++) test_add_body(L[s], 1.0 + 0.05 * i, 0.3, 0.02, -0.01, 0.1);
        for (i = 0; i < n; i++) {
            int32_t parent = i ? (int32_t)test_uniform(&r, i / 2.0, i) : AQS_WORLD;
            int32_t type = i % 5 == 3 ? AQS_JOINT_SPHERICAL : i % 3 == 1 ? AQS_JOINT_PRISMATIC : AQS_JOINT_REVOLUTE;
            test_add_joint(L[s], type, parent, i, i ? test_uniform(&r, -0.8, 0.8) : 0.0, test_uniform(&r, -0.5, 0.5),
                           0.2, test_uniform(&r, -1, 1), test_uniform(&r, -1, 1), 1.0);
        }
        assert_int_equal(aqs_linkage_finalize(L[s]), AQS_OK);
        if (s) assert_int_equal(aqs_linkage_set_tolerance(L[s], AQS_METRIC_REL_JOINT, ldexp(1.0, -20)), AQS_OK);
        for (i = 0; i < 4; i++) assert_int_equal(aqs_linkage_step(L[s], 0.05), AQS_OK);
    }
    assert_null(L[0]->t.poses);
    assert_non_null(L[1]->t.poses);
    {   /* the same random positions on both */
        int32_t nq, off, m;
        double *q;
        assert_int_equal(aqs_linkage_get_sizes(L[0], NULL, NULL, &nq, NULL), AQS_OK);
        q = malloc(sizeof(double) * (size_t)nq);
        for (i = 0; i < n; i++) {
            int k;
            assert_int_equal(aqs_joint_get_layout(L[0], i, &off, &m, NULL, NULL), AQS_OK);
            if (m == 4) test_random_quat(&rng, q + off);
            else for (k = 0; k < m; k++) q[off + k] = test_uniform(&rng, -1.5, 1.5);
        }
        for (s = 0; s < 2; s++) assert_int_equal(aqs_linkage_set_positions(L[s], q, (size_t)nq), AQS_OK);
        free(q);
    }
    for (i = 0; i < n; i++) {
        double p0[3], q0[4], p1[3], q1[4], dot = 0.0;
        int k;
        assert_int_equal(aqs_body_get_pose_world(L[0], i, p0, q0), AQS_OK);
        assert_int_equal(aqs_body_get_pose_world(L[1], i, p1, q1), AQS_OK);
        for (k = 0; k < 4; k++) dot += q0[k] * q1[k];
        for (k = 0; k < 3; k++) worst = fmax(worst, fabs(p0[k] - p1[k]));
        for (k = 0; k < 4; k++) worst = fmax(worst, fabs((dot < 0 ? -q0[k] : q0[k]) - q1[k]));
    }
    assert_true(worst <= 1e-12);
    assert_true(pose_paths_differ(L[0]) <= 1e-12);
    assert_null(L[0]->t.poses); /* reading allocated nothing */
    for (s = 0; s < 2; s++) aqs_linkage_destroy(L[s]);
}

/* A chain whose bodies and joints are numbered against the kinematic order
 * (the root is the last body, each joint's parent has the higher index):
 * the articulated-body order is depth first whatever the numbering, and
 * agrees with the DCA. */
static void test_reverse_numbered_chain(void **state)
{
    aqs_linkage *L[2];
    outputs o[2];
    int s, i, n = 25;
    (void)state;
    for (s = 0; s < 2; s++) {
        double g[3] = {0.1, -9.81, 0.3};
        L[s] = test_new_linkage();
        assert_int_equal(aqs_linkage_set_exact_solver(L[s], s ? AQS_EXACT_DCA : AQS_EXACT_ABA), AQS_OK);
        for (i = 0; i < n; i++) test_add_body(L[s], 1.0 + 0.1 * i, 0.4, 0.05, 0, 0.1);
        for (i = n - 1; i >= 0; i--) /* joint of body i, parent body i + 1 */
            test_add_joint(L[s], i % 4 == 1 ? AQS_JOINT_PRISMATIC : AQS_JOINT_REVOLUTE, i == n - 1 ? AQS_WORLD : i + 1,
                           i, i == n - 1 ? 0.0 : 0.8, 0.1, 0, 0.3, 0.2 * (i % 3), 1);
        assert_int_equal(aqs_linkage_finalize(L[s]), AQS_OK);
        assert_int_equal(aqs_linkage_set_gravity(L[s], g), AQS_OK);
        {
            double f[3] = {1, 2, -1}, p[3] = {0.5, 0, 0};
            assert_int_equal(aqs_body_set_force(L[s], 0, f, p, NULL), AQS_OK);
        }
        assert_int_equal(aqs_linkage_solve(L[s]), AQS_OK);
        read_outputs(L[s], &o[s]);
    }
    assert_true(test_rel_diff(o[0].qdd, o[1].qdd, (size_t)o[0].nv) <= 1e-10);
    assert_true(test_rel_diff(o[0].f, o[1].f, 6 * (size_t)o[0].nj) <= 1e-10);
    for (s = 0; s < 2; s++) {
        free_outputs(&o[s]);
        aqs_linkage_destroy(L[s]);
    }
}

/* A solve that fails inside the backward pass (a prismatic joint moved 1e200
 * m: the moved articulated inertia overflows) leaves the solver's
 * accumulators partly summed; the next solve at sane positions resets them
 * and agrees with the DCA twin. */
static void test_failed_solve_then_solve(void **state)
{
    aqs_linkage *L[2];
    outputs o[2];
    int s, i, n = 8;
    (void)state;
    for (s = 0; s < 2; s++) {
        double g[3] = {0, -9.81, 0.5}, q[8];
        L[s] = test_new_linkage();
        assert_int_equal(aqs_linkage_set_exact_solver(L[s], s ? AQS_EXACT_DCA : AQS_EXACT_ABA), AQS_OK);
        for (i = 0; i < n; i++) test_add_body(L[s], 1.0 + 0.2 * i, 0.4, 0.05, 0, 0.1);
        for (i = 0; i < n; i++)
            test_add_joint(L[s], i == 5 ? AQS_JOINT_PRISMATIC : AQS_JOINT_REVOLUTE, i - 1, i, i ? 0.8 : 0.0, 0.1, 0,
                           0.3, 0.2 * (i % 3), 1);
        assert_int_equal(aqs_linkage_finalize(L[s]), AQS_OK);
        assert_int_equal(aqs_linkage_set_gravity(L[s], g), AQS_OK);
        for (i = 0; i < n; i++) q[i] = 0.1 * i;
        if (!s) {
            q[5] = 1e200;
            assert_int_equal(aqs_linkage_set_positions(L[s], q, (size_t)n), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L[s]), AQS_ENUMERIC);
            q[5] = 0.5;
        }
        assert_int_equal(aqs_linkage_set_positions(L[s], q, (size_t)n), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L[s]), AQS_OK);
        read_outputs(L[s], &o[s]);
    }
    assert_true(test_rel_diff(o[0].qdd, o[1].qdd, (size_t)o[0].nv) <= 1e-10);
    assert_true(test_rel_diff(o[0].f, o[1].f, 6 * (size_t)o[0].nj) <= 1e-10);
    for (s = 0; s < 2; s++) {
        free_outputs(&o[s]);
        aqs_linkage_destroy(L[s]);
    }
}

/* A free body in free fall has every point's acceleration g and no joint
 * force, exactly, however near a point mass it is and however far its centre
 * of mass lies from its frame's origin. The articulated-body solve took the
 * free joint's accelerations as D^-1 (u - U^T a_p) with D = U = the body's
 * articulated inertia about its origin, whose rotational part is k I plus
 * m |c|^2: a round trip that lost cond(D) u (0.75 kg, k = 1e-16, c = (0.3, 0,
 * 0), status AQS_OK: angular accelerations (0, 0.5, 4) rad/s^2 for 0; m =
 * 1e16 with k = 0.25: 8.4), and its joint force IA a + pA as much (8e301 for
 * 0). Found from outside, 2026-12-05. Now qdd = D^-1 u - a_p and f = Q for a
 * free joint (src/solve/aba.c; S = 1), exact here: the angular
 * accelerations and forces asserted to 0, the linear ones to R^T g within
 * 1e-14 |g| (the frame's rotation). The DCA agrees to rounding (its
 * inverse-inertia factor works at the centre of mass). Free joints hang
 * from the world only (aqs_joint_add). */
static void test_free_fall_exact(void **state)
{
    static const double ks[] = {1e-6, 1e-10, 1e-12, 1e-14, 1e-16}, ms[] = {0.75, 1e9, 1e16};
    const double g[3] = {0.3, -9.81, 1.2}, zero[3] = {0, 0, 0}, c[3] = {0.3, -0.1, 0.2};
    size_t a, b;
    int32_t solver, i;
    (void)state;
    for (a = 0; a < sizeof ks / sizeof ks[0]; a++)
        for (b = 0; b < sizeof ms / sizeof ms[0]; b++)
            for (solver = AQS_EXACT_ABA; solver <= AQS_EXACT_DCA; solver++) {
                aqs_linkage *L = test_new_linkage();
                const double k = ks[a], I[9] = {k, 0, 0, 0, 2 * k, 0, 0, 0, 1.5 * k};
                const double n = sqrt(0.8 * 0.8 + 0.2 * 0.2 + 0.4 * 0.4 + 0.4 * 0.4);
                const double q[7] = {0.1, -0.2, 0.3, 0.8 / n, 0.2 / n, -0.4 / n, 0.4 / n}; /* a turned frame */
                double qdd[6], f[6], R[9], gl[3], pos[3], qt[4];
                assert_int_equal(aqs_body_add(L, ms[b], c, I, NULL), AQS_OK);
                assert_int_equal(aqs_joint_add(L, AQS_JOINT_FREE, AQS_WORLD, 0, zero, q + 3, NULL, NULL), AQS_OK);
                assert_int_equal(aqs_linkage_set_exact_solver(L, solver), AQS_OK);
                assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
                assert_int_equal(aqs_linkage_set_positions(L, q, 7), AQS_OK);
                assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
                assert_int_equal(aqs_linkage_solve(L), AQS_OK);
                assert_int_equal(aqs_linkage_get_accelerations(L, qdd, 6), AQS_OK);
                assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6), AQS_OK);
                /* qdd = [alpha; a_O] in the body frame: alpha = 0, a_O = R^T g */
                assert_int_equal(aqs_body_get_pose_world(L, 0, pos, qt), AQS_OK);
                {
                    const double w = qt[0], x = qt[1], y = qt[2], z = qt[3];
                    R[0] = 1 - 2 * (y * y + z * z), R[1] = 2 * (x * y - w * z), R[2] = 2 * (x * z + w * y);
                    R[3] = 2 * (x * y + w * z), R[4] = 1 - 2 * (x * x + z * z), R[5] = 2 * (y * z - w * x);
                    R[6] = 2 * (x * z - w * y), R[7] = 2 * (y * z + w * x), R[8] = 1 - 2 * (x * x + y * y);
                }
                for (i = 0; i < 3; i++) gl[i] = R[i] * g[0] + R[3 + i] * g[1] + R[6 + i] * g[2];
                for (i = 0; i < 3; i++) {
                    /* the ABA exactly; the DCA to rounding (angular accelerations of
                     * |g| / |c| scale; measured 8.4e-26 at k = 1e-6, 0 elsewhere) */
                    assert_true(solver == AQS_EXACT_ABA ? qdd[i] == 0.0 : fabs(qdd[i]) <= 1e-14 * 9.81 / 0.3);
                    assert_true(fabs(qdd[3 + i] - gl[i]) <= 1e-14 * 9.81);
                }
                for (i = 0; i < 6; i++)
                    assert_true(solver == AQS_EXACT_ABA ? f[i] == 0.0 : fabs(f[i]) <= 1e-14 * ms[b] * 9.81);
                aqs_linkage_destroy(L);
            }
}

/* set_positions on a finalized linkage of scalar coordinates checks every
 * value in one pass: a non-finite one is refused with the joint and value
 * named, and no position changes. */
static void test_set_positions_refused(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double q[6] = {0.1, 0.2, 0.3, 0.4, 0.5, 0.6}, before[6], after[6];
    int i;
    (void)state;
    for (i = 0; i < 6; i++) {
        test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, i - 1, i, i ? 1.0 : 0.0, 0, 0, 0, 0, 1);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, 6), AQS_OK);
    assert_int_equal(aqs_linkage_get_positions(L, before, 6), AQS_OK);
    q[4] = NAN;
    q[5] = 9.0;
    assert_int_equal(aqs_linkage_set_positions(L, q, 6), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "joint 4");
    test_assert_contains(aqs_linkage_last_error(L), "nan");
    assert_int_equal(aqs_linkage_get_positions(L, after, 6), AQS_OK);
    assert_memory_equal(before, after, sizeof before);
    q[4] = INFINITY;
    assert_int_equal(aqs_linkage_set_positions(L, q, 6), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "joint 4");
    assert_int_equal(aqs_linkage_get_positions(L, after, 6), AQS_OK);
    assert_memory_equal(before, after, sizeof before);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_aba_equals_dca),
        cmocka_unit_test(test_pendulum_closed_form),
        cmocka_unit_test(test_stale_tree_recomputed),
        cmocka_unit_test(test_exact_solver_errors),
        cmocka_unit_test(test_dca_coefficients_on_demand),
        cmocka_unit_test(test_lazy_tree_poses),
        cmocka_unit_test(test_no_tree_poses),
        cmocka_unit_test(test_reverse_numbered_chain),
        cmocka_unit_test(test_set_positions_refused),
        cmocka_unit_test(test_free_fall_exact),
        cmocka_unit_test(test_failed_solve_then_solve),
    };
    return cmocka_run_group_tests_name("aba", tests, NULL, NULL);
}
