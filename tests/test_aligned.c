/* test_aligned.c -- the aligned frames (docs/math.md §13b): every solver
 * works in frames turned so that each joint's axis is z, with the world
 * leaf's frame its first joint's. Two descriptions of one planar chain:
 *
 *   oblique: world-aligned body frames, every revolute axis (0, 1, 1)/sqrt 2
 *            (the hard-case family "oblique");
 *   tilted:  body frames turned by C = [u v a] (joint.h), so that every axis
 *            is z, the root joint's frame turned by C in the world.
 *
 * Same bodies, same placements (C^T com = com, C^T (1, 0, 0) = (1, 0, 0)
 * and C^T diag(0.01, 0.1, 0.1) C = the same diagonal to the rounding), so
 * the same accelerations. The tilted one's articulated-body solve keeps its
 * frames as given (every C the identity), the reference; the problem is well
 * conditioned (hard cases: both within 1.3e-16 of a quad-precision
 * reference at 1,000 links). Before the aligned frames (main at 957bc39), at
 * 400 links: the oblique chain's articulated-body solve was 5.0e-9 off (its
 * error grows like n^3 u), the unrefined DCA 2.2e-10 (oblique) and 1.7e-11
 * (tilted) off, and the oblique chain's adaptive solves uncertified (answered
 * by the ABA, every joint computed); at 1,000 links the tilted chain's
 * certified bounds fell below the truth (docs/hardcases.md). Tolerance 1e-14
 * relative: 25x the rounding seen now (4.3e-16), 1e3x below the former
 * errors. The constraint-force test checks the getters' frames (the solvers
 * keep the aligned ones), which main passes too: its ABA's forces were
 * accurate to 1e-13 there. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { N = 400 };

static const double S2 = 0.70710678118654752; /* 1/sqrt 2 */

/* The chain; tilted = 0: oblique, 1: tilted. */
static aqs_linkage *chain(int tilted)
{
    const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, g[3] = {0, -9.81, 0};
    const double a_obl[3] = {0, S2, S2}, a_z[3] = {0, 0, 1}, q1[4] = {1, 0, 0, 0};
    /* C = [e_x, (0, s, -s), (0, s, s)]: a turn by -pi/4 about x */
    const double qC[4] = {cos(-0.39269908169872414), sin(-0.39269908169872414), 0, 0}; /* -pi/8 */
    aqs_linkage *L = test_new_linkage();
    int32_t prev = AQS_WORLD, b, i;
    for (i = 0; i < N; i++) {
        const double p[3] = {i ? 1.0 : 0.0, 0, 0};
        assert_int_equal(aqs_body_add(L, 1.0, com, I, &b), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, p, tilted && i == 0 ? qC : q1,
                                       tilted ? a_z : a_obl, NULL),
                         AQS_OK);
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    return L;
}

static double max_abs(const double *a, size_t n)
{
    double m = 0.0;
    size_t i;
    for (i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
    return m;
}

/* max |a - ref| over the joints computed (all when computed is NULL) / max |ref|. */
static double rel_err(const aqs_linkage *L, const double *a, const double *ref, int only_computed)
{
    double e = 0.0;
    int32_t i, c = 1;
    for (i = 0; i < N; i++) {
        if (only_computed) assert_int_equal(aqs_joint_get_computed(L, i, &c), AQS_OK);
        if (c) e = fmax(e, fabs(a[i] - ref[i]));
    }
    return e / max_abs(ref, N);
}

/* The reference: the tilted chain's articulated-body solve. */
static void reference(double *ref)
{
    aqs_linkage *L = chain(1);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, ref, N), AQS_OK);
    assert_true(fabs(ref[0]) > 1.0); /* the chain swings: gravity has a component in its plane */
    aqs_linkage_destroy(L);
}

static void test_every_solver(void **state)
{
    double ref[N], a[N];
    int t;
    (void)state;
    reference(ref);
    for (t = 0; t < 2; t++) {
        aqs_linkage *L = chain(t);
        int e;
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_ABA), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(L, a, N), AQS_OK);
        assert_true(rel_err(L, a, ref, 0) < 1e-14);
        /* the DCA without the refinement, which would hide its own error */
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
        assert_int_equal(aqs_linkage_set_exact_refinement(L, 0), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(L, a, N), AQS_OK);
        assert_true(rel_err(L, a, ref, 0) < 1e-14);
        /* adaptive: the computed joints as accurate, the bound true */
        for (e = 10; e <= 30; e += 10) {
            aqs_solve_stats st;
            double skipped = 0.0;
            int32_t i, c;
            memset(&st, 0, sizeof st);
            st.size = sizeof st;
            assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_JOINT, ldexp(1.0, -e)), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            assert_int_equal(aqs_linkage_get_accelerations(L, a, N), AQS_OK);
            assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
            assert_true(rel_err(L, a, ref, 1) < 1e-14);
            for (i = 0; i < N; i++) {
                assert_int_equal(aqs_joint_get_computed(L, i, &c), AQS_OK);
                if (!c) skipped = fmax(skipped, fabs(a[i] - ref[i]));
            }
            assert_true(st.certified);
            assert_true(st.computed_joints < N); /* the bound let it skip joints */
            /* the measure (the skipped joints' error) against the truth within
             * the certified bound */
            assert_true(skipped <= st.error_bound + st.rounding_bound);
        }
        aqs_linkage_destroy(L);
    }
}

/* Constraint forces are read in each child body's frame: turned to the
 * world, both descriptions give the same forces (the solvers keep them in
 * the aligned frames, the getters turn them back). */
static void test_constraint_forces_in_body_frames(void **state)
{
    static double f[2][6 * N];
    double fw[2][6 * N], scale;
    int t;
    int32_t j, h, r;
    (void)state;
    for (t = 0; t < 2; t++) {
        aqs_linkage *L = chain(t);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* the ABA */
        assert_int_equal(aqs_linkage_get_constraint_forces(L, f[t], 6 * N), AQS_OK);
        for (j = 0; j < N; j++) {
            double pos[3], quat[4], R[9];
            assert_int_equal(aqs_body_get_pose_world(L, j, pos, quat), AQS_OK); /* body j is joint j's child */
            test_quat_matrix(quat, R);
            for (h = 0; h < 6; h += 3)
                for (r = 0; r < 3; r++)
                    fw[t][6 * j + h + r] = R[3 * r] * f[t][6 * j + h] + R[3 * r + 1] * f[t][6 * j + h + 1] +
                                           R[3 * r + 2] * f[t][6 * j + h + 2];
        }
        aqs_linkage_destroy(L);
    }
    scale = max_abs(fw[1], 6 * N);
    assert_true(scale > 1.0);
    /* the oblique chain's body frames are the world's at q = 0 */
    assert_true(fabs(f[0][6 * (N - 1) + 4] - fw[0][6 * (N - 1) + 4]) <= 1e-15 * scale);
    assert_true(test_max_abs_diff(fw[0], fw[1], 6 * N) < 1e-13 * scale);
}

/* Two roots, the world leaf's frame turned as the first root joint's: a
 * 20-link chain 1e6 m away (first) and the tilted 400-link chain at the
 * origin, both in planes turned alike, so the second is solved in its plane's
 * frames too, its coordinates about the world's origin (frames.h). Its
 * accelerations from the unrefined DCA against the tilted chain's
 * articulated-body solve alone (the first chain is independent of it), within
 * 1e-14 relative as above. With the first root not turned (the world leaf's
 * frame then the world's, as before the aligned frames) this fails. */
static void test_far_first_root(void **state)
{
    const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, g[3] = {0, -9.81, 0};
    const double a_z[3] = {0, 0, 1}, q1[4] = {1, 0, 0, 0};
    const double qC[4] = {cos(-0.39269908169872414), sin(-0.39269908169872414), 0, 0};
    double ref[N], a[20 + N];
    aqs_linkage *L = test_new_linkage();
    int32_t prev = AQS_WORLD, b, i;
    (void)state;
    reference(ref);
    for (i = 0; i < 20 + N; i++) {
        const int first = i == 0 || i == 20;
        const double far[3] = {1e6, 0, 0}, one[3] = {1.0, 0, 0}, zero[3] = {0, 0, 0};
        if (i == 20) prev = AQS_WORLD;
        assert_int_equal(aqs_body_add(L, 1.0, com, I, &b), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, i == 0 ? far : first ? zero : one,
                                       first ? qC : q1, a_z, NULL),
                         AQS_OK);
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_refinement(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, a, 20 + N), AQS_OK);
    assert_true(rel_err(L, a + 20, ref, 0) < 1e-14);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_solver),
        cmocka_unit_test(test_far_first_root),
        cmocka_unit_test(test_constraint_forces_in_body_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
