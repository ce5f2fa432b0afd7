/*
 * auto_main.c -- aqs-auto (built as build/bench/auto_main): the automatic path
 * against the exact step, the two linkages stepped alternately in one process
 * (issue 14, item 3).
 *
 *   auto_main [--joints N] [--forces LIST] [--steps K] [--eps E] [--heavy F]
 *
 * Two copies of the molecule (bench/scenes.c, seed 1) under the same N_f
 * seeded unit forces: E is solved exactly (no tolerance: the articulated-body
 * step), A has rel_joint E (default 2^-19) with the automatic path on (the
 * library's default). Each takes K steps (default 40, dt 1e-3), one of E then
 * one of A; printed: the median step of each and A / E. What it measures is
 * what a user of either mode pays per step, with the same machine load on both
 * sides (aqs-bench times its exact steps on a third linkage right after a DCA
 * step, which is not the same thing: docs/bench.md, "The automatic path").
 * --heavy F: bench_build_molecule_heavy's molecule (every 400th terminal
 * atom F times heavier; the exact solves refine there), default 1.
 */
#define _POSIX_C_SOURCE 200809L

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

#define MAX_STEPS 1000

static double heavy = 1.0;

static aqs_linkage *molecule(int32_t joints, int32_t nf)
{
    aqs_linkage *L = NULL;
    bench_rng r;
    int32_t i;
    if (aqs_linkage_create(&L) != AQS_OK) return NULL;
    if (bench_build_molecule_heavy(L, joints, 1, heavy) != AQS_OK || aqs_linkage_finalize(L) != AQS_OK) {
        fprintf(stderr, "auto_main: %s\n", aqs_linkage_last_error(L));
        aqs_linkage_destroy(L);
        return NULL;
    }
    bench_rng_seed(&r, 7);
    for (i = 0; i < nf; i++) {
        double d[3];
        bench_rng_unit_vector(&r, d);
        if (aqs_body_set_force(L, (int32_t)bench_rng_below(&r, (uint64_t)joints), d, NULL, NULL) != AQS_OK) {
            aqs_linkage_destroy(L);
            return NULL;
        }
    }
    return L;
}

static int run(int32_t joints, int32_t nf, int32_t steps, double eps)
{
    static double te[MAX_STEPS], ta[MAX_STEPS];
    aqs_linkage *E = molecule(joints, nf), *A = molecule(joints, nf);
    aqs_solve_stats st;
    int32_t s, exact_steps = 0;
    int rc = 1;
    if (!E || !A) goto done;
    if (aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, eps) != AQS_OK) goto done;
    for (s = 0; s < steps; s++) {
        double t0 = bench_now();
        if (aqs_linkage_step(E, 1e-3) != AQS_OK) goto done;
        te[s] = bench_now() - t0;
        t0 = bench_now();
        if (aqs_linkage_step(A, 1e-3) != AQS_OK) goto done;
        ta[s] = bench_now() - t0;
        st.size = (uint32_t)sizeof st;
        if (aqs_linkage_get_stats(A, &st) != AQS_OK) goto done;
        exact_steps += st.path != AQS_PATH_ADAPTIVE;
    }
    {
        const double me = bench_median(te, (size_t)steps), ma = bench_median(ta, (size_t)steps);
        printf("%8d %6d %6d %11.3f %11.3f %8.3f %12d\n", (int)joints, (int)nf, (int)steps, me * 1e3, ma * 1e3,
               ma / me, (int)exact_steps);
    }
    rc = 0;
done:
    if (rc) fprintf(stderr, "auto_main: failed (N_f = %d)\n", (int)nf);
    aqs_linkage_destroy(E);
    aqs_linkage_destroy(A);
    return rc;
}

int main(int argc, char **argv)
{
    int32_t joints = 50000, steps = 40, nf[32], nnf = 0, a, i;
    double eps = 1.0 / 524288.0; /* 2^-19 */
    char forces[256] = "1,10,30,100,300,1000", *tok;
    for (a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--joints") && a + 1 < argc) joints = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--steps") && a + 1 < argc) steps = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--eps") && a + 1 < argc) eps = atof(argv[++a]);
        else if (!strcmp(argv[a], "--heavy") && a + 1 < argc) heavy = atof(argv[++a]);
        else if (!strcmp(argv[a], "--forces") && a + 1 < argc) {
            strncpy(forces, argv[++a], sizeof forces - 1);
            forces[sizeof forces - 1] = '\0';
        } else {
            fprintf(stderr, "usage: auto_main [--joints N] [--forces LIST] [--steps K] [--eps E] [--heavy F]\n");
            return 2;
        }
    }
    if (joints < 1 || steps < 1 || steps > MAX_STEPS || !(eps > 0.0) || !(heavy > 0.0)) {
        fprintf(stderr, "auto_main: need joints >= 1, 1 <= steps <= %d, eps > 0, heavy > 0\n", MAX_STEPS);
        return 2;
    }
    for (tok = strtok(forces, ","); tok && nnf < 32; tok = strtok(NULL, ",")) nf[nnf++] = atoi(tok);
    printf("molecule, rel_joint eps %g, automatic path on (A) against exact (E), steps alternated\n", eps);
    printf("%8s %6s %6s %11s %11s %8s %12s\n", "joints", "N_f", "steps", "E ms/step", "A ms/step", "A / E",
           "A exact steps");
    for (i = 0; i < nnf; i++)
        if (run(joints, nf[i], steps, eps) != 0) return 1;
    return 0;
}
