/* test_fpenv.c -- the floating-point environment of a solve (src/base/fpenv.h,
 * docs/api.md "Subnormal numbers"): results that would be subnormal are
 * flushed to zero inside solve, step and refine, and the caller's MXCSR is
 * control bits are the same after every return, successful or not (its
 * exception flags keep what the solve raised). */
#include <float.h>
#include <math.h>
#include <string.h>

#include "testutil.h"

#if defined(__SSE2__)
#include <xmmintrin.h>
#define HAVE_SSE 1
/* MXCSR without its exception flags (bits 0-5), which any arithmetic may set */
#define CONTROL(c) ((c) & ~0x3fu)
#endif

/* A chain of n links of 1e5 kg (inertia 1e4 about the centre of mass, 0.5 m
 * from the axis), every joint driven by tau. n = 1, a pendulum: the exact
 * acceleration is tau / 3.5e4, subnormal (2.9e-309) for tau = 1e-304. */
static aqs_linkage *chain(int32_t n, double tau)
{
    aqs_linkage *L = test_new_linkage();
    int32_t i, prev = AQS_WORLD;
    for (i = 0; i < n; i++) {
        const int32_t b = test_add_body(L, 1e5, 0.5, 0, 0, 1e4);
        const int32_t j = test_add_joint(L, AQS_JOINT_REVOLUTE, prev, b, i ? 1.0 : 0.0, 0, 0, 0, 0, 1);
        (void)j;
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    for (i = 0; i < n; i++) assert_int_equal(aqs_joint_set_force(L, i, &tau, 1), AQS_OK);
    return L;
}

static void check_no_subnormal(aqs_linkage *L, int32_t n, int *zeros)
{
    double qdd[64];
    int32_t i;
    assert_true(n <= 64);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, (size_t)n), AQS_OK);
    for (i = 0; i < n; i++) {
        assert_true(fpclassify(qdd[i]) != FP_SUBNORMAL);
        assert_true(isfinite(qdd[i]));
        if (qdd[i] == 0.0) ++*zeros;
    }
}

static void test_flush_and_restore(void **state)
{
#ifdef HAVE_SSE
    const int32_t n = 40;
    aqs_linkage *L;
    unsigned int before;
    int zeros = 0, solver;
    (void)state;
    before = _mm_getcsr();
    assert_int_equal(before & _MM_FLUSH_ZERO_ON, 0); /* the process default: gradual underflow */
    /* The pendulum: tau = 1 gives tau / 3.5e4 exactly enough; tau = 1e-304
     * would give 2.9e-309, subnormal, and gives 0. */
    L = chain(1, 1.0);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    check_no_subnormal(L, 1, &zeros);
    assert_int_equal(zeros, 0);
    aqs_linkage_destroy(L);
    /* Both exact solvers and the adaptive one (solver 0, 1, 2), on the
     * pendulum and on a 40-link chain. */
    for (solver = 0; solver < 3; solver++) {
        int32_t size;
        for (size = 1; size <= n; size += n - 1) {
            zeros = 0;
            L = chain(size, 1e-304);
            if (solver == 1) assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
            if (solver == 2) {
                assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
                assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_JOINT, 1e-320), AQS_OK);
            }
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            assert_int_equal(CONTROL(_mm_getcsr()), CONTROL(before));
            check_no_subnormal(L, size, &zeros);
            if (size == 1) assert_int_equal(zeros, 1); /* flushed */
            assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
            assert_int_equal(CONTROL(_mm_getcsr()), CONTROL(before));
            if (solver == 2) {
                assert_int_equal(aqs_linkage_solve(L), AQS_OK);
                assert_int_equal(aqs_linkage_refine(L, 0.0), AQS_OK);
                assert_int_equal(CONTROL(_mm_getcsr()), CONTROL(before));
            }
            /* A failing call restores it as well. */
            assert_int_equal(aqs_linkage_step(L, -1.0), AQS_EINVAL);
            assert_int_equal(CONTROL(_mm_getcsr()), CONTROL(before));
            aqs_linkage_destroy(L);
        }
    }
    /* A caller that runs with flush-to-zero keeps it. */
    _mm_setcsr(before | _MM_FLUSH_ZERO_ON);
    L = chain(n, 1.0);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(CONTROL(_mm_getcsr()), CONTROL(before | _MM_FLUSH_ZERO_ON));
    aqs_linkage_destroy(L);
    _mm_setcsr(before);
#else
    (void)state;
    skip();
#endif
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flush_and_restore),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
