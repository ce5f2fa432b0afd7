/* autocount_main.c -- instruction counts of the automatic path against the
 * exact and the adaptive step, for callgrind (docs/bench.md, "The automatic
 * path"):
 *
 *   valgrind --tool=callgrind --toggle-collect=bench_counted_steps \
 *       build/bench/autocount_main MODE JOINTS FORCES STEPS [FORM [HEAVY]]
 *
 * MODE: auto (a tolerance, the automatic path on: the library's default),
 * adaptive (a tolerance, the automatic path off), exact (eps = 0, the
 * articulated-body algorithm) or exactdca (eps = 0, AQS_EXACT_DCA). The
 * molecule of JOINTS joints (HEAVY: bench_build_molecule_heavy's factor,
 * default 1: the plain molecule), FORCES forces
 * drawn as aqs-bench draws them (seed 1: the first FORCES distinct bodies of
 * one bench_rng sequence, 1 N at the centre of mass in a random direction),
 * rel_joint 2^-19, gravity off; dt as aqs-bench's (the fastest joint of the
 * exact first solve moves 1e-3 rad). One untimed solve (the full update after
 * setting the loads), then STEPS steps inside bench_counted_steps, the only
 * function callgrind counts. Prints the paths taken, the mean N_E and the
 * automatic path's costs of the last step (0 where it did not choose). FORM:
 * sqrt (the default) or phi, aqs_linkage_set_dca_form. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"

/* Not static, not inlined: callgrind's --toggle-collect names it. */
int bench_counted_steps(aqs_linkage *L, double dt, int steps, int *exact_steps, double *mean_ne);

__attribute__((noinline)) int bench_counted_steps(aqs_linkage *L, double dt, int steps,
                                                  int *exact_steps, double *mean_ne)
{
    int s;
    *exact_steps = 0;
    *mean_ne = 0.0;
    for (s = 0; s < steps; s++) {
        aqs_solve_stats st;
        if (aqs_linkage_step(L, dt) != AQS_OK) return 1;
        st.size = sizeof st;
        if (aqs_linkage_get_stats(L, &st) != AQS_OK) return 1;
        *exact_steps += st.path != AQS_PATH_ADAPTIVE;
        *mean_ne += st.computed_joints / (double)steps;
    }
    return 0;
}

int main(int argc, char **argv)
{
    aqs_linkage *L = NULL;
    int32_t joints, nf, steps, nv, k, i, exact_steps;
    const char *mode, *form = argc > 5 ? argv[5] : "sqrt";
    const double heavy = argc > 6 ? atof(argv[6]) : 1.0;
    double *qdd, amax = 0.0, dt, mean_ne;
    aqs_solve_stats last;
    bench_rng rng;
    unsigned char *used;
    if (argc < 5 || argc > 7) {
        fprintf(stderr, "usage: autocount_main auto|adaptive|exact|exactdca JOINTS FORCES STEPS [sqrt|phi [HEAVY]]\n");
        return 2;
    }
    mode = argv[1];
    joints = atoi(argv[2]);
    nf = atoi(argv[3]);
    steps = atoi(argv[4]);
    if ((strcmp(mode, "auto") && strcmp(mode, "adaptive") && strcmp(mode, "exact") && strcmp(mode, "exactdca")) ||
        joints < 1 || nf < 1 || nf > joints || steps < 1 || (strcmp(form, "sqrt") && strcmp(form, "phi")) ||
        !(heavy > 0.0)) {
        fprintf(stderr, "autocount_main: bad arguments\n");
        return 2;
    }
    if (aqs_linkage_create(&L) != AQS_OK ||
        aqs_linkage_set_dca_form(L, strcmp(form, "phi") ? AQS_DCA_FORM_SQRT : AQS_DCA_FORM_PHI) != AQS_OK ||
        bench_build_molecule_heavy(L, joints, BENCH_MOLECULE_SEED, heavy) != AQS_OK ||
        aqs_linkage_set_exact_solver(L, strcmp(mode, "exactdca") ? AQS_EXACT_ABA : AQS_EXACT_DCA) != AQS_OK ||
        aqs_linkage_finalize(L) != AQS_OK) {
        fprintf(stderr, "autocount_main: building: %s\n", L ? aqs_linkage_last_error(L) : "");
        return 1;
    }
    used = calloc((size_t)joints, 1);
    bench_rng_seed(&rng, 1);
    for (k = 0; k < nf;) {
        const int32_t body = (int32_t)bench_rng_below(&rng, (uint64_t)joints);
        double dir[3], com[3], f[3];
        if (used[body]) continue;
        used[body] = 1;
        bench_rng_unit_vector(&rng, dir);
        bench_scene_body_com(BENCH_SCENE_MOLECULE, body, com);
        for (i = 0; i < 3; i++) f[i] = dir[i];
        if (aqs_body_set_force(L, body, f, com, NULL) != AQS_OK) return 1;
        k++;
    }
    free(used);
    /* dt from the exact solve */
    aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv);
    qdd = malloc(sizeof(double) * (size_t)nv);
    if (aqs_linkage_solve(L) != AQS_OK || aqs_linkage_get_accelerations(L, qdd, (size_t)nv) != AQS_OK) return 1;
    for (i = 0; i < nv; i++) amax = fabs(qdd[i]) > amax ? fabs(qdd[i]) : amax;
    free(qdd);
    dt = sqrt(1e-3 / amax);
    if (strcmp(mode, "exact") != 0 && strcmp(mode, "exactdca") != 0) {
        if (aqs_linkage_set_auto(L, strcmp(mode, "auto") == 0) != AQS_OK ||
            aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)) != AQS_OK ||
            aqs_linkage_solve(L) != AQS_OK)
            return 1;
    }
    if (bench_counted_steps(L, dt, steps, &exact_steps, &mean_ne) != 0) {
        fprintf(stderr, "autocount_main: %s\n", aqs_linkage_last_error(L));
        return 1;
    }
    last.size = sizeof last;
    if (aqs_linkage_get_stats(L, &last) != AQS_OK) return 1;
    printf("{\"mode\":\"%s\",\"form\":\"%s\",\"heavy\":%g,\"joints\":%d,\"forces\":%d,\"steps\":%d,"
           "\"exact_steps\":%d,\"mean_ne\":%.1f,\"cost_adaptive\":%.4g,\"cost_exact\":%.4g}\n",
           mode, form, heavy, (int)joints, (int)nf, (int)steps, exact_steps, mean_ne, last.cost_adaptive,
           last.cost_exact);
    aqs_linkage_destroy(L);
    return 0;
}
