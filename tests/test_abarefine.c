/* test_abarefine.c -- the articulated-body solve's balance check and its
 * refinement (src/solve/abarefine.c, docs/math.md §5b):
 *   - an arm holding an oblique planar chain of 1,000 links and floating
 *     trees of every joint type with masses over 1e6: the unrefined ABA
 *     (aqs_linkage_set_exact_refinement 0) is more than 1e-11 from the exact
 *     DCA there (measured below), the default one within 1e-14, its
 *     constraint forces within 1e-12 of the DCA's (relative to the largest;
 *     on every such tree the DCA's and the refined ABA's forces agree within
 *     1e-13: src/solve/refine.c, state_forces);
 *   - floating trees whose balance is at the rounding level but whose joint
 *     forces do not satisfy their own joints' equations S^T f = Q (the
 *     projection check, docs/math.md §5b): refined, accelerations and forces
 *     at the DCA's where that is accurate (measured against __float128);
 *   - where the balance is at the rounding level (a chain, a free fall, a
 *     benign random tree) nothing is refined and the answer is bit for bit
 *     the unrefined one;
 *   - out of memory in the refinement's arrays: the solve succeeds with the
 *     unrefined answer, nothing leaks;
 *   - chains of planar (or spherical) joints between bodies 1e9 apart, where
 *     the articulated-body factors lose every digit (or find an articulated
 *     inertia singular): the exact solve is the exact DCA's, bit for bit,
 *     and says so (path AQS_PATH_EXACT_DCA); its first such solve allocates
 *     the DCA's storage, and out of memory there is AQS_ENOMEM (the accuracy
 *     against __float128 is hardcases' altmass/joints; the library of
 *     bf565f1 answered the planar chain here 0.15 off the DCA and the
 *     spherical one AQS_ENUMERIC).
 * The reference is the refined exact DCA: an independent algorithm, within
 * 1e-15 of the __float128 reference on these models (tests/reference/
 * hardcases.cpp, families armchain and jtypes: 1.4e-16 .. 5.0e-16). */
#include "testutil.h"
#include "randtree.h"
#include "refinetest.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linkage.h"

/* The arm of hardcases' "armchain": three 10 kg links (axes z, y, x at q =
 * 0.3, 0.5, 0.7) holding n links of 1 kg whose axes are (0, 1, 1)/sqrt 2,
 * gravity (0, -9.81, 0). */
static aqs_linkage *armchain_in(counting_state *cs, int n)
{
    aqs_linkage *L;
    const double com[3] = {0.5, 0, 0}, quat[4] = {1, 0, 0, 0}, g[3] = {0, -9.81, 0};
    const double axes[3][3] = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}}, ob[3] = {0, 0.70710678118654752, 0.70710678118654752};
    const double Ia[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, Ic[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    double *q = calloc((size_t)n + 3, sizeof *q);
    int32_t prev = AQS_WORLD, i, b;
    assert_non_null(q);
    L = test_new_linkage_in(cs);
    for (i = 0; i < n + 3; i++) {
        const double pos[3] = {i ? 1.0 : 0.0, 0, 0};
        assert_int_equal(aqs_body_add(L, i < 3 ? 10.0 : 1.0, com, i < 3 ? Ia : Ic, &b), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, pos, quat, i < 3 ? axes[i] : ob, NULL), AQS_OK);
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    q[0] = 0.3, q[1] = 0.5, q[2] = 0.7;
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)n + 3), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    free(q);
    return L;
}

typedef struct {
    double acc, force; /* relative to the reference's largest */
} dist;

/* Solve L with the given exact refinement count and exact solver; into q, f. */
static void solve_with(aqs_linkage *L, int32_t refine, int32_t solver, double *q, double *f)
{
    int32_t nv, nj;
    aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_refinement(L, refine), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, solver), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nj), AQS_OK);
}

static double max_abs(const double *x, size_t n)
{
    double m = 0.0;
    size_t i;
    for (i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
    return m;
}

/* The unrefined ABA, the default ABA and the refined exact DCA of L: the two
 * ABAs' distances to the DCA; refined: the default ABA's correction count. */
static void compare(aqs_linkage *L, dist *plain, dist *aba, int32_t *refined)
{
    int32_t nv, nj;
    double *qp, *fp, *qa, *fa, *qd, *fd;
    aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv);
    qp = malloc(sizeof(double) * (size_t)nv), qa = malloc(sizeof(double) * (size_t)nv);
    qd = malloc(sizeof(double) * (size_t)nv);
    fp = malloc(sizeof(double) * 6 * (size_t)nj), fa = malloc(sizeof(double) * 6 * (size_t)nj);
    fd = malloc(sizeof(double) * 6 * (size_t)nj);
    assert_true(qp && qa && qd && fp && fa && fd);
    solve_with(L, 0, AQS_EXACT_ABA, qp, fp);
    assert_int_equal(L->s.refined, 0);
    solve_with(L, AQS_REFINEMENT_MAX, AQS_EXACT_ABA, qa, fa);
    *refined = L->s.refined;
    solve_with(L, AQS_REFINEMENT_MAX, AQS_EXACT_DCA, qd, fd);
    plain->acc = test_max_abs_diff(qp, qd, (size_t)nv) / max_abs(qd, (size_t)nv);
    plain->force = test_max_abs_diff(fp, fd, 6 * (size_t)nj) / max_abs(fd, 6 * (size_t)nj);
    aba->acc = test_max_abs_diff(qa, qd, (size_t)nv) / max_abs(qd, (size_t)nv);
    aba->force = test_max_abs_diff(fa, fd, 6 * (size_t)nj) / max_abs(fd, 6 * (size_t)nj);
    free(qp), free(qa), free(qd), free(fp), free(fa), free(fd);
}

/* The arm holding the oblique chain: the unrefined ABA 5e-10 off at 1,000
 * links (its articulated inertias mix the chain's n^3 out-of-plane inertia
 * with its O(1) in-plane part in the arm's frame), refined to the DCA's. */
static void test_armchain(void **state)
{
    aqs_linkage *L = armchain_in(NULL, 1000);
    dist plain, aba;
    int32_t refined;
    (void)state;
    compare(L, &plain, &aba, &refined);
    printf("armchain 1000: unrefined %.2e (forces %.2e), refined %.2e (forces %.2e), %d corrections\n", plain.acc,
           plain.force, aba.acc, aba.force, (int)refined);
    assert_true(plain.acc > 1e-11); /* the loss is there */
    assert_true(refined >= 1);
    assert_true(aba.acc <= 1e-14);
    assert_true(aba.force <= 1e-12);
    aqs_linkage_destroy(L);
}

/* Floating trees of every joint type, masses log-uniform over 1e-3 .. 1e3:
 * the ones whose unrefined ABA loses more than 1e-11 (spherical and planar
 * joints between very different masses) come out within 1e-14. On every
 * tree the refined ABA's constraint forces and the exact DCA's agree within
 * 1e-13 of the largest: measured against __float128 (docs/math.md §13a,
 * "The forces of the refined bodies' accelerations"), the DCA's 3.0e-16 ..
 * 7.9e-15, the refined ABA's 3.7e-16 .. 3.1e-15 but 6.2e-14 on one tree;
 * before the exact refinement took the forces of the refined bodies'
 * accelerations, four of the DCA's were 2.4e-13 .. 1.6e-11 off. */
static void test_mixed_trees(void **state)
{
    uint64_t rng = 4242;
    int k, lossy = 0;
    (void)state;
    for (k = 0; k < 12; k++) {
        aqs_linkage *L = test_mixed_tree(&rng, 60, 1, 3, 1e3);
        dist plain, aba;
        int32_t refined;
        compare(L, &plain, &aba, &refined);
        printf("mixed tree %d: unrefined %.2e (forces %.2e), refined %.2e (forces %.2e), %d corrections\n", k,
               plain.acc, plain.force, aba.acc, aba.force, (int)refined);
        if (plain.acc > 1e-11) lossy++;
        assert_true(aba.acc <= fmax(1e-14, plain.acc)); /* never worse */
        if (plain.acc > 1e-13) {
            assert_true(refined >= 1);
            assert_true(aba.acc <= 1e-14);
        }
        assert_true(aba.force <= 1e-13);
        aqs_linkage_destroy(L);
    }
    assert_true(lossy >= 2); /* the family has the loss this file is about */
}

/* Trees 3 and 4 of test_mixed_trees' stream: their balance of forces is at
 * 0.003 u and 0.015 u of the largest term, their joints' own equations
 * Q - S^T f at 3.9e5 u and 1.2e6 u of the largest joint force. Measured
 * against the __float128 reference (tests/reference/hard_reference.hpp, a
 * throw-away driver over these trees, 2026-12-04): tree 3's unrefined forces
 * 8.8e-11 off, the DCA's 8.1e-16; tree 4's unrefined accelerations 9.0e-14
 * off, the DCA's 1.1e-15 (its forces 7.6e-16, 5.9e-12 before 2026-12-04's
 * state_forces). The
 * refined ABA: tree 3's forces within 1e-13 of the DCA's (8.9e-16 from the
 * reference), tree 4's accelerations within 1e-14 (1.1e-15). Since
 * 2026-12-05 a free joint's accelerations and force are written without the
 * round trip through its articulated inertia (src/solve/aba.c): tree 3 has
 * no loss left (1.7e-15 unrefined, nothing refined), tree 4 only its
 * forces' (3.2e-12), which the projection check still finds. */
static void test_projection(void **state)
{
    uint64_t rng = 4242;
    int k;
    (void)state;
    for (k = 0; k < 5; k++) {
        aqs_linkage *L = test_mixed_tree(&rng, 60, 1, 3, 1e3);
        dist plain, aba;
        int32_t refined;
        if (k < 3) {
            aqs_linkage_destroy(L);
            continue;
        }
        compare(L, &plain, &aba, &refined);
        printf("projection, mixed tree %d: unrefined %.2e (forces %.2e), refined %.2e (forces %.2e), %d corrections\n",
               k, plain.acc, plain.force, aba.acc, aba.force, (int)refined);
        if (k == 3) {
            /* its loss was the root free joint's force I^A a + p^A (8.8e-11,
             * refined by the projection check to 8.9e-16): since 2026-12-05 a
             * free joint's force is Q exactly (src/solve/aba.c) and the
             * unrefined solve is within 1e-14 (measured 1.7e-15). Its
             * masses spread 1e3: a child more than 1e2 times heavier than its
             * parent makes every solve take the residual (model.heavy_ratio,
             * docs/math.md 5b), whose corrections are then at the rounding
             * level (with the residual in double 3 were kept, to 7.5e-17 and
             * forces 1.0e-15; in double-double the first is at 4 u and the
             * solve keeps its answer: 2.0e-16, forces 1.7e-15) */
            assert_true(plain.force <= 1e-14);
            assert_true(aba.force <= 1e-14);
            assert_true(aba.acc <= 1e-14);
        } else {
            /* the accelerations' loss (9.0e-14) was the free joint's too: now
             * 1.9e-15 unrefined; its forces still lose digits elsewhere
             * (3.2e-12), which the projection check sees and refines */
            assert_true(refined >= 1);
            assert_true(plain.force > 1e-12);
            assert_true(aba.force <= 1e-13);
            assert_true(aba.acc <= 1e-14);
        }
        aqs_linkage_destroy(L);
    }
}

/* Where the balance is at the rounding level nothing is refined, and the
 * answer is bit for bit the unrefined one (the balance reads, never writes,
 * the solve's values): a chain under gravity, a free fall (floating base,
 * gravity alone: every joint force 0, the bodies' weights the scale),
 * benign random trees. */
static void expect_unrefined(aqs_linkage *L)
{
    int32_t nv, nj;
    double *q0, *q1, *f0, *f1;
    aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv);
    q0 = malloc(sizeof(double) * (size_t)nv), q1 = malloc(sizeof(double) * (size_t)nv);
    f0 = malloc(sizeof(double) * 6 * (size_t)nj), f1 = malloc(sizeof(double) * 6 * (size_t)nj);
    assert_true(q0 && q1 && f0 && f1);
    solve_with(L, 0, AQS_EXACT_ABA, q0, f0);
    solve_with(L, AQS_REFINEMENT_MAX, AQS_EXACT_ABA, q1, f1);
    assert_int_equal(L->s.refined, 0);
    assert_memory_equal(q0, q1, sizeof(double) * (size_t)nv);
    assert_memory_equal(f0, f1, sizeof(double) * 6 * (size_t)nj);
    free(q0), free(q1), free(f0), free(f1);
}

static void test_benign_unrefined(void **state)
{
    uint64_t rng = 99;
    int k;
    test_tree_spec sp;
    (void)state;
    memset(&sp, 0, sizeof sp);
    sp.nbodies = 200, sp.chain = 1, sp.gravity = 1, sp.revolute_only = 1, sp.mass_spread = 1.0;
    {
        aqs_linkage *L = test_random_tree(&rng, &sp);
        expect_unrefined(L);
        aqs_linkage_destroy(L);
    }
    { /* a free fall */
        aqs_linkage *L = test_mixed_tree(&rng, 40, 1, 0, 10.0);
        int32_t nv, nj, i;
        const double g[3] = {0, 0, -9.81};
        double *q, *f;
        aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv);
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
        assert_int_equal(aqs_linkage_clear_forces(L), AQS_OK);
        expect_unrefined(L);
        /* and it is a free fall: every joint force 0 to the rounding of the weights */
        q = malloc(sizeof(double) * (size_t)nv), f = malloc(sizeof(double) * 6 * (size_t)nj);
        assert_true(q && f);
        assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nj), AQS_OK);
        for (i = 0; i < 6 * nj; i++) assert_true(isnan(f[i]) || fabs(f[i]) <= 1e-12);
        free(q), free(f);
        aqs_linkage_destroy(L);
    }
    for (k = 0; k < 6; k++) {
        aqs_linkage *L = test_mixed_tree(&rng, 60, k % 2, 3, 10.0);
        expect_unrefined(L);
        aqs_linkage_destroy(L);
    }
}

/* Out of memory in the refinement's arrays (its six blocks, each failed in
 * turn): the solve succeeds unrefined, nothing leaks; then it refines. */
static void test_out_of_memory(void **state)
{
    counting_state cs;
    aqs_linkage *L, *X = armchain_in(NULL, 200);
    double q0[203], f[6 * 203];
    (void)state;
    memset(&cs, 0, sizeof cs);
    L = armchain_in(&cs, 200);
    solve_with(X, 0, AQS_EXACT_ABA, q0, f);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    {
        const test_oom o = {L, &cs, &L->s.refined, q0, 203, 0};
        test_oom_each(&o, 6);
    }
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(X);
    assert_int_equal(cs.live, 0);
}

/* A chain of n links whose joints are `type` and `type2` in turn, identity
 * joint frames, axes drawn from seed, masses ratio kg ('H') and 1 kg ('l')
 * in `pattern` repeated, inertia diag(0.05, 0.07, 0.06) times the mass,
 * positions drawn from seed (set_q; else zero), gravity (0.3, -9.81, 0.2);
 * cs: the counting allocator, or NULL. */
static aqs_linkage *heavy_chain(counting_state *cs, int32_t type, int32_t type2, const char *pattern, double ratio,
                                int32_t n, uint64_t seed, int set_q)
{
    aqs_linkage *L = test_new_linkage_in(cs);
    const double quat[4] = {1, 0, 0, 0}, g[3] = {0.3, -9.81, 0.2};
    const size_t np = strlen(pattern);
    double q[4 * 40];
    int32_t i, b, prev = AQS_WORLD, nq;
    assert_true(n <= 40);
    for (i = 0; i < n; i++) {
        const double m = pattern[(size_t)i % np] == 'H' ? ratio : 1.0, com[3] = {0.5, 0.05, 0};
        const double I[9] = {0.05 * m, 0, 0, 0, 0.07 * m, 0, 0, 0, 0.06 * m}, pos[3] = {i ? 1.0 : 0.0, 0, 0};
        double axis[3];
        axis[0] = test_uniform(&seed, -1, 1), axis[1] = test_uniform(&seed, -1, 1), axis[2] = test_uniform(&seed, 0.5, 1);
        assert_int_equal(aqs_body_add(L, m, com, I, &b), AQS_OK);
        assert_int_equal(aqs_joint_add(L, i % 2 ? type2 : type, prev, b, pos, quat, axis, NULL), AQS_OK);
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    assert_true(nq <= 4 * 40);
    if (set_q) {
        assert_true(type == AQS_JOINT_PLANAR && type2 == AQS_JOINT_PLANAR); /* no quaternions to draw */
        for (i = 0; i < nq; i++) q[i] = test_uniform(&seed, -1, 1);
        assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
    }
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    return L;
}

static int32_t last_path(const aqs_linkage *L)
{
    aqs_solve_stats st;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    return st.path;
}

/* The default exact solve of L is the exact DCA's, bit for bit, and its
 * stats say so; the textbook pass (refinement 0) is more than `off` from it
 * (the case is as hard as claimed), or fails with AQS_ENUMERIC (off < 0). */
static void expect_dca_answers(aqs_linkage *L, double off)
{
    int32_t nv, nj;
    double q[120], f[6 * 40], qd[120], fd[6 * 40];
    aqs_status st;
    aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv);
    assert_true(nv <= 120 && nj <= 40);
    assert_int_equal(aqs_linkage_set_exact_refinement(L, 0), AQS_OK);
    st = aqs_linkage_solve(L);
    if (off < 0) {
        assert_int_equal(st, AQS_OK); /* the ABA's AQS_ENUMERIC is answered by the DCA too */
        assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
    } else {
        assert_int_equal(st, AQS_OK);
        assert_int_equal(last_path(L), AQS_PATH_EXACT_ABA); /* no refinement: no check, no fallback */
        assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
    }
    assert_int_equal(aqs_linkage_set_exact_refinement(L, AQS_REFINEMENT_MAX), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_string_equal(aqs_linkage_last_error(L), ""); /* the ABA's failure is not the call's */
    assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
    assert_int_equal(aqs_linkage_get_accelerations(L, qd, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, fd, 6 * (size_t)nj), AQS_OK);
    if (off >= 0) assert_true(test_max_abs_diff(q, qd, (size_t)nv) > off * max_abs(qd, (size_t)nv));
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    /* the corrections by the articulated-body factors (aba_polish) are tried
     * here, not in the hand-over: they cannot (factors more than 1e-3 off, or
     * an articulated inertia found singular), so the same answer bit for bit,
     * and the factors' failure is not the call's either */
    assert_string_equal(aqs_linkage_last_error(L), "");
    assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
    assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nj), AQS_OK);
    assert_memory_equal(q, qd, sizeof(double) * (size_t)nv);
    assert_memory_equal(f, fd, sizeof(double) * 6 * (size_t)nj);
}

/* Planar joints between bodies 1e9 apart: the articulated-body factors lose
 * every digit (the textbook pass more than 1e-3 off), its refinement cannot
 * contract; the exact solve goes to the DCA. Spherical joints: the
 * articulated inertia is found singular; the same. */
static void test_dca_answers(void **state)
{
    aqs_linkage *L;
    (void)state;
    L = heavy_chain(NULL, AQS_JOINT_PLANAR, AQS_JOINT_PLANAR, "lllH", 1e9, 30, 5, 1);
    expect_dca_answers(L, 1e-3);
    aqs_linkage_destroy(L);
    L = heavy_chain(NULL, AQS_JOINT_SPHERICAL, AQS_JOINT_REVOLUTE, "Hllll", 1e9, 30, 5, 0);
    expect_dca_answers(L, -1.0);
    aqs_linkage_destroy(L);
}

/* After a hand-over the next AQS_HANDOVER_RUN exact solves go to the DCA
 * without the articulated-body attempt (the same answers, bit for bit), then
 * it is tried again; with refinement 0 (the textbook pass) the run does not
 * apply. */
static void test_handover_run(void **state)
{
    aqs_linkage *L = heavy_chain(NULL, AQS_JOINT_PLANAR, AQS_JOINT_PLANAR, "lllH", 1e9, 30, 5, 1);
    double q0[90], q[90];
    int32_t nv, k;
    (void)state;
    aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv);
    assert_true(nv <= 90);
    assert_int_equal(L->aba_skip, 0);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
    assert_int_equal(L->aba_skip, AQS_HANDOVER_RUN);
    assert_int_equal(aqs_linkage_get_accelerations(L, q0, (size_t)nv), AQS_OK);
    for (k = AQS_HANDOVER_RUN - 1; k >= 0; k--) {
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
        assert_int_equal(L->aba_skip, k);
        assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
        assert_memory_equal(q, q0, sizeof(double) * (size_t)nv);
    }
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* tried again: hands over again */
    assert_int_equal(L->aba_skip, AQS_HANDOVER_RUN);
    assert_int_equal(aqs_linkage_set_exact_refinement(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(last_path(L), AQS_PATH_EXACT_ABA);
    assert_int_equal(L->aba_skip, AQS_HANDOVER_RUN);
    aqs_linkage_destroy(L);
}

/* Out of memory in the DCA's storage at the first solve that goes to it:
 * AQS_ENOMEM with a message, nothing leaks; the next solve allocates it. */
static void test_dca_answers_out_of_memory(void **state)
{
    counting_state cs;
    aqs_linkage *L;
    long k, tested = 0;
    (void)state;
    for (k = 1;; k++) {
        aqs_status st;
        memset(&cs, 0, sizeof cs);
        L = heavy_chain(&cs, AQS_JOINT_PLANAR, AQS_JOINT_PLANAR, "lllH", 1e9, 30, 5, 1);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* the refinement's arrays, then the DCA's */
        aqs_linkage_destroy(L);
        memset(&cs, 0, sizeof cs);
        L = heavy_chain(&cs, AQS_JOINT_PLANAR, AQS_JOINT_PLANAR, "lllH", 1e9, 30, 5, 1);
        cs.fail_at = cs.count + k;
        st = aqs_linkage_solve(L);
        if (cs.count < cs.fail_at) { /* every allocation of the solve passed */
            assert_int_equal(st, AQS_OK);
            aqs_linkage_destroy(L);
            assert_int_equal(cs.live, 0);
            break;
        }
        if (st != AQS_OK) {
            assert_int_equal(st, AQS_ENOMEM);
            test_assert_contains(aqs_linkage_last_error(L), "out of memory");
            tested++;
        }
        cs.fail_at = 0;
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(last_path(L), AQS_PATH_EXACT_DCA);
        aqs_linkage_destroy(L);
        assert_int_equal(cs.live, 0);
    }
    print_message("%ld allocations of the DCA's storage failed in turn\n", tested);
    assert_true(tested >= 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_armchain),
        cmocka_unit_test(test_mixed_trees),
        cmocka_unit_test(test_projection),
        cmocka_unit_test(test_benign_unrefined),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_dca_answers),
        cmocka_unit_test(test_dca_answers_out_of_memory),
        cmocka_unit_test(test_handover_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
