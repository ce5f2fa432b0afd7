/* test_threads.c -- linkages used from several threads at once (docs/api.md,
 * "Thread safety and memory": distinct linkages are independent; one linkage
 * is used by one thread at a time). The library keeps no global mutable
 * state, so the same work gives the same bytes whether it runs alone or
 * beside other threads:
 *   - four jobs (random trees of 300-500 bodies: exact ABA steps, adaptive
 *     steps at rel_joint 2^-10 with the automatic path, the exact DCA solve
 *     with its refinement, an adaptive solve computing every joint), each
 *     run alone first, then all four at once in four threads, twice: every
 *     position, acceleration and constraint force is byte-identical;
 *   - each thread provokes an error on its own linkage while the others
 *     work: the message names that thread's value (the last error is per
 *     linkage, not shared);
 *   - the flush of subnormals inside a solve (src/base/fpenv.c) leaves
 *     each thread's MXCSR as it was.
 * The linkages are built on the main thread (the generator asserts with
 * cmocka, whose failures must not happen off the main thread); the threads
 * record their first failed check's line instead.
 * Run under the sanitizers by `make check SANITIZE=1` like every test. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"
#include "randtree.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "linkage.h"

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#define NJOBS 4
#define NSTEPS 30

typedef struct {
    int kind;               /* 0: exact ABA steps, 1: adaptive steps, 2: exact DCA solves, 3: adaptive, all */
    uint64_t seed;
    aqs_linkage *L;         /* built by the main thread (the generator asserts) */
    double *out;            /* positions, accelerations, forces after the run */
    size_t nout;
    int failed_line;        /* 0, or the line of the first failed check (no cmocka
                               assertion off the main thread) */
    int error_ok;           /* the provoked error named this job's value */
    int fenv_kept;          /* MXCSR after the run as before it */
} job;

#define CHECK(c)                                                                                   \
    do {                                                                                           \
        if (!(c)) {                                                                                \
            if (!jb->failed_line) jb->failed_line = __LINE__;                                      \
            return;                                                                                \
        }                                                                                          \
    } while (0)

static void make_job(job *jb, int kind)
{
    uint64_t rng;
    test_tree_spec sp = {0};
    memset(jb, 0, sizeof *jb);
    jb->kind = kind;
    jb->seed = 2026u + 7u * (uint64_t)kind;
    rng = jb->seed;
    sp.nbodies = 300 + (int32_t)(jb->seed % 200);
    sp.gravity = 1;
    sp.nforces = 4;
    sp.mass_spread = 10.0;
    sp.some_prismatic = sp.uniform_quat = 1;
    sp.revolute_only = kind == 2;
    jb->L = test_random_tree(&rng, &sp);
    switch (kind) {
    case 0:
        assert_int_equal(aqs_linkage_set_exact_solver(jb->L, AQS_EXACT_ABA), AQS_OK);
        break;
    case 1:
        assert_int_equal(aqs_linkage_set_tolerance(jb->L, AQS_METRIC_REL_JOINT, ldexp(1.0, -10)), AQS_OK);
        break;
    case 2: /* test_random_tree's exact solver is the DCA: refined exact solves */
        break;
    default:
        assert_int_equal(aqs_linkage_set_auto(jb->L, 0), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(jb->L, AQS_METRIC_REL_JOINT, ldexp(1.0, -60)), AQS_OK);
        break;
    }
}

static void run_job(job *jb)
{
    aqs_linkage *L = jb->L;
    int32_t nq, nv, nj, s;
    size_t at = 0;
    CHECK(aqs_linkage_get_sizes(L, NULL, &nj, &nq, &nv) == AQS_OK);
    for (s = 0; s < NSTEPS; s++) {
        if (jb->kind >= 2) CHECK(aqs_linkage_solve(L) == AQS_OK);
        CHECK(aqs_linkage_step(L, 1e-3) == AQS_OK);
        /* an error on this linkage while the other threads work: its own
         * message */
        if (s == NSTEPS / 2) {
            const double bad = -1.0 - (double)jb->kind;
            char want[64];
            const char *msg;
            CHECK(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, bad) == AQS_EINVAL);
            msg = aqs_linkage_last_error(L);
            snprintf(want, sizeof want, "%g", bad);
            jb->error_ok = msg && strstr(msg, "aqs_linkage_set_tolerance") && strstr(msg, want);
        }
    }
    CHECK(aqs_linkage_solve(L) == AQS_OK);
    jb->nout = (size_t)nq + (size_t)nv + 6 * (size_t)nj;
    jb->out = calloc(jb->nout, sizeof(double));
    CHECK(jb->out != NULL);
    CHECK(aqs_linkage_get_positions(L, jb->out + at, (size_t)nq) == AQS_OK);
    at += (size_t)nq;
    CHECK(aqs_linkage_get_accelerations(L, jb->out + at, (size_t)nv) == AQS_OK);
    at += (size_t)nv;
    CHECK(aqs_linkage_get_constraint_forces(L, jb->out + at, 6 * (size_t)nj) == AQS_OK);
}

static void *thread_main(void *arg)
{
    job *jb = arg;
#if defined(__SSE2__)
    const unsigned int before = _mm_getcsr();
#endif
    run_job(jb);
#if defined(__SSE2__)
    jb->fenv_kept = _mm_getcsr() == before;
#else
    jb->fenv_kept = 1;
#endif
    return NULL;
}

static void finish_job(job *jb)
{
    assert_int_equal(jb->failed_line, 0);
    assert_true(jb->error_ok);
    assert_true(jb->fenv_kept);
    aqs_linkage_destroy(jb->L);
    jb->L = NULL;
}

static void test_threads_match_alone(void **state)
{
    job alone[NJOBS], par[NJOBS];
    pthread_t th[NJOBS];
    int i, round;
    (void)state;
    /* alone: each in a thread of its own, one after the other */
    for (i = 0; i < NJOBS; i++) {
        make_job(&alone[i], i);
        assert_int_equal(pthread_create(&th[0], NULL, thread_main, &alone[i]), 0);
        assert_int_equal(pthread_join(th[0], NULL), 0);
        finish_job(&alone[i]);
    }
    /* all four at once, twice */
    for (round = 0; round < 2; round++) {
        for (i = 0; i < NJOBS; i++) make_job(&par[i], i);
        for (i = 0; i < NJOBS; i++) assert_int_equal(pthread_create(&th[i], NULL, thread_main, &par[i]), 0);
        for (i = 0; i < NJOBS; i++) assert_int_equal(pthread_join(th[i], NULL), 0);
        for (i = 0; i < NJOBS; i++) {
            finish_job(&par[i]);
            assert_int_equal(par[i].nout, alone[i].nout);
            assert_memory_equal(par[i].out, alone[i].out, sizeof(double) * alone[i].nout);
            free(par[i].out);
        }
    }
    /* the jobs differ from each other (the comparison above could fail) */
    assert_true(alone[0].nout != alone[1].nout ||
                memcmp(alone[0].out, alone[1].out, sizeof(double) * alone[0].nout) != 0);
    for (i = 0; i < NJOBS; i++) free(alone[i].out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_threads_match_alone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
