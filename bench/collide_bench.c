/* collide_bench.c -- speed of the lazy self-collision query on the assembly
 * tree after an adaptive step, against a brute-force all-pairs query and a
 * fresh full-tree query, side by side in one run (docs/bench.md, section
 * "Collision"). Self-contained: it builds its own millipede and molecule
 * (the shapes of the paper's scenes, bench/README.md), one sphere or capsule
 * per body.
 *
 *   build/bench/collide_bench [reps]     (make bench-collide)
 *
 * Per scene and size: an adaptive solver (relative joint-wise error
 * 2^-19), one applied force (N_f = 1) on a random body, no gravity. Two
 * identical copies of the scene take the same adaptive steps; after each,
 * the lazy query is timed on one, the full-tree and brute-force queries on
 * the other (same positions, both tree queries right after a step), and the
 * three must find the same number of contacts (brute force on every
 * repetition, on the first only at 50,000 atoms). Medians over the
 * repetitions, after WARMUP steps; also per row the mean lazy time per
 * processed node, the sphere tests per processed node, the near-list pairs
 * re-tested and the certificates reused / made by the lazy query (aqs_linkage_get_query_stats
 * counters: docs/collision.md, "Certificates"). */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "aqs.h"

static const double Q1[4] = {1, 0, 0, 0}, O3[3] = {0, 0, 0};

/* Steps (lazy queries on the lazy copy, untimed) before the timed ones, so
 * that the first certificates, made after setup's full query, are not timed. */
#define WARMUP 3

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t rng_state = 88172645463325252ull;
static double uniform(void) /* xorshift64*, [0, 1) */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ull) >> 11) / 9007199254740992.0;
}

static int check(aqs_linkage *L, aqs_status st, const char *what)
{
    if (st != AQS_OK) {
        fprintf(stderr, "collide_bench: %s: %s\n", what, aqs_linkage_last_error(L));
        return 1;
    }
    return 0;
}

static int add_link(aqs_linkage *L, double mass, double cx, int32_t parent, const double pos[3],
                    const double quat[4], const double axis[3], int32_t *body)
{
    const double com[3] = {cx, 0, 0}, I[9] = {0.1 * mass, 0, 0, 0, 0.1 * mass, 0, 0, 0, 0.1 * mass};
    return check(L, aqs_body_add(L, mass, com, I, body), "aqs_body_add") ||
           check(L, aqs_joint_add(L, AQS_JOINT_REVOLUTE, parent, *body, pos, quat, axis, NULL), "aqs_joint_add");
}

/* Millipede: spine rods of 1 m along x (axes alternating z, y; a free base),
 * a leg of 10 links of 0.3 m on every third rod. A capsule along each rod
 * and leg link (radius 0.12 / 0.05). */
static int build_millipede(aqs_linkage *L, int32_t spine)
{
    const double zax[3] = {0, 0, 1}, yax[3] = {0, 1, 0}, half = 0.70710678118654752;
    const double along_x[4] = {half, 0, half, 0}; /* capsule z onto body x */
    int32_t i, k, b;
    for (i = 0; i < spine; i++) {
        const double pos[3] = {i ? 1.0 : 0.0, 0, 0}, cap[3] = {0.12, 0.35, 0}, at[3] = {0.5, 0, 0};
        if (i == 0) {
            const double com[3] = {0.5, 0, 0}, I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
            if (check(L, aqs_body_add(L, 1.0, com, I, &b), "aqs_body_add") ||
                check(L, aqs_joint_add(L, AQS_JOINT_FREE, AQS_WORLD, b, O3, Q1, NULL, NULL), "free joint"))
                return 1;
        } else if (add_link(L, 1.0, 0.5, b, pos, Q1, i % 2 ? zax : yax, &b)) {
            return 1;
        }
        if (check(L, aqs_shape_add(L, b, AQS_SHAPE_CAPSULE, cap, at, along_x, NULL), "aqs_shape_add"))
            return 1;
    }
    for (i = 0; i < spine; i += 3) {
        const double s = (i / 3) % 2 ? -1.0 : 1.0, q[4] = {half, 0, 0, s * half}; /* x onto +-y */
        int32_t parent = i, lb;
        for (k = 0; k < 10; k++) {
            const double first[3] = {0.5, 0, 0}, next[3] = {0.3, 0, 0}, cap[3] = {0.05, 0.1, 0};
            const double at[3] = {0.15, 0, 0};
            if (add_link(L, 0.1, 0.15, parent, k ? next : first, k ? Q1 : q, k % 2 ? yax : zax, &lb) ||
                check(L, aqs_shape_add(L, lb, AQS_SHAPE_CAPSULE, cap, at, along_x, NULL), "aqs_shape_add"))
                return 1;
            parent = lb;
        }
    }
    return 0;
}

/* Molecule-like tree: a backbone with side chains of 1-4 atoms on about
 * half its atoms; bonds of 1.5 along each atom's z, bond angles 111 degrees,
 * random backbone dihedrals, a side chain 120 degrees from the backbone; torsion joints about the incoming bond; a sphere of
 * radius 0.4 per atom (a hard core: atoms closer than 0.8 touch). */
static int build_molecule(aqs_linkage *L, int32_t natoms, double r)
{
    const double zax[3] = {0, 0, 1}, deg = 3.14159265358979323846 / 180.0;
    const double third = 2.0 * 3.14159265358979323846 / 3.0;
    double next_phi = 0.0; /* dihedral of the next backbone atom, drawn in advance */
    int32_t n = 0, prev = AQS_WORLD, b;
    while (n < natoms) {
        int32_t parent = prev, len = 0, k;
        /* a backbone atom, then maybe a side chain */
        for (k = 0; k <= len && n < natoms; k++) {
            /* the backbone continues at next_phi; a side chain leaves 120 degrees
             * away from it (as substituents do); further side atoms at random */
            double a = (180.0 - 111.0) * deg, phi = k == 0 ? next_phi : k == 1 ? next_phi + third
                                                               : 3.0 * third * uniform();
            double pos[3], quat[4];
            const double sz[3] = {r, 0, 0};
            if (parent == AQS_WORLD) {
                pos[0] = pos[1] = pos[2] = 0.0;
                memcpy(quat, Q1, sizeof quat);
            } else {
                /* child frame: Rz(phi) Ry(a), at 1.5 along its own z */
                double cz = cos(0.5 * phi), sz2 = sin(0.5 * phi), cy = cos(0.5 * a), sy = sin(0.5 * a);
                quat[0] = cz * cy;
                quat[1] = -sz2 * sy;
                quat[2] = cz * sy;
                quat[3] = sz2 * cy;
                pos[0] = 1.5 * sin(a) * cos(phi);
                pos[1] = 1.5 * sin(a) * sin(phi);
                pos[2] = 1.5 * cos(a);
            }
            if (add_link(L, 14.0, 0.0, parent, pos, quat, zax, &b) ||
                check(L, aqs_shape_add(L, b, AQS_SHAPE_SPHERE, sz, O3, Q1, NULL), "aqs_shape_add"))
                return 1;
            n++;
            if (k == 0) {
                prev = b;
                next_phi = 3.0 * third * uniform();
                if (uniform() < 0.5) len = 1 + (int32_t)(4.0 * uniform());
            }
            parent = b;
        }
    }
    return 0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof(double), cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Build a scene, load it (one force), set the adaptive tolerance, take one
 * step and run the first (allocating) query. dt: the largest joint
 * increment dt^2 |qdd| of the exact solve is 1e-3. */
static aqs_linkage *setup(int which, int32_t size, double radius, double *dt)
{
    aqs_linkage *L = NULL;
    int32_t bodies, nv, i;
    double *qdd, m = 0.0;
    size_t count;
    const double f[3] = {0.0, 1.0, 0.5};
    if (aqs_linkage_create(&L) != AQS_OK) return NULL;
    if ((which == 0 ? build_millipede(L, size) : build_molecule(L, size, radius)) ||
        check(L, aqs_linkage_finalize(L), "aqs_linkage_finalize"))
        return NULL;
    aqs_linkage_get_sizes(L, &bodies, NULL, NULL, &nv);
    if (check(L, aqs_body_set_force(L, (int32_t)(uniform() * bodies), f, NULL, NULL), "force")) return NULL;
    qdd = calloc((size_t)nv, sizeof(double));
    if (!qdd || check(L, aqs_linkage_solve(L), "solve")) return NULL;
    aqs_linkage_get_accelerations(L, qdd, (size_t)nv);
    for (i = 0; i < nv; i++) m = fmax(m, fabs(qdd[i]));
    free(qdd);
    *dt = sqrt(1e-3 / m);
    if (check(L, aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), "tolerance") ||
        check(L, aqs_linkage_step(L, *dt), "step") ||
        aqs_linkage_collide(L, AQS_COLLIDE_FULL, NULL, 0, &count) == AQS_ENOMEM)
        return NULL;
    return L;
}

/* Two identical linkages stepped identically (the library is deterministic):
 * one queried lazily, the other by a full-tree then a brute-force query, so
 * both tree queries start right after a step (same cache state). */
static int run(const char *name, int which, int32_t size, double radius, int reps, int brute_every)
{
    aqs_linkage *A, *B;
    int32_t bodies, r, nodes;
    double *tl = calloc((size_t)reps, sizeof(double)), *tf = calloc((size_t)reps, sizeof(double));
    double *tb = calloc((size_t)reps, sizeof(double)), *ratio_f = calloc((size_t)reps, sizeof(double));
    double *ratio_b = calloc((size_t)reps, sizeof(double)), *proc = calloc((size_t)reps, sizeof(double));
    double *refit = calloc((size_t)reps, sizeof(double)), *vt = calloc((size_t)reps, sizeof(double));
    double *vtf = calloc((size_t)reps, sizeof(double)), *per = calloc((size_t)reps, sizeof(double));
    double *tper = calloc((size_t)reps, sizeof(double)), *near = calloc((size_t)reps, sizeof(double));
    double *reused = calloc((size_t)reps, sizeof(double)), *made = calloc((size_t)reps, sizeof(double));
    double lazy_sum = 0.0, proc_sum = 0.0;
    int nb = 0;
    double dt, dt2;
    size_t count = 0, cf = 0, cb = 0;
    int bad = 0;
    uint64_t seed = rng_state;
    A = setup(which, size, radius, &dt);
    rng_state = seed;
    B = setup(which, size, radius, &dt2);
    if (!A || !B || dt != dt2 || !tl || !tf || !tb || !ratio_f || !ratio_b || !proc || !refit || !vt ||
        !vtf || !per || !tper || !near || !reused || !made)
        return 1;
    aqs_linkage_get_sizes(A, &bodies, NULL, NULL, NULL);
    aqs_linkage_get_tree_stats(A, &nodes, NULL, NULL, NULL);
    for (r = 0; r < WARMUP; r++) /* certificates made after setup's full query */
        if (check(A, aqs_linkage_step(A, dt), "step") || check(B, aqs_linkage_step(B, dt), "step") ||
            aqs_linkage_collide(A, AQS_COLLIDE_LAZY, NULL, 0, &count) == AQS_ENOMEM)
            return 1;
    for (r = 0; r < reps; r++) {
        aqs_solve_stats st;
        aqs_collision_stats cs;
        double t0;
        aqs_status s;
        if (check(A, aqs_linkage_step(A, dt), "step") || check(B, aqs_linkage_step(B, dt), "step")) return 1;
        st.size = sizeof st;
        aqs_linkage_get_stats(A, &st);
        t0 = now();
        s = aqs_linkage_collide(A, AQS_COLLIDE_LAZY, NULL, 0, &count);
        tl[r] = now() - t0;
        cs.size = sizeof cs;
        aqs_linkage_get_query_stats(A, &cs);
        refit[r] = cs.nodes_refit;
        vt[r] = cs.volume_tests;
        near[r] = cs.near_tests;
        reused[r] = cs.certs_reused;
        made[r] = cs.certs_made;
        t0 = now();
        s |= aqs_linkage_collide(B, AQS_COLLIDE_FULL, NULL, 0, &cf);
        tf[r] = now() - t0;
        cs.size = sizeof cs;
        aqs_linkage_get_query_stats(B, &cs);
        vtf[r] = cs.volume_tests;
        if (r % brute_every == 0) {
            t0 = now();
            s |= aqs_linkage_collide(B, AQS_COLLIDE_BRUTE, NULL, 0, &cb);
            tb[nb] = now() - t0;
            ratio_b[nb] = tb[nb] / tl[r];
            nb++;
        }
        if ((s != AQS_OK && s != AQS_ESIZE) || cf != count || cb != count) bad = 1;
        proc[r] = st.nodes_processed;
        ratio_f[r] = tf[r] / tl[r];
        per[r] = 1e6 * tl[r] / (st.nodes_processed > 0 ? st.nodes_processed : 1);
        tper[r] = vt[r] / (st.nodes_processed > 0 ? st.nodes_processed : 1);
        lazy_sum += tl[r];
        proc_sum += st.nodes_processed;
    }
    printf("| %s | %d | %d | %.0f | %.0f | %.0f | %.0f | %zu | %.3g | %.3g | %.3g | %.1f | %.0f | %.2f "
           "| %.2f | %.1f | %.0f | %.0f / %.0f |%s\n",
           name, (int)bodies, (int)nodes, median(proc, reps), median(refit, reps), median(vt, reps),
           median(vtf, reps), count, 1e3 * median(tl, reps), 1e3 * median(tf, reps),
           1e3 * median(tb, nb), median(ratio_f, reps), median(ratio_b, nb), median(per, reps),
           1e6 * lazy_sum / (proc_sum > 0 ? proc_sum : 1), median(tper, reps), median(near, reps),
           median(reused, reps), median(made, reps), bad ? " MISMATCH" : "");
    fflush(stdout);
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
    free(tl); free(tf); free(tb); free(ratio_f); free(ratio_b); free(proc);
    free(refit); free(vt); free(vtf); free(per); free(tper); free(near); free(reused); free(made);
    return bad;
}

int main(int argc, char **argv)
{
    int reps = argc > 1 ? atoi(argv[1]) : 9, bad = 0;
    if (reps < 1) reps = 1;
    printf("Collision queries after one adaptive step (rel. joint 2^-19, N_f = 1), medians of %d "
           "repetitions after %d warm-up steps; times in ms.\n\n", reps, WARMUP);
    printf("| scene | bodies | tree nodes | processed nodes | refitted | sphere tests lazy | sphere tests full "
           "| contacts | lazy | full tree | brute force | full / lazy | brute / lazy | lazy us per processed node "
           "| lazy us per processed node, mean | sphere tests per processed node | near pairs re-tested "
           "| certificates reused / made |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    bad |= run("millipede", 0, 300, 0, reps, 1);  /* 300 spine + 100 legs: 1,300 bodies */
    bad |= run("millipede", 0, 3000, 0, reps, 1); /* 13,000 bodies: the paper's */
    /* atoms of radius 0.3: the random coil (no excluded volume) touches
     * itself in ~5% of its atoms, radius 0.6 in ~40%: every subassembly
     * holding a contact replays it at each query */
    bad |= run("molecule r=0.3", 1, 1000, 0.3, reps, 1);
    bad |= run("molecule r=0.3", 1, 10000, 0.3, reps, 1);
    bad |= run("molecule r=0.6", 1, 10000, 0.6, reps, 1);
    /* atoms of radius 0.1: few contacts (0.3% of the atoms), so the lazy
     * query's cost is that of the processed nodes */
    bad |= run("molecule r=0.1", 1, 1000, 0.1, reps, 1);
    bad |= run("molecule r=0.1", 1, 10000, 0.1, reps, 1);
    bad |= run("molecule r=0.1", 1, 50000, 0.1, reps, reps); /* brute force: ~8 s a query */
    if (bad) fprintf(stderr, "collide_bench: the three queries disagreed (MISMATCH rows)\n");
    return bad;
}
