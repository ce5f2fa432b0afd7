/* test_units.c -- the unit of length: the same linkage built in metres, in
 * millimetres (the unit of most CAD models), in kilometres and at the powers
 * of two 2^10 and 2^-10 (lengths x s, inertias x s^2, gravity, forces and
 * their points x s). With revolute joints only, the joint accelerations are
 * the same physical answer in every unit (rad/s^2), and so are the four
 * joint measures of the adaptive solver, its certified bound, and its
 * rounding estimate (docs/math.md §10a, "The unit of length"). Before the
 * estimate weighed linear against angular parts by the linkage's length
 * scale, the rounding_bound of the backbone tree below moved from 2.7e-12
 * (metres) to 6.3e-10 (millimetres) and 1.4e-9 (kilometres), and that of a
 * 2,000-body random tree from 8.8e-9 (certified) to 5.7e-6 (not certified). */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "linkage.h"

#define NB 300

static const double kScales[] = {1.0, 1000.0, 1e-3, 1024.0, 1.0 / 1024.0};
#define NSCALES ((int)(sizeof kScales / sizeof kScales[0]))

/* A molecule-like tree of NB bodies with revolute joints: with backbone, the
 * first half a chain (a long straight-ish spine with lever arms of ~NB/2
 * m), the rest hung from random earlier bodies. Drawn from seed, built at
 * scale s. */
static aqs_linkage *build(uint64_t seed, int backbone, double s, int nforces)
{
    uint64_t rng = seed;
    aqs_linkage *L = NULL;
    int32_t i, nq;
    double *q, g[3];
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    for (i = 0; i < NB; i++) {
        double m = test_uniform(&rng, 1.0, 16.0), r = test_uniform(&rng, 0.3, 1.0), com[3], I[9] = {0};
        int k;
        for (k = 0; k < 3; k++) com[k] = s * test_uniform(&rng, -0.2, 0.2);
        I[0] = s * s * 0.4 * m * r * r * test_uniform(&rng, 0.8, 1.2);
        I[4] = s * s * 0.4 * m * r * r * test_uniform(&rng, 0.8, 1.2);
        I[8] = s * s * 0.4 * m * r * r * test_uniform(&rng, 0.8, 1.2);
        assert_int_equal(aqs_body_add(L, m, com, I, NULL), AQS_OK);
    }
    for (i = 0; i < NB; i++) {
        int32_t parent = i == 0 ? AQS_WORLD
                         : backbone && i < NB / 2 ? i - 1
                                                  : (int32_t)test_uniform(&rng, 0, i);
        double pos[3], axis[3], quat[4];
        int k;
        pos[0] = s * test_uniform(&rng, 0.8, 1.5);
        pos[1] = s * test_uniform(&rng, -0.3, 0.3);
        pos[2] = s * test_uniform(&rng, -0.3, 0.3);
        for (k = 0; k < 3; k++) axis[k] = test_uniform(&rng, -1, 1);
        test_random_quat(&rng, quat);
        if (parent >= i) parent = i - 1;
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, parent, i, pos, quat, axis, NULL), AQS_OK);
    }
    if (aqs_linkage_finalize(L) != AQS_OK) fail_msg("finalize: %s", aqs_linkage_last_error(L));
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    q = malloc(sizeof(double) * (size_t)nq);
    assert_non_null(q);
    for (i = 0; i < nq; i++) q[i] = test_uniform(&rng, -0.6, 0.6);
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
    free(q);
    g[0] = 0.0;
    g[1] = nforces < 8 ? 0.0 : -9.81 * s; /* gravity moves every joint */
    g[2] = 0.0;
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    for (i = 0; i < nforces; i++) {
        int32_t b = (int32_t)test_uniform(&rng, 0, NB);
        double f[3], p[3];
        int k;
        for (k = 0; k < 3; k++) {
            f[k] = s * test_uniform(&rng, -50, 50);
            p[k] = s * test_uniform(&rng, -0.2, 0.2);
        }
        assert_int_equal(aqs_body_set_force(L, b, f, p, NULL), AQS_OK);
    }
    return L;
}

static void accelerations(aqs_linkage *L, double *qdd)
{
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, NB), AQS_OK);
}

/* The exact answer is the same in every unit (a check of the generator:
 * the ABA agrees with itself to its rounding, 1e-15 .. 1e-14 here). */
static void test_exact_same_answer(void **state)
{
    int backbone, k;
    (void)state;
    for (backbone = 0; backbone < 2; backbone++) {
        double ref[NB], qdd[NB];
        for (k = 0; k < NSCALES; k++) {
            aqs_linkage *L = build(11 + (uint64_t)backbone, backbone, kScales[k], 8);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            accelerations(L, k == 0 ? ref : qdd);
            if (k > 0) {
                double e = test_rel_diff(qdd, ref, NB);
                if (!(e < 1e-12)) fail_msg("backbone %d, scale %g: ABA differs by %.3g", backbone, kScales[k], e);
            }
            aqs_linkage_destroy(L);
        }
    }
}

/* The adaptive solve under each joint measure: the same computed joints, the
 * same certified bound, and the same rounding estimate in every unit. The
 * solves are not bit for bit those of metres (x1000 is not exact in binary;
 * some of the DCA's choices, e.g. the frame of a node's relative mode, are
 * not unit-free), so the estimate is held to a factor 3 (it moved by
 * 230-650x before; here it agrees to 3 digits, but ratios of terms to a
 * result at rounding level, e.g. a grounded handle's b, can move it by 1.6x
 * under perturbations at the rounding level: seen on a 4,000-atom molecule);
 * at the powers of two, where every length, mass moment and load is scaled
 * exactly, to 1e-9 relative. */
static void test_adaptive_same_estimate(void **state)
{
    static const int32_t metrics[] = {AQS_METRIC_ABS_LINKAGE, AQS_METRIC_REL_LINKAGE, AQS_METRIC_ABS_JOINT,
                                      AQS_METRIC_REL_JOINT};
    static const double eps_of[] = {1e-3, 1.0 / 524288.0, 1e-4, 1.0 / 524288.0};
    int backbone, mi, k;
    (void)state;
    for (backbone = 0; backbone < 2; backbone++)
        for (mi = 0; mi < 4; mi++) {
            aqs_solve_stats ref;
            memset(&ref, 0, sizeof ref);
            for (k = 0; k < NSCALES; k++) {
                aqs_linkage *L = build(21 + (uint64_t)backbone, backbone, kScales[k], 8);
                aqs_solve_stats st;
                const int pow2 = k >= 3;
                assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
                assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK); /* the estimate itself */
                assert_int_equal(aqs_linkage_set_tolerance(L, metrics[mi], eps_of[mi]), AQS_OK);
                assert_int_equal(aqs_linkage_solve(L), AQS_OK);
                st.size = sizeof st;
                assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
                assert_true(isfinite(st.rounding_bound) && st.rounding_bound > 0.0);
                if (k == 0) {
                    ref = st;
                } else {
                    const double r = st.rounding_bound / ref.rounding_bound;
                    const int ok = pow2 ? fabs(r - 1.0) <= 1e-9 : r >= 1.0 / 3.0 && r <= 3.0;
                    if (!ok)
                        fail_msg("backbone %d, metric %d, scale %g: rounding_bound %.4g against %.4g in metres",
                                 backbone, (int)metrics[mi], kScales[k], st.rounding_bound, ref.rounding_bound);
                    assert_int_equal(st.certified, ref.certified);
                    if (pow2) {
                        assert_int_equal(st.computed_joints, ref.computed_joints);
                        assert_true(fabs(st.error_bound - ref.error_bound) <= 1e-9 * ref.error_bound);
                    } else {
                        /* near ties in the queue may go either way at x1000 */
                        assert_true(abs(st.computed_joints - ref.computed_joints) <= NB / 20);
                    }
                }
                aqs_linkage_destroy(L);
            }
        }
}

/* The rounding fallback (on by default) decides the same in every unit. With
 * two forces and no gravity, at rel_joint 2^-5, the random tree computes 36
 * of its 300 joints in every unit; before the length scale its estimate was
 * 7.3e-11 in metres but 3.2e-8 in millimetres, above the fallback's 1e-8, so
 * the same solve in millimetres was answered by the ABA (the adaptive
 * speedup lost for a model in the unit of most CAD files). */
static void test_fallback_same_decision(void **state)
{
    int backbone, k;
    (void)state;
    for (backbone = 0; backbone < 2; backbone++)
        for (k = 0; k < NSCALES; k++) {
            aqs_linkage *L = build(31 + (uint64_t)backbone, backbone, kScales[k], 2);
            aqs_solve_stats st;
            assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
            assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1.0 / 32.0), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            st.size = sizeof st;
            assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
            if (st.rounding_fallback)
                fail_msg("backbone %d, scale %g: fell back (rounding_bound %.3g)", backbone, kScales[k],
                         st.rounding_bound);
            assert_int_equal(st.path, AQS_PATH_ADAPTIVE);
            aqs_linkage_destroy(L);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_exact_same_answer),
        cmocka_unit_test(test_adaptive_same_estimate),
        cmocka_unit_test(test_fallback_same_decision),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
