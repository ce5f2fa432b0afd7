/* world_millipede.c -- the world measure on the millipede along a trajectory
 * (issue 16; docs/bench.md "4,000 steps: the molecule at N_f = 10 and the millipede").
 * Not built by any target. From the repository's top, after `make`:
 *
 *   gcc -O2 -std=gnu99 -Iinclude -Ibench -Itests -Itests/support -Isrc/model -Isrc/base \
 *       -Isrc/solve -Isrc/collide -Isrc/api tools/experiments/world_millipede.c bench/scenes.c \
 *       tests/support/*.c build/libaqs_internal.a -lcmocka -lccd -lm -lexpat -o /tmp/world_millipede
 *   /tmp/world_millipede STEPS EVERY E     # rel_world 2^-E, a 1 N pull on leg 400's link 9
 *
 * Every EVERY steps: N_E, the lower bound L_w against the true largest body
 * measure (an exact solve), and the queued nodes split by which part of
 * their key dominates: the inside bound E_in or the bound beyond the
 * handles they hold up E_h. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "aqs.h"
#include "linkage.h"
#include "worldbound.h"
#include "scenes.h"
#define main wb_test_main
#include "test_worldbound.c"
#undef main

static aqs_linkage *scene2(int kind, int size, int leg, int link)
{
    aqs_linkage *L;
    const double f[3] = {0.3, 0.8, -0.52}, z[3] = {0, 0, 0};
    aqs_linkage_create(&L);
    aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA);
    bench_build_scene(L, kind, size);
    aqs_linkage_finalize(L);
    aqs_body_set_force(L, kind == BENCH_SCENE_MILLIPEDE ? bench_millipede_leg_body(leg, link) : L->nbodies / 3, f, z, z);
    aqs_linkage_set_auto(L, 0);
    return L;
}


static void split(aqs_linkage *L, double *sin_, double *sh, int *nin, int *nh)
{
    int32_t i;
    *sin_ = *sh = 0; *nin = *nh = 0;
    for (i = 0; i < L->s.heap_size; i++) {
        int32_t n = L->s.heap_item[i];
        const struct worldbound *w = L->wb;
        double a = L->s.aval[n], R = w->sph[4 * n + 3] > 0 ? w->sph[4 * n + 3] : 0, rho = 2 * R + w->lmax[n];
        double ein = a > 0 ? sqrt(a) * (sqrt(w->sl2[n]) + rho * sqrt(w->sa2[n])) : 0, k = L->s.heap_key[i];
        if (k > ein * (1 + 1e-9)) { *sh += k; (*nh)++; } else { *sin_ += k; (*nin)++; }
    }
}

int main(int argc, char **argv)
{
    int steps = argc > 1 ? atoi(argv[1]) : 2000, every = argc > 2 ? atoi(argv[2]) : 250, s;
    double eps = ldexp(1.0, -(argc > 3 ? atoi(argv[3]) : 3)), dt, qmax = 0, *q;
    aqs_linkage *L = scene2(BENCH_SCENE_MILLIPEDE, 0, 400, 9);
    aqs_solve_stats st;
    int32_t i;
    st.size = sizeof st;
    q = malloc(sizeof(double) * L->nv);
    aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, 0.0);
    aqs_linkage_solve(L);
    aqs_linkage_get_accelerations(L, q, L->nv);
    for (i = 0; i < L->nv; i++) if (fabs(q[i]) > qmax) qmax = fabs(q[i]);
    dt = sqrt(1e-3 / qmax) * 30; /* larger motion, to deform within the run */
    for (s = 0; s <= steps; s++) {
        if (s % every == 0) {
            double tmax, sin_, sh; int nin, nh;
            aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, 0.0);
            aqs_linkage_solve(L);
            tmax = L->wb->lower;
            aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, eps);
            aqs_linkage_solve(L);
            aqs_linkage_get_stats(L, &st);
            split(L, &sin_, &sh, &nin, &nh);
            printf("step %5d: N_E %5d bound %.3g L_w %.4g true max %.4g (ratio %.3g) root R %.4g | queued: inside-dominated %d sum %.3g, held-dominated %d sum %.3g\n",
                   s, st.computed_joints, st.error_bound, L->wb->lower, tmax, L->wb->lower / tmax,
                   L->wb->sph[4 * L->t.root + 3], nin, sin_, nh, sh);
            fflush(stdout);
        }
        aqs_linkage_step(L, dt);
    }
    return 0;
}
