/* test_frames.c -- src/solve/frames.c: world poses of bodies found through the
 * assembly tree's hierarchical frames (aqs_body_get_pose_world, O(log N)
 * per body) and in one pass (aqs_linkage_get_body_poses_world), against
 * poses chained joint by joint in the test itself, on a 10,000-link chain
 * of every joint type and on branched trees with fixed joints; after
 * finalize, after setting positions (all, or one joint: the O(log N)
 * update of the cross poses), and after steps.
 *
 * The reference chains the joints in long double (64-bit mantissa, unit
 * roundoff 5e-20), from the header's definitions of each joint type, so its
 * own error is negligible and the comparison measures the library's. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef long double ld;

typedef struct {
    ld R[9], p[3];
} lpose;

/* The model as the test built it (after the library's own normalization of
 * axes and placement quaternions, replicated in double). */
typedef struct {
    int32_t n;
    int32_t *parent, *type;
    double (*pos)[3], (*quat)[4], (*axis)[3];
} model_copy;

static void lmul(const ld A[9], const ld B[9], ld C[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

static void lcompose(const lpose *a, const lpose *b, lpose *out)
{
    int i;
    lmul(a->R, b->R, out->R);
    for (i = 0; i < 3; i++)
        out->p[i] = a->p[i] + a->R[3 * i] * b->p[0] + a->R[3 * i + 1] * b->p[1] + a->R[3 * i + 2] * b->p[2];
}

static void lidentity(lpose *P)
{
    int i;
    memset(P, 0, sizeof *P);
    for (i = 0; i < 3; i++) P->R[4 * i] = 1;
}

/* Rotation of angle about the unit axis a (Rodrigues). */
static void lrot(const ld a[3], ld angle, ld R[9])
{
    ld K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0}, K2[9], s = sinl(angle), c = 1 - cosl(angle);
    int i;
    lmul(K, K, K2);
    for (i = 0; i < 9; i++) R[i] = (i % 4 == 0) + s * K[i] + c * K2[i];
}

static void lquat(const double q[4], ld R[9])
{
    ld w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = 1 - 2 * (y * y + z * z);
    R[1] = 2 * (x * y - w * z);
    R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);
    R[4] = 1 - 2 * (x * x + z * z);
    R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);
    R[7] = 2 * (y * z + w * x);
    R[8] = 1 - 2 * (x * x + y * y);
}

/* The child pose of aqs.h's joint types; u, v by the header's rule. */
static void lchild(int32_t type, const double axis[3], const double *q, lpose *P)
{
    ld a[3] = {axis[0], axis[1], axis[2]}, u[3], v[3], n;
    int i, e = 0;
    if (fabsl(a[1]) < fabsl(a[e])) e = 1;
    if (fabsl(a[2]) < fabsl(a[e])) e = 2;
    for (i = 0; i < 3; i++) u[i] = (i == e) - a[e] * a[i];
    n = sqrtl(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (i = 0; i < 3; i++) u[i] /= n;
    v[0] = a[1] * u[2] - a[2] * u[1];
    v[1] = a[2] * u[0] - a[0] * u[2];
    v[2] = a[0] * u[1] - a[1] * u[0];
    lidentity(P);
    switch (type) {
    case AQS_JOINT_REVOLUTE: lrot(a, q[0], P->R); break;
    case AQS_JOINT_PRISMATIC:
        for (i = 0; i < 3; i++) P->p[i] = q[0] * a[i];
        break;
    case AQS_JOINT_SPHERICAL: lquat(q, P->R); break;
    case AQS_JOINT_FREE:
        lquat(q + 3, P->R);
        for (i = 0; i < 3; i++) P->p[i] = q[i];
        break;
    case AQS_JOINT_FIXED: break;
    case AQS_JOINT_UNIVERSAL: {
        ld Ra[9], Ru[9];
        lrot(a, q[0], Ra);
        lrot(u, q[1], Ru);
        lmul(Ra, Ru, P->R);
        break;
    }
    case AQS_JOINT_CYLINDRICAL:
        lrot(a, q[0], P->R);
        for (i = 0; i < 3; i++) P->p[i] = q[1] * a[i];
        break;
    case AQS_JOINT_PLANAR:
        lrot(a, q[2], P->R);
        for (i = 0; i < 3; i++) P->p[i] = q[0] * u[i] + q[1] * v[i];
        break;
    default: fail();
    }
}

/* World poses of all bodies, chained joint by joint. Joint i has child i
 * and a parent < i (or the world), so index order is parents first. */
static void reference_poses(const model_copy *M, const double *q, lpose *out)
{
    int32_t i;
    size_t off = 0;
    for (i = 0; i < M->n; i++) {
        lpose place, J, jp;
        int k;
        lquat(M->quat[i], place.R);
        for (k = 0; k < 3; k++) place.p[k] = M->pos[i][k];
        lchild(M->type[i], M->axis[i], q + off, &J);
        lcompose(&place, &J, &jp);
        if (M->parent[i] == AQS_WORLD) out[i] = jp;
        else lcompose(&out[M->parent[i]], &jp, &out[i]);
        off += (size_t)(M->type[i] == AQS_JOINT_FREE ? 7 : M->type[i] == AQS_JOINT_SPHERICAL ? 4
                        : M->type[i] == AQS_JOINT_PLANAR ? 3 : M->type[i] == AQS_JOINT_FIXED ? 0
                        : (M->type[i] == AQS_JOINT_UNIVERSAL || M->type[i] == AQS_JOINT_CYLINDRICAL) ? 2 : 1);
    }
}

/* Compare the library's poses with the reference: positions to pos_tol
 * absolute, rotation matrices (from the reported quaternions) to rot_tol.
 * Returns the largest position error seen. */
static double compare_pose(const double pos[3], const double quat[4], const lpose *ref, double pos_tol,
                           double rot_tol)
{
    double R[9], e = 0, n = sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
    int k;
    assert_true(fabs(n - 1) < 1e-14);
    test_quat_matrix(quat, R);
    for (k = 0; k < 3; k++) {
        double d = fabs(pos[k] - (double)ref->p[k]);
        if (!(d <= pos_tol)) {
            print_error("position[%d] %.17g vs %.17Lg (diff %.3g)\n", k, pos[k], ref->p[k], d);
            fail();
        }
        if (d > e) e = d;
    }
    for (k = 0; k < 9; k++)
        if (!(fabs(R[k] - (double)ref->R[k]) <= rot_tol)) {
            print_error("R[%d] %.17g vs %.17Lg\n", k, R[k], ref->R[k]);
            fail();
        }
    return e;
}

/* Both ways of reading world poses against the reference, for every body. */
static void check_all_poses(aqs_linkage *L, const model_copy *M, double pos_tol, double rot_tol)
{
    int32_t nq, i;
    double *q, *poses = malloc(sizeof(double) * 7 * (size_t)M->n);
    lpose *ref = malloc(sizeof(lpose) * (size_t)M->n);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    q = malloc(sizeof(double) * ((size_t)nq + 1));
    assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
    reference_poses(M, q, ref);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, poses, 7 * (size_t)M->n), AQS_OK);
    for (i = 0; i < M->n; i++) {
        double pos[3], quat[4];
        compare_pose(poses + 7 * i, poses + 7 * i + 3, &ref[i], pos_tol, rot_tol);
        assert_int_equal(aqs_body_get_pose_world(L, i, pos, quat), AQS_OK);
        compare_pose(pos, quat, &ref[i], pos_tol, rot_tol);
    }
    free(q);
    free(poses);
    free(ref);
}

static void model_alloc(model_copy *M, int32_t n)
{
    M->n = n;
    M->parent = malloc(sizeof(int32_t) * (size_t)n);
    M->type = malloc(sizeof(int32_t) * (size_t)n);
    M->pos = malloc(sizeof *M->pos * (size_t)n);
    M->quat = malloc(sizeof *M->quat * (size_t)n);
    M->axis = malloc(sizeof *M->axis * (size_t)n);
}

static void model_release(model_copy *M)
{
    free(M->parent);
    free(M->type);
    free(M->pos);
    free(M->quat);
    free(M->axis);
}

/* Add joint i (child = body i) and record it as the library stores it:
 * axis and quaternion divided by their norms, as aqs_joint_add does. */
static void add_joint(aqs_linkage *L, model_copy *M, int32_t i, int32_t type, int32_t parent,
                      const double pos[3], const double quat[4], const double axis[3])
{
    double an = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double qn = sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
    int k;
    assert_int_equal(aqs_joint_add(L, type, parent, i, pos, quat, axis, NULL), AQS_OK);
    M->parent[i] = parent;
    M->type[i] = type;
    for (k = 0; k < 3; k++) M->pos[i][k] = pos[k];
    for (k = 0; k < 4; k++) M->quat[i][k] = quat[k] / qn;
    for (k = 0; k < 3; k++) M->axis[i][k] = axis[k] / an;
}

/* Random small rotation quaternion: angle up to max about a random axis. */
static void small_quat(uint64_t *s, double max, double q[4])
{
    double a[3], n, t = test_uniform(s, -max, max);
    int k;
    for (k = 0; k < 3; k++) a[k] = test_uniform(s, -1, 1);
    n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    q[0] = cos(0.5 * t);
    for (k = 0; k < 3; k++) q[1 + k] = sin(0.5 * t) * a[k] / n;
}

/* Random position values: angles and lengths in (-amp, amp), quaternions
 * small rotations (free: translation base_p). */
static void random_positions(uint64_t *s, const model_copy *M, double amp, const double base_p[3], double *q)
{
    int32_t i;
    size_t off = 0;
    for (i = 0; i < M->n; i++) {
        int32_t t = M->type[i];
        int k, nq = t == AQS_JOINT_FREE ? 7 : t == AQS_JOINT_SPHERICAL ? 4 : t == AQS_JOINT_PLANAR ? 3
                    : t == AQS_JOINT_FIXED ? 0 : (t == AQS_JOINT_UNIVERSAL || t == AQS_JOINT_CYLINDRICAL) ? 2 : 1;
        for (k = 0; k < nq; k++) q[off + k] = test_uniform(s, -amp, amp);
        if (t == AQS_JOINT_SPHERICAL) small_quat(s, 4 * amp, q + off);
        if (t == AQS_JOINT_FREE) {
            for (k = 0; k < 3; k++) q[off + k] = base_p[k];
            small_quat(s, 3.0, q + off + 3);
        }
        off += (size_t)nq;
    }
}

/* ------------------------------------------------------------ the chain */

/* 10,000 links, each joint frame 1 m further along the parent's x axis
 * (turned by up to 0.1 rad), of every type but free after a free base at
 * (2000, -1000, 500), at small random positions: the chain runs straight
 * enough that the bodies lie 1e3 to 1e4 m from the origin.
 *
 * Tolerance. Each body's pose is a product of up to 1e4 transforms; each
 * product rounds positions by ~u |p| <= 1.1e-16 * 1e4 = 1e-12 and
 * orientations by ~u. Independent roundings add up like a random walk:
 * sqrt(1e4) * 1e-12 = 1e-10 from the sums, and orientation errors of
 * sqrt(k) u at link k move the rest of the chain by sum_k sqrt(k) u (1 m)
 * ~ (2/3) 1e6 u ~ 7e-11. So ~1e-10 is expected for either method of the
 * library (the reference's own error is 1e-3 of that); 1e-9 absolute
 * leaves a factor of ten, and a wrong transform anywhere in the chain moves
 * everything after it by far more. Rotation matrix entries: sqrt(1e4) u
 * ~ 1e-14 expected; 1e-12. (Measured: 2.8e-11 and 1.6e-14.) */
#define CHAIN_POS_TOL 1e-9
#define CHAIN_ROT_TOL 1e-12

static void build_chain(aqs_linkage *L, model_copy *M, int32_t n, uint64_t *s)
{
    static const int types[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,
                                AQS_JOINT_FIXED,    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL,
                                AQS_JOINT_PLANAR};
    int32_t i;
    model_alloc(M, n);
    for (i = 0; i < n; i++) {
        double pos[3] = {1.0, 0, 0}, quat[4], axis[3];
        int k;
        int32_t type = i == 0 ? AQS_JOINT_FREE : types[(int)test_uniform(s, 0, 7)];
        test_add_body(L, test_uniform(s, 0.5, 2), 0.5, 0, 0, 0.1);
        small_quat(s, 0.1, quat);
        for (k = 0; k < 3; k++) axis[k] = test_uniform(s, -1, 1);
        if (i == 0) pos[0] = 0;
        add_joint(L, M, i, type, i - 1, pos, quat, axis);
    }
}

static void test_chain_10000(void **state)
{
    const int32_t n = 10000;
    const double base[3] = {2000, -1000, 500};
    aqs_linkage *L = test_new_linkage();
    model_copy M;
    uint64_t s = 41;
    int32_t nq, i;
    double *q;
    (void)state;
    build_chain(L, &M, n, &s);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    q = malloc(sizeof(double) * (size_t)nq);
    /* at the zero position (free base at the origin) */
    check_all_poses(L, &M, CHAIN_POS_TOL, CHAIN_ROT_TOL);
    /* at random positions */
    random_positions(&s, &M, 0.05, base, q);
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
    {
        /* the far end is where the brief says: 1e3 .. 1e4 m out */
        double pos[3], quat[4], r;
        assert_int_equal(aqs_body_get_pose_world(L, n - 1, pos, quat), AQS_OK);
        r = sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]);
        assert_true(r > 1e3 && r < 2e4);
    }
    check_all_poses(L, &M, CHAIN_POS_TOL, CHAIN_ROT_TOL);
    /* one joint at a time (the O(log N) update of the cross poses): a few
     * joints early, in the middle and at the end */
    for (i = 0; i < 6; i++) {
        int32_t j = i < 2 ? 1 + i : i < 4 ? n / 2 + i : n - 1 - i, qo, jn;
        double v[7];
        assert_int_equal(aqs_joint_get_layout(L, j, &qo, &jn, NULL, NULL), AQS_OK);
        if (jn == 0) continue;
        random_positions(&s, &M, 0.05, base, q); /* fresh values; take joint j's */
        memcpy(v, q + qo, sizeof(double) * (size_t)jn);
        assert_int_equal(aqs_joint_set_position(L, j, v, jn), AQS_OK);
    }
    check_all_poses(L, &M, CHAIN_POS_TOL, CHAIN_ROT_TOL);
    /* after steps (positions moved by the solver; the reference reads them
     * back): gravity and a pull on the tip */
    {
        double g[3] = {0, 0, -9.81}, F[3] = {10, 0, 0};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
        assert_int_equal(aqs_body_set_force(L, n - 1, F, NULL, NULL), AQS_OK);
        for (i = 0; i < 3; i++) assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        {
            double *q2 = malloc(sizeof(double) * (size_t)nq);
            int32_t k, moved = 0;
            assert_int_equal(aqs_linkage_get_positions(L, q2, (size_t)nq), AQS_OK);
            for (k = 0; k < nq; k++) moved += q2[k] != q[k];
            assert_true(moved > 0); /* the steps did move the chain */
            free(q2);
        }
        check_all_poses(L, &M, CHAIN_POS_TOL, CHAIN_ROT_TOL);
    }
    free(q);
    model_release(&M);
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------- branched trees */

/* Random trees with fixed joints: welded groups inside the tree, bodies
 * welded to the world (with moving subtrees below them), several roots on
 * the world, a free base. Links of ~1 m, paths of up to a few hundred
 * joints, positions up to ~100 m: the chain argument above gives
 * sqrt(300) u 100 ~ 2e-13 (2e-14 seen); 1e-12 absolute. */
#define TREE_POS_TOL 1e-12
static void test_branched_trees(void **state)
{
    static const int types[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,
                                AQS_JOINT_FIXED,    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL,
                                AQS_JOINT_PLANAR,   AQS_JOINT_FIXED};
    uint64_t s = 42;
    int rep;
    (void)state;
    for (rep = 0; rep < 6; rep++) {
        int32_t n = rep < 4 ? 300 : 3000, i, nq;
        aqs_linkage *L = test_new_linkage();
        model_copy M;
        double *q, base[3] = {10, 20, -5};
        model_alloc(&M, n);
        for (i = 0; i < n; i++) {
            double pos[3], quat[4], axis[3];
            int32_t parent, type;
            int k;
            if (i == 0 || test_uniform(&s, 0, 1) < 0.02) parent = AQS_WORLD;
            else if (rep % 2) parent = (int32_t)test_uniform(&s, 0, i);
            else parent = (int32_t)test_uniform(&s, i > 3 ? i - 3 : 0, i);
            type = types[(int)test_uniform(&s, 0, 8)];
            if (i == 0) type = rep % 3 == 0 ? AQS_JOINT_FIXED : AQS_JOINT_FREE;
            test_add_body(L, test_uniform(&s, 0.5, 2), 0.3, 0.1, 0, 0.1);
            for (k = 0; k < 3; k++) {
                pos[k] = test_uniform(&s, -1, 1);
                axis[k] = test_uniform(&s, -1, 1);
            }
            test_random_quat(&s, quat);
            add_joint(L, &M, i, type, parent, pos, quat, axis);
        }
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
        q = malloc(sizeof(double) * ((size_t)nq + 1));
        check_all_poses(L, &M, TREE_POS_TOL, CHAIN_ROT_TOL);
        random_positions(&s, &M, 1.0, base, q);
        assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
        check_all_poses(L, &M, TREE_POS_TOL, CHAIN_ROT_TOL);
        {
            double g[3] = {0, -9.81, 0}, F[3] = {0, 0, 5}, P[3] = {0.1, 0, 0};
            assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
            assert_int_equal(aqs_body_set_force(L, n / 2, F, P, NULL), AQS_OK);
            for (i = 0; i < 2; i++) assert_int_equal(aqs_linkage_step(L, 1e-2), AQS_OK);
        }
        check_all_poses(L, &M, TREE_POS_TOL, CHAIN_ROT_TOL);
        free(q);
        model_release(&M);
        aqs_linkage_destroy(L);
    }
}

/* A hand-checked case: two revolute joints about z, 90 degrees each, the
 * second 1 m along the first body's x axis. */
static void test_small_closed_form(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double q[2] = {1.5707963267948966, 1.5707963267948966}, pos[3], quat[4], poses[14];
    (void)state;
    test_add_body(L, 1, 0.5, 0, 0, 0.1);
    test_add_body(L, 1, 0.5, 0, 0, 0.1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, 0, 1, 1, 0, 0, 0, 0, 1);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, 2), AQS_OK);
    assert_int_equal(aqs_body_get_pose_world(L, 1, pos, quat), AQS_OK);
    /* body 0 sits at the origin turned 90 degrees about z, so joint 1 (at
     * its (1, 0, 0)) is at (0, 1, 0); body 1 there is turned 180 degrees:
     * quaternion (0, 0, 0, +-1) */
    assert_true(fabs(pos[0]) < 1e-15 && fabs(pos[1] - 1) < 1e-15 && fabs(pos[2]) < 1e-15);
    assert_true(fabs(quat[0]) < 1e-15 && fabs(fabs(quat[3]) - 1) < 1e-15);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, poses, 14), AQS_OK);
    assert_true(fabs(poses[7]) < 1e-15 && fabs(poses[8] - 1) < 1e-15 && fabs(fabs(poses[13]) - 1) < 1e-15);
    assert_true(fabs(poses[3] - sqrt(0.5)) < 1e-15 && fabs(poses[6] - sqrt(0.5)) < 1e-15);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_small_closed_form),
        cmocka_unit_test(test_chain_10000),
        cmocka_unit_test(test_branched_trees),
    };
    return cmocka_run_group_tests_name("update", tests, NULL, NULL);
}
