/* simd_main.c -- wall time of the adaptive step with the AVX kernels of
 * src/solve/dca.c against the SSE2 ones, interleaved in one process
 * (docs/bench.md, "AVX kernels for the square-root node"):
 *
 *   build/bench/simd_main JOINTS FORCES STEPS
 *
 * Two identical molecules of JOINTS joints with the forces of autocount_main
 * (FORCES forces drawn as aqs-bench draws them, seed 1, rel_joint 2^-19,
 * gravity off, dt from the exact first solve); the first takes the library's
 * choice (AVX where the processor has it), the second is enabled with
 * AQS_SIMD=sse2 (the path of a processor without AVX). STEPS steps of each,
 * alternately (the order swapped every step), each timed; then the two
 * linkages' accelerations must be identical, bit for bit (exit status 1 if
 * not). Prints one JSON line: the per-step medians and totals of both, and
 * the median over the steps of the ratio default / sse2 of the same step. */
#define _POSIX_C_SOURCE 200112L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

static int setup(aqs_linkage **out, int32_t joints, int32_t nf, int sse2, double *dt)
{
    aqs_linkage *L = NULL;
    bench_rng rng;
    unsigned char *used = calloc((size_t)joints, 1);
    double *qdd, amax = 0.0;
    int32_t k, i, nv;
    if (!used || aqs_linkage_create(&L) != AQS_OK || bench_build_molecule(L, joints, BENCH_MOLECULE_SEED) != AQS_OK ||
        aqs_linkage_finalize(L) != AQS_OK)
        return 1;
    bench_rng_seed(&rng, 1);
    for (k = 0; k < nf;) {
        const int32_t body = (int32_t)bench_rng_below(&rng, (uint64_t)joints);
        double dir[3], com[3];
        if (used[body]) continue;
        used[body] = 1;
        bench_rng_unit_vector(&rng, dir);
        bench_scene_body_com(BENCH_SCENE_MOLECULE, body, com);
        if (aqs_body_set_force(L, body, dir, com, NULL) != AQS_OK) return 1;
        k++;
    }
    free(used);
    aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv);
    qdd = malloc(sizeof(double) * (size_t)nv);
    if (!qdd || aqs_linkage_solve(L) != AQS_OK || aqs_linkage_get_accelerations(L, qdd, (size_t)nv) != AQS_OK)
        return 1;
    for (i = 0; i < nv; i++) amax = fabs(qdd[i]) > amax ? fabs(qdd[i]) : amax;
    free(qdd);
    *dt = sqrt(1e-3 / amax);
    /* the kernels are chosen when the adaptive solver is first enabled */
    if (sse2) setenv("AQS_SIMD", "sse2", 1);
    else unsetenv("AQS_SIMD");
    if (aqs_linkage_set_auto(L, 0) != AQS_OK ||
        aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)) != AQS_OK || aqs_linkage_solve(L) != AQS_OK)
        return 1;
    unsetenv("AQS_SIMD");
    *out = L;
    return 0;
}

int main(int argc, char **argv)
{
    aqs_linkage *L[2] = {NULL, NULL};
    int32_t joints, nf, steps, s, nv[2];
    double dt[2], *t[2], tot[2] = {0.0, 0.0}, *q[2], *ratio, ne = 0.0;
    int h;
    if (argc != 4 || (joints = atoi(argv[1])) < 1 || (nf = atoi(argv[2])) < 1 || nf > joints ||
        (steps = atoi(argv[3])) < 1) {
        fprintf(stderr, "usage: simd_main JOINTS FORCES STEPS\n");
        return 2;
    }
    for (h = 0; h < 2; h++) {
        if (setup(&L[h], joints, nf, h, &dt[h]) != 0) {
            fprintf(stderr, "simd_main: set-up: %s\n", L[h] ? aqs_linkage_last_error(L[h]) : "");
            return 1;
        }
        t[h] = malloc(sizeof(double) * (size_t)steps);
        if (!t[h]) return 1;
    }
    for (s = 0; s < steps; s++) {
        int k;
        for (k = 0; k < 2; k++) {
            const int hh = (s & 1) ? 1 - k : k;
            const double t0 = bench_now();
            aqs_solve_stats st;
            if (aqs_linkage_step(L[hh], dt[hh]) != AQS_OK) {
                fprintf(stderr, "simd_main: step: %s\n", aqs_linkage_last_error(L[hh]));
                return 1;
            }
            t[hh][s] = bench_now() - t0;
            tot[hh] += t[hh][s];
            st.size = sizeof st;
            if (hh == 0 && aqs_linkage_get_stats(L[hh], &st) == AQS_OK) ne += st.computed_joints / (double)steps;
        }
    }
    ratio = malloc(sizeof(double) * (size_t)steps);
    if (!ratio) return 1;
    for (s = 0; s < steps; s++) ratio[s] = t[0][s] / t[1][s]; /* paired: the same step of both */
    for (h = 0; h < 2; h++) {
        aqs_linkage_get_sizes(L[h], NULL, NULL, NULL, &nv[h]);
        q[h] = malloc(sizeof(double) * (size_t)nv[h]);
        if (!q[h] || aqs_linkage_get_accelerations(L[h], q[h], (size_t)nv[h]) != AQS_OK) return 1;
    }
    printf("{\"joints\":%d,\"forces\":%d,\"steps\":%d,\"mean_ne\":%.1f,\"default_ms_median\":%.4f,"
           "\"sse2_ms_median\":%.4f,\"default_ms_total\":%.2f,\"sse2_ms_total\":%.2f,\"ratio_median\":%.4f,\"identical\":%s}\n",
           (int)joints, (int)nf, (int)steps, ne, 1e3 * bench_median(t[0], (size_t)steps),
           1e3 * bench_median(t[1], (size_t)steps), 1e3 * tot[0], 1e3 * tot[1],
           bench_median(ratio, (size_t)steps),
           nv[0] == nv[1] && memcmp(q[0], q[1], sizeof(double) * (size_t)nv[0]) == 0 ? "true" : "false");
    s = nv[0] == nv[1] && memcmp(q[0], q[1], sizeof(double) * (size_t)nv[0]) == 0 ? 0 : 1;
    free(ratio);
    for (h = 0; h < 2; h++) {
        free(t[h]);
        free(q[h]);
        aqs_linkage_destroy(L[h]);
    }
    return s;
}
