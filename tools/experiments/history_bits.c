/* history_bits.c -- two linkages in the same state, one of which once had a
 * tolerance (an adaptive solve, then eps reset to 0), stepped exactly side by
 * side: where their results differ in the last bits (docs/api.md, "Same state,
 * same bits?"). Not built by any target:
 *
 *   make -j2 && gcc -std=c99 -O2 -Iinclude -Ibench -o /tmp/history_bits \
 *       tools/experiments/history_bits.c bench/scenes.c build/libaqs.a -lccd -lm -lexpat
 *   /tmp/history_bits
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"

static aqs_linkage *build(int had_tolerance)
{
    aqs_linkage *L;
    int32_t b;
    if (aqs_linkage_create(&L) != AQS_OK || bench_build_molecule(L, 300, BENCH_MOLECULE_SEED) != AQS_OK ||
        aqs_linkage_finalize(L) != AQS_OK)
        exit(1);
    for (b = 5; b < 300; b += 37) {
        const double f[3] = {0.3, -1.0, 0.7}, p[3] = {0.01, 0.02, 0.0};
        if (aqs_body_set_force(L, b, f, p, NULL) != AQS_OK) exit(1);
    }
    if (had_tolerance && (aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3) != AQS_OK ||
                          aqs_linkage_solve(L) != AQS_OK ||
                          aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0) != AQS_OK))
        exit(1);
    return L;
}

int main(void)
{
    aqs_linkage *A = build(0), *B = build(1);
    int32_t nq, nv, s, i;
    double *qa, *qb, *aa, *ab;
    aqs_linkage_get_sizes(A, NULL, NULL, &nq, &nv);
    qa = malloc(sizeof(double) * (size_t)nq);
    qb = malloc(sizeof(double) * (size_t)nq);
    aa = malloc(sizeof(double) * (size_t)nv);
    ab = malloc(sizeof(double) * (size_t)nv);
    if (!qa || !qb || !aa || !ab) return 1;
    for (s = 0; s < 5; s++) {
        double dmax = 0.0, amax = 0.0, rmax = 0.0, qmax = 0.0;
        int32_t worst = -1, nqd = 0;
        if (aqs_linkage_step(A, 1e-3) != AQS_OK || aqs_linkage_step(B, 1e-3) != AQS_OK) return 1;
        aqs_linkage_get_positions(A, qa, (size_t)nq);
        aqs_linkage_get_positions(B, qb, (size_t)nq);
        aqs_linkage_get_accelerations(A, aa, (size_t)nv);
        aqs_linkage_get_accelerations(B, ab, (size_t)nv);
        for (i = 0; i < nv; i++) {
            const double d = fabs(aa[i] - ab[i]), r = d / (fabs(aa[i]) + 1e-300);
            dmax = fmax(dmax, d);
            amax = fmax(amax, fabs(aa[i]));
            if (r > rmax) {
                rmax = r;
                worst = i;
            }
        }
        for (i = 0; i < nq; i++) {
            nqd += qa[i] != qb[i];
            qmax = fmax(qmax, fabs(qa[i] - qb[i]));
        }
        printf("step %d: accelerations %s, largest difference %.3g of the largest acceleration", (int)s,
               memcmp(aa, ab, sizeof(double) * (size_t)nv) ? "differ" : "bit for bit the same", dmax / amax);
        if (worst >= 0)
            printf(" (%.3g relative at dof %d, %.3g of the largest)", rmax, (int)worst, fabs(aa[worst]) / amax);
        printf("; %d of %d positions differ, by up to %.3g\n", (int)nqd, (int)nq, qmax);
    }
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
    free(qa);
    free(qb);
    free(aa);
    free(ab);
    return 0;
}
