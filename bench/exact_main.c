/*
 * exact_main.c -- aqs-exact (built as build/bench/exact_main): the exact pass
 * (aqs_linkage_set_positions + aqs_linkage_solve, the articulated-body
 * algorithm) per joint at several sizes of one scene, timed interleaved in one
 * process, and the memory each linkage holds (counted by its allocator).
 *
 *   exact_main [--scene NAME] [--sizes LIST] [--rounds R] [--reps K]
 *              [--gravity] [--tolerance] [--memory] [--trace]
 *   exact_main --bandwidth MB
 *
 * Each linkage gets one force (1 N at the centre of mass of a seeded body,
 * seeded direction; gravity off unless --gravity). Every pass sets the
 * positions q0 + 1e-3 sin(i + pass) (a fresh state, as after a step) and
 * solves. A round times K passes of each size in turn; the figure per size is
 * the median over rounds of each round's median pass, divided by the joints.
 * The ratio column is the time per joint against the first size's, in the
 * same run. "B/joint" is what the linkage holds after the first solve (peak
 * and current; aqs_linkage_get_memory, checked against a counting allocator),
 * divided by the joints; --tolerance sets rel_joint 2^-19 on the linkages
 * first (the adaptive solver's storage) but still solves exactly by
 * aqs_linkage_set_tolerance(..., 0) after. --memory: after the timed rounds,
 * each linkage gets rel_joint 2^-19 and one solve, and its memory per joint is
 * printed exact and with the tolerance, by category (make bench-scaling).
 *
 * --trace: every pass's time as it is taken, "trace JOINTS ROUND PASS NS_PER_JOINT"
 * (to see a size's passes one by one: the first after another size, bimodality).
 *
 * --bandwidth MB: the single-core streaming read bandwidth, the floor of a
 * pass over memory: MB megabytes of doubles summed with 4 accumulators, 7
 * times; prints the median and best GB/s.
 *
 * Instruction counts: run one size under callgrind with
 *   valgrind --tool=callgrind --toggle-collect=bench_exact_pass \
 *       build/bench/exact_main --sizes 5000 --rounds 1 --reps 10
 * and divide by reps x joints (the toggle covers only the timed passes).
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

#define MAX_SIZES 16

typedef struct {
    size_t now, peak;
} counter;

static void *count_alloc(void *user, size_t size)
{
    counter *c = (counter *)user;
    size_t *p = (size_t *)malloc(size + 16);
    if (!p) return NULL;
    p[0] = size;
    c->now += size;
    if (c->now > c->peak) c->peak = c->now;
    return (char *)p + 16;
}

static void count_free(void *user, void *ptr)
{
    counter *c = (counter *)user;
    size_t *p = (size_t *)((char *)ptr - 16);
    c->now -= p[0];
    free(p);
}

typedef struct {
    int32_t size, joints, nq;
    aqs_linkage *L;
    counter mem;
    double *q0, *q;
    double *round_ns; /* per round: median ns per pass */
} item;

int bench_exact_pass(aqs_linkage *L, const double *q, size_t nq);

/* One exact pass: the positions, then the solve. Kept out of line so that
 * callgrind can toggle on it. */
__attribute__((noinline)) int bench_exact_pass(aqs_linkage *L, const double *q, size_t nq)
{
    if (aqs_linkage_set_positions(L, q, nq) != AQS_OK) return 1;
    return aqs_linkage_solve(L) != AQS_OK;
}

/* What the linkage holds by its own count; a mismatch with the counting
 * allocator (which sees every request) is an error of the count. */
static aqs_memory_stats memory(const item *it)
{
    aqs_memory_stats m;
    memset(&m, 0, sizeof m);
    m.size = sizeof m;
    if (aqs_linkage_get_memory(it->L, &m) != AQS_OK || m.bytes != it->mem.now || m.peak != it->mem.peak)
        fprintf(stderr, "exact_main: aqs_linkage_get_memory (%llu, peak %llu) differs from the allocator's count (%zu, peak %zu)\n",
                (unsigned long long)m.bytes, (unsigned long long)m.peak, it->mem.now, it->mem.peak);
    return m;
}

static int fail(aqs_linkage *L, const char *what)
{
    fprintf(stderr, "exact_main: %s failed: %s\n", what, L ? aqs_linkage_last_error(L) : "");
    return 1;
}

static int setup(item *it, int scene, int gravity, int tolerance)
{
    const double zero[3] = {0, 0, 0};
    int32_t bodies, nv, i, body;
    double f[3], p[3];
    bench_rng rng;
    if (aqs_linkage_create_with_allocator(count_alloc, count_free, &it->mem, &it->L) != AQS_OK)
        return fail(NULL, "create");
    if (bench_build_scene(it->L, (bench_scene_kind)scene, it->size) != AQS_OK) return fail(it->L, "build");
    if (aqs_linkage_finalize(it->L) != AQS_OK) return fail(it->L, "finalize");
    if (aqs_linkage_get_sizes(it->L, &bodies, &it->joints, &it->nq, &nv) != AQS_OK) return fail(it->L, "sizes");
    it->q0 = (double *)malloc(sizeof(double) * (size_t)it->nq + 8);
    it->q = (double *)malloc(sizeof(double) * (size_t)it->nq + 8);
    if (!it->q0 || !it->q) return fail(NULL, "malloc");
    if (aqs_linkage_get_positions(it->L, it->q0, (size_t)it->nq) != AQS_OK) return fail(it->L, "positions");
    if (!gravity && aqs_linkage_set_gravity(it->L, zero) != AQS_OK) return fail(it->L, "gravity");
    bench_rng_seed(&rng, 1);
    body = scene == BENCH_SCENE_MILLIPEDE ? BENCH_MILLIPEDE_SPINE + (int32_t)bench_rng_below(&rng, (uint64_t)(bodies - BENCH_MILLIPEDE_SPINE))
                                          : (int32_t)bench_rng_below(&rng, (uint64_t)bodies);
    bench_rng_unit_vector(&rng, f);
    bench_scene_body_com((bench_scene_kind)scene, body, p);
    if (aqs_body_set_force(it->L, body, f, p, NULL) != AQS_OK) return fail(it->L, "force");
    if (tolerance) {
        if (aqs_linkage_set_tolerance(it->L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)) != AQS_OK ||
            aqs_linkage_solve(it->L) != AQS_OK || aqs_linkage_set_tolerance(it->L, AQS_METRIC_REL_JOINT, 0.0) != AQS_OK)
            return fail(it->L, "tolerance");
    }
    (void)i;
    return bench_exact_pass(it->L, it->q0, (size_t)it->nq) ? fail(it->L, "first pass") : 0;
}

/* Positions of pass k: q0 moved a little (unit quaternions of free joints
 * are left as they are: the perturbation touches the revolute angles only
 * when the scene has no free joint; the millipede's first 7 are skipped). */
static void positions(item *it, int scene, int k)
{
    int32_t i, lo = scene == BENCH_SCENE_MILLIPEDE ? 7 : 0;
    memcpy(it->q, it->q0, sizeof(double) * (size_t)it->nq);
    for (i = lo; i < it->nq; i++) it->q[i] += 1e-3 * sin((double)i + 0.7 * k);
}

static int bandwidth(long mb)
{
    size_t n = (size_t)mb * 1000000 / sizeof(double), i;
    double *x = (double *)malloc(n * sizeof(double)), gbs[7], best = 0.0, sink = 0.0;
    int r;
    if (!x) return fail(NULL, "malloc");
    for (i = 0; i < n; i++) x[i] = (double)(i & 1023);
    for (r = 0; r < 7; r++) {
        double s0 = 0, s1 = 0, s2 = 0, s3 = 0, t0 = bench_now(), t;
        for (i = 0; i + 4 <= n; i += 4) {
            s0 += x[i];
            s1 += x[i + 1];
            s2 += x[i + 2];
            s3 += x[i + 3];
        }
        t = bench_now() - t0;
        sink += s0 + s1 + s2 + s3;
        gbs[r] = (double)(n * sizeof(double)) / t * 1e-9;
        if (gbs[r] > best) best = gbs[r];
    }
    printf("streaming read of %ld MB, one core: median %.1f GB/s, best %.1f GB/s (checksum %g)\n", mb,
           bench_median(gbs, 7), best, sink);
    free(x);
    return 0;
}

int main(int argc, char **argv)
{
    int scene = BENCH_SCENE_MOLECULE, rounds = 5, reps = 5, gravity = 0, tolerance = 0, mem_report = 0, trace = 0;
    int nsizes = 0, a, r, s, k;
    int32_t sizes[MAX_SIZES];
    item items[MAX_SIZES];
    double *tmp;
    for (a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--scene") && a + 1 < argc) {
            scene = bench_scene_from_name(argv[++a]);
            if (scene < 0) return fprintf(stderr, "exact_main: unknown scene %s\n", argv[a]), 2;
        } else if (!strcmp(argv[a], "--sizes") && a + 1 < argc) {
            char *p = argv[++a];
            while (*p && nsizes < MAX_SIZES) {
                sizes[nsizes++] = (int32_t)strtol(p, &p, 10);
                if (*p == ',') p++;
            }
        } else if (!strcmp(argv[a], "--rounds") && a + 1 < argc) {
            rounds = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--reps") && a + 1 < argc) {
            reps = atoi(argv[++a]);
        } else if (!strcmp(argv[a], "--bandwidth") && a + 1 < argc) {
            return bandwidth(atol(argv[++a]));
        } else if (!strcmp(argv[a], "--gravity")) {
            gravity = 1;
        } else if (!strcmp(argv[a], "--tolerance")) {
            tolerance = 1;
        } else if (!strcmp(argv[a], "--memory")) {
            mem_report = 1;
        } else if (!strcmp(argv[a], "--trace")) {
            trace = 1;
        } else {
            fprintf(stderr, "usage: exact_main [--scene NAME] [--sizes LIST] [--rounds R] [--reps K] [--gravity] [--tolerance] [--memory] [--trace]\n");
            return 2;
        }
    }
    if (nsizes == 0) sizes[nsizes++] = 5000;
    if (rounds < 1 || reps < 1) return 2;
    tmp = (double *)malloc(sizeof(double) * (size_t)reps);
    for (s = 0; s < nsizes; s++) {
        memset(&items[s], 0, sizeof items[s]);
        items[s].size = sizes[s];
        items[s].round_ns = (double *)malloc(sizeof(double) * (size_t)rounds);
        if (setup(&items[s], scene, gravity, tolerance)) return 1;
    }
    for (r = 0; r < rounds; r++)
        for (s = 0; s < nsizes; s++) {
            item *it = &items[s];
            for (k = 0; k < reps; k++) {
                double t0;
                positions(it, scene, r * reps + k + 1);
                t0 = bench_now();
                if (bench_exact_pass(it->L, it->q, (size_t)it->nq)) return fail(it->L, "pass");
                tmp[k] = 1e9 * (bench_now() - t0);
                if (trace) printf("trace %d %d %d %.1f\n", (int)it->joints, r, k, tmp[k] / it->joints);
            }
            it->round_ns[r] = bench_median(tmp, (size_t)reps);
        }
    printf("scene %s, %d rounds x %d passes (set_positions + solve), interleaved\n",
           bench_scene_name((bench_scene_kind)scene), rounds, reps);
    printf("%10s %12s %10s %14s %8s %12s %12s\n", "joints", "ms/pass", "ns/joint", "ns/joint range", "ratio",
           "B/joint", "peak B/joint");
    {
        double base = 0.0;
        for (s = 0; s < nsizes; s++) {
            item *it = &items[s];
            aqs_memory_stats m = memory(it);
            double lo = it->round_ns[0], hi = it->round_ns[0], med;
            for (r = 0; r < rounds; r++) {
                lo = it->round_ns[r] < lo ? it->round_ns[r] : lo;
                hi = it->round_ns[r] > hi ? it->round_ns[r] : hi;
            }
            med = bench_median(it->round_ns, (size_t)rounds) / it->joints;
            if (s == 0) base = med;
            printf("%10d %12.3f %10.1f %6.0f-%-7.0f %8.2f %12.0f %12.0f\n", (int)it->joints, med * it->joints * 1e-6,
                   med, lo / it->joints, hi / it->joints, med / base, (double)m.bytes / it->joints,
                   (double)m.peak / it->joints);
        }
    }
    if (mem_report) {
        /* Subnormal accelerations after the last pass: operations on them
         * cost ~100 cycles each on x86, so they slow the pass (docs/bench.md,
         * "Scaling") */
        for (s = 0; s < nsizes; s++) {
            item *it = &items[s];
            int32_t nv = 0, i;
            long sub = 0;
            double *qdd;
            if (aqs_linkage_get_sizes(it->L, NULL, NULL, NULL, &nv) != AQS_OK) return fail(it->L, "sizes");
            qdd = (double *)malloc(sizeof(double) * (size_t)nv + 8);
            if (!qdd || aqs_linkage_get_accelerations(it->L, qdd, (size_t)nv) != AQS_OK) return fail(it->L, "accelerations");
            for (i = 0; i < nv; i++) sub += fpclassify(qdd[i]) == FP_SUBNORMAL;
            printf("%10d joints: %ld of %d accelerations subnormal after the last pass\n", (int)it->joints, sub, (int)nv);
            free(qdd);
        }
        /* B/joint held: exact (as timed), then with rel_joint 2^-19 after one
         * solve, by category (aqs_memory_stats) */
        printf("memory per joint (aqs_linkage_get_memory), exact and with rel_joint 2^-19 after one solve\n");
        printf("%10s %10s %10s %10s | %8s %8s %8s %8s %8s %8s\n", "joints", "exact", "tolerance", "peak", "model",
               "tree", "exact", "dca", "factors", "other");
        for (s = 0; s < nsizes; s++) {
            item *it = &items[s];
            aqs_memory_stats e = memory(it), m;
            const double J = it->joints;
            if (aqs_linkage_set_tolerance(it->L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)) != AQS_OK ||
                aqs_linkage_solve(it->L) != AQS_OK)
                return fail(it->L, "tolerance");
            m = memory(it);
            printf("%10d %10.0f %10.0f %10.0f | %8.0f %8.0f %8.0f %8.0f %8.0f %8.0f\n", (int)it->joints, e.bytes / J,
                   m.bytes / J, m.peak / J, m.model / J, m.tree / J, m.exact / J, m.dca / J, m.factors / J,
                   (double)(m.world + m.collision) / J);
        }
    }
    for (s = 0; s < nsizes; s++) {
        aqs_linkage_destroy(items[s].L);
        free(items[s].q0);
        free(items[s].q);
        free(items[s].round_ns);
    }
    free(tmp);
    return 0;
}
