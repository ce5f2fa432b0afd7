/*
 * adaptive_bench.c -- the error-bounded adaptive solver against the exact one
 * on the molecule scene (paper section 6.3, Table 1 and Figure 7).
 *
 * One process builds the molecule twice from the same seed: linkage E is
 * only ever stepped exactly (eps = 0; it never enables the total-acceleration
 * factors, so its steps cost what an exact user pays) and linkage A is
 * stepped adaptively (relative joint-acceleration error, AQS_METRIC_REL_JOINT).
 * Every run starts from the same initial positions (the scene as built,
 * q = 0), set with aqs_linkage_set_positions, followed by one untimed solve
 * (the full coefficient update after setting every position); then every
 * step of the run is timed.
 *
 *  (a) the exact step: median over --steps K steps with one force, giving the
 *      exact time per assembly-tree node and per joint;
 *  (b) for N_f = 1, 10, 100, 1000 forces: an exact reference run and an
 *      adaptive run at eps = 2^-19 over the same steps with the same dt,
 *      taken alternately in chunks of 10 steps (so both see the same load)
 *      (--run-steps S for N_f <= 10, S/2 for 100, S/4 for 1000, to keep the
 *      default run near 3 minutes), reporting the adaptive median time per
 *      step, the mean N_E (computed joints), nodes updated and nodes
 *      processed, the ratio R = t_adaptive / ((N_E + N_f log2 N) t_node) with
 *      t_node = t_exact / (tree nodes), the speedup t_exact / t_adaptive
 *      (t_exact: the median of the exact run of the same N_f),
 *      and the relative displacement error max_i |d_i - d_i^exact| /
 *      max_i |d_i^exact| of the bodies' centres of mass after the run. At
 *      the initial state it also compares the first adaptive solve with the
 *      exact one: the true error (it must be <= eps, else the program fails)
 *      and the fewest joints any algorithm could compute (those with
 *      |qdd_j| > eps max |qdd|);
 *  (c) an eps sweep, eps = 2^-i, i in {0, 5, 10, 15, 19}, at N_f = 1 and 100.
 *
 * Loads: gravity off; N_f distinct bodies drawn with a seeded generator (the
 * first N_f of one sequence, so the sets are nested), each pulled at its atom
 * (body origin, which is also its centre of mass) by a force of 1 N in a
 * seeded uniformly random world direction. The scene's units are consistent
 * (masses 12-33, bonds 1.5, so "amu-like kg and angstrom-like m"): the
 * quasi-static response is linear in the force, so only its direction and
 * the step size matter. dt is chosen per N_f so that the fastest joint of
 * the exact first solve turns 1e-3 rad in the first step (as exact_bench).
 *
 * Prints tables and appends one JSON line per measurement to
 * docs/bench/adaptive.jsonl (or --out PATH).
 *
 * usage: adaptive_bench [--joints N] [--steps K] [--run-steps S] [--out PATH]
 *        adaptive_bench --profile exact|adaptive [--joints N] [--steps K]
 *                       [--forces F] [--eps-log2 I]
 * --profile takes one run of K steps on one linkage, for a profiler, e.g.
 *   valgrind --tool=callgrind --toggle-collect=aqs_linkage_step \
 *       build/bench/adaptive_bench --profile adaptive --joints 5000 --steps 20
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

#define FORCE_SEED UINT64_C(0xada971fe)
#define FORCE_MAGNITUDE 1.0 /* N, per force */
#define FIRST_STEP_MOVE 1e-3 /* rad: the fastest joint's move in the first step */
#define MAX_FORCES 1000
#define TABLE_EPS_LOG2 19
#define RUN_CHUNK 10 /* exact and adaptive steps alternate in chunks of this many */

static const int32_t force_counts[] = {1, 10, 100, 1000};
#define NCOUNTS ((int)(sizeof force_counts / sizeof force_counts[0]))
static const int sweep_log2[] = {0, 5, 10, 15, 19};
#define NSWEEP ((int)(sizeof sweep_log2 / sizeof sweep_log2[0]))
static const int32_t sweep_counts[] = {1, 100};
#define NSWEEPCOUNTS ((int)(sizeof sweep_counts / sizeof sweep_counts[0]))

typedef struct options {
    int32_t joints;
    int32_t steps;     /* exact timing steps of (a) */
    int32_t run_steps; /* steps per run of (b), (c); half of it for 1,000 forces */
    const char *out;
    int profile;         /* 0: the benchmark; 1: exact only; 2: adaptive only */
    int32_t forces;      /* N_f of a profile run */
    int eps_log2;        /* eps = 2^-eps_log2 of an adaptive profile run */
} options;

/* Everything the benchmark shares between its runs. */
typedef struct bench {
    aqs_linkage *exact, *adapt;
    int32_t bodies, joints, nq, nv;
    int32_t tree_nodes, tree_height, max_handles;
    double mean_handles;
    double *q0;       /* initial positions (nq) */
    double *poses0;   /* initial world poses (7 bodies) */
    double *poses;    /* scratch world poses (7 bodies) */
    double *disp_ref; /* exact displacements of the current N_f (3 bodies) */
    double *qdd;      /* scratch (nv) */
    double *qdd_ref;  /* exact accelerations at the initial state, current N_f (nv) */
    double qdd_ref_max; /* max |qdd_ref| */
    double *times;    /* scratch (max steps) */
    double *times2;   /* scratch (max steps) */
    int32_t force_body[MAX_FORCES];
    double force_dir[MAX_FORCES][3];
    FILE *json;
    char stamp[32];
} bench;

/* One run of steps. */
typedef struct run_result {
    int32_t steps;
    double median_s, mean_s;
    double mean_ne, mean_nu, mean_np; /* computed joints, nodes updated, processed */
    int32_t max_ne;
    double max_bound; /* largest certified error bound over the steps */
    double disp_err;  /* relative displacement error (adaptive runs) */
    int32_t first_ne; /* N_E of the first solve (at the initial state) */
    int32_t oracle_ne; /* joints with |qdd_exact| > eps max |qdd_exact| there: the
                          fewest any algorithm may compute */
    double first_err; /* the measure's true value for the first solve */
    double max_disp;  /* max_i |d_i| of this run */
} run_result;

static int failed(aqs_status status, const aqs_linkage *linkage, const char *what)
{
    if (status == AQS_OK) {
        return 0;
    }
    fprintf(stderr, "adaptive_bench: %s failed: %s (%d): %s\n", what, aqs_status_string(status),
            (int)status, aqs_linkage_last_error(linkage));
    return 1;
}

static double log2_of(double x)
{
    return log(x) / log(2.0);
}

/* The first MAX_FORCES distinct bodies of one seeded sequence and a uniform
 * random direction for each. */
static int draw_forces(bench *b)
{
    bench_rng rng;
    unsigned char *used = (unsigned char *)calloc((size_t)b->bodies, 1);
    int32_t k = 0;
    if (used == NULL) {
        return 1;
    }
    bench_rng_seed(&rng, FORCE_SEED);
    while (k < MAX_FORCES && k < b->bodies) {
        const int32_t body = (int32_t)bench_rng_below(&rng, (uint64_t)b->bodies);
        if (used[body]) {
            continue;
        }
        used[body] = 1;
        b->force_body[k] = body;
        bench_rng_unit_vector(&rng, b->force_dir[k]);
        ++k;
    }
    free(used);
    return 0;
}

/* Initial positions, the first nf forces, no gravity, and a solve so that the
 * full coefficient update after setting the positions is not timed. */
static int reset(bench *b, aqs_linkage *L, int32_t nf)
{
    const double zero[3] = {0.0, 0.0, 0.0};
    int32_t k;
    if (failed(aqs_linkage_clear_forces(L), L, "aqs_linkage_clear_forces") ||
        failed(aqs_linkage_set_gravity(L, zero), L, "aqs_linkage_set_gravity") ||
        failed(aqs_linkage_set_positions(L, b->q0, (size_t)b->nq), L,
               "aqs_linkage_set_positions")) {
        return 1;
    }
    for (k = 0; k < nf; ++k) {
        double f[3];
        int i;
        for (i = 0; i < 3; ++i) {
            f[i] = FORCE_MAGNITUDE * b->force_dir[k][i];
        }
        if (failed(aqs_body_set_force(L, b->force_body[k], f, NULL, NULL), L,
                   "aqs_body_set_force")) {
            return 1;
        }
    }
    return failed(aqs_linkage_solve(L), L, "aqs_linkage_solve");
}

/* dt for nf forces: the fastest joint of the exact solve at the initial
 * positions turns FIRST_STEP_MOVE in the first step. */
static int choose_dt(bench *b, int32_t nf, double *dt)
{
    double max_abs = 0.0;
    int32_t i;
    if (reset(b, b->exact, nf) != 0 ||
        failed(aqs_linkage_get_accelerations(b->exact, b->qdd_ref, (size_t)b->nv), b->exact,
               "aqs_linkage_get_accelerations")) {
        return 1;
    }
    for (i = 0; i < b->nv; ++i) {
        max_abs = fabs(b->qdd_ref[i]) > max_abs ? fabs(b->qdd_ref[i]) : max_abs;
    }
    b->qdd_ref_max = max_abs;
    if (!(max_abs > 0.0) || !isfinite(max_abs)) {
        fprintf(stderr, "adaptive_bench: the forces produce no finite acceleration\n");
        return 1;
    }
    *dt = sqrt(FIRST_STEP_MOVE / max_abs);
    return 0;
}

/* Per-step times and solver statistics of one run, gathered over chunks. */
typedef struct run_acc {
    double *times;
    int32_t n;
    double sum_t, sum_ne, sum_nu, sum_np, max_bound;
    int32_t max_ne;
} run_acc;

/* Take k timed steps of L and add them to a. */
static int step_acc(aqs_linkage *L, double dt, int32_t k, run_acc *a)
{
    int32_t s;
    for (s = 0; s < k; ++s) {
        aqs_solve_stats st;
        const double t0 = bench_now();
        double t;
        if (failed(aqs_linkage_step(L, dt), L, "aqs_linkage_step")) {
            return 1;
        }
        t = bench_now() - t0;
        a->times[a->n++] = t;
        a->sum_t += t;
        st.size = (uint32_t)sizeof st;
        if (failed(aqs_linkage_get_stats(L, &st), L, "aqs_linkage_get_stats")) {
            return 1;
        }
        a->sum_ne += st.computed_joints;
        a->sum_nu += st.nodes_updated;
        a->sum_np += st.nodes_processed;
        a->max_ne = st.computed_joints > a->max_ne ? st.computed_joints : a->max_ne;
        a->max_bound = st.error_bound > a->max_bound ? st.error_bound : a->max_bound;
    }
    return 0;
}

static void acc_finish(run_acc *a, run_result *r)
{
    memset(r, 0, sizeof *r);
    r->steps = a->n;
    r->mean_s = a->sum_t / a->n;
    r->median_s = bench_median(a->times, (size_t)a->n);
    r->mean_ne = a->sum_ne / a->n;
    r->mean_nu = a->sum_nu / a->n;
    r->mean_np = a->sum_np / a->n;
    r->max_ne = a->max_ne;
    r->max_bound = a->max_bound;
}

/* Time nsteps steps of L (already reset) and gather the solver statistics. */
static int run_steps(bench *b, aqs_linkage *L, double dt, int32_t nsteps, run_result *r)
{
    run_acc a;
    memset(&a, 0, sizeof a);
    a.times = b->times;
    if (step_acc(L, dt, nsteps, &a) != 0) {
        return 1;
    }
    acc_finish(&a, r);
    return 0;
}

/* Displacements of the bodies' centres of mass since the initial positions.
 * In the molecule every centre of mass is at its body origin (the atom), so
 * the displacement of the body origin is that of the centre of mass. With
 * ref = 1 they are stored as the reference; otherwise the relative error
 * against the reference is returned in r->disp_err. */
static int displacement(bench *b, aqs_linkage *L, int ref, double ref_max, run_result *r)
{
    double max_d = 0.0, max_err = 0.0;
    int32_t i;
    if (failed(aqs_linkage_get_body_poses_world(L, b->poses, 7 * (size_t)b->bodies), L,
               "aqs_linkage_get_body_poses_world")) {
        return 1;
    }
    for (i = 0; i < b->bodies; ++i) {
        double d2 = 0.0, e2 = 0.0;
        int k;
        for (k = 0; k < 3; ++k) {
            const double d = b->poses[7 * (size_t)i + k] - b->poses0[7 * (size_t)i + k];
            d2 += d * d;
            if (ref) {
                b->disp_ref[3 * (size_t)i + k] = d;
            } else {
                const double e = d - b->disp_ref[3 * (size_t)i + k];
                e2 += e * e;
            }
        }
        max_d = d2 > max_d ? d2 : max_d;
        max_err = e2 > max_err ? e2 : max_err;
    }
    r->max_disp = sqrt(max_d);
    r->disp_err = ref ? 0.0 : (ref_max > 0.0 ? sqrt(max_err) / ref_max : 0.0);
    return 0;
}

static long peak_rss_bytes(void)
{
    const long kb = bench_peak_rss_kb();
    return kb < 0 ? -1 : 1024 * kb;
}

static void json_line(bench *b, int32_t nf, double eps, int eps_log2, double dt,
                      const run_result *r, double exact_s, int exact_only)
{
    const double n_u = (double)nf;
    const double denom = r->mean_ne + n_u * log2_of((double)b->joints);
    const double t_node = exact_s / b->tree_nodes;
    const double ratio = exact_only ? 0.0 : r->median_s / (denom * t_node);
    const double t_internal = exact_s / ((b->tree_nodes - 1) / 2.0);
    const double ratio_int = exact_only ? 0.0 : r->median_s / (denom * t_internal);
    if (b->json == NULL) {
        return;
    }
    fprintf(b->json,
            "{\"bench\": \"adaptive\", \"time\": \"%s\", \"version\": \"%s\", "
            "\"scene\": \"molecule\", \"joints\": %d, \"tree_nodes\": %d, \"tree_height\": %d, "
            "\"forces\": %d, \"force_magnitude_n\": %.1f, \"metric\": \"rel_joint\", "
            "\"eps\": %.9g, \"eps_log2\": %d, \"dt\": %.6e, \"steps\": %d, "
            "\"ms_per_step\": %.6f, \"mean_ms_per_step\": %.6f, \"exact_ms_per_step\": %.6f, "
            "\"exact_us_per_node\": %.6f, \"speedup\": %.3f, "
            "\"computed_joints\": %.2f, \"max_computed_joints\": %d, \"nodes_updated\": %.2f, "
            "\"nodes_processed\": %.2f, \"max_error_bound\": %.6e, \"ratio_R\": %.4f, "
            "\"ratio_R_internal_nodes\": %.4f, \"displacement_error\": %.6e, "
            "\"max_displacement\": %.6e, \"first_computed_joints\": %d, "
            "\"first_min_computed_joints\": %d, \"first_true_error\": %.6e, "
            "\"peak_rss_bytes\": %ld}\n",
            b->stamp, aqs_version_string(), (int)b->joints, (int)b->tree_nodes,
            (int)b->tree_height, (int)nf, FORCE_MAGNITUDE, eps, eps_log2, dt, (int)r->steps,
            1e3 * r->median_s, 1e3 * r->mean_s, 1e3 * exact_s, 1e6 * t_node,
            exact_only ? 1.0 : exact_s / r->median_s, r->mean_ne, (int)r->max_ne, r->mean_nu,
            r->mean_np, r->max_bound, ratio, ratio_int, r->disp_err, r->max_disp,
            (int)r->first_ne, (int)r->oracle_ne, r->first_err, peak_rss_bytes());
    fflush(b->json);
}

static int steps_for(const options *opt, int32_t nf)
{
    const int32_t s = nf >= 1000 ? opt->run_steps / 4
                      : nf >= 100 ? opt->run_steps / 2
                                  : opt->run_steps;
    return s < 1 ? 1 : s;
}

/* One table row of (b) or (c): the adaptive run at eps for nf forces from
 * the initial state. With ref non-NULL the exact reference run (same steps,
 * same dt) is taken at the same time, in chunks of RUN_CHUNK steps that
 * alternate between the two linkages so that both medians see the same
 * machine load; its displacements become the reference and *exact_s,
 * *ref_max are set. With ref NULL the reference of an earlier call is used. */
static int adaptive_run(bench *b, const options *opt, int32_t nf, int eps_log2, double dt,
                        run_result *ref, double *exact_s, double *ref_max, run_result *r)
{
    const double eps = ldexp(1.0, -eps_log2);
    const int32_t nsteps = steps_for(opt, nf);
    aqs_solve_stats st;
    run_acc aa, ae;
    double err = 0.0;
    int32_t oracle = 0, i, done = 0;
    st.size = (uint32_t)sizeof st;
    if (failed(aqs_linkage_set_tolerance(b->adapt, AQS_METRIC_REL_JOINT, eps), b->adapt,
               "aqs_linkage_set_tolerance") ||
        reset(b, b->adapt, nf) != 0 ||
        failed(aqs_linkage_get_stats(b->adapt, &st), b->adapt, "aqs_linkage_get_stats") ||
        failed(aqs_linkage_get_accelerations(b->adapt, b->qdd, (size_t)b->nv), b->adapt,
               "aqs_linkage_get_accelerations")) {
        return 1;
    }
    /* The first solve against the exact one at the same state: the true
     * relative joint error, and how many joints any algorithm must compute
     * (every revolute joint is one value of qdd). */
    for (i = 0; i < b->nv; ++i) {
        const double e = fabs(b->qdd[i] - b->qdd_ref[i]);
        err = e > err ? e : err;
        oracle += fabs(b->qdd_ref[i]) > eps * b->qdd_ref_max;
    }
    memset(&aa, 0, sizeof aa);
    memset(&ae, 0, sizeof ae);
    aa.times = b->times;
    ae.times = b->times2;
    if (ref != NULL && reset(b, b->exact, nf) != 0) {
        return 1;
    }
    while (done < nsteps) {
        const int32_t k = nsteps - done < RUN_CHUNK ? nsteps - done : RUN_CHUNK;
        if ((ref != NULL && step_acc(b->exact, dt, k, &ae) != 0) ||
            step_acc(b->adapt, dt, k, &aa) != 0) {
            return 1;
        }
        done += k;
    }
    if (ref != NULL) {
        acc_finish(&ae, ref);
        if (displacement(b, b->exact, 1, 0.0, ref) != 0) {
            return 1;
        }
        *exact_s = ref->median_s;
        *ref_max = ref->max_disp;
    }
    acc_finish(&aa, r);
    if (displacement(b, b->adapt, 0, *ref_max, r) != 0) {
        return 1;
    }
    r->first_ne = st.computed_joints;
    r->oracle_ne = oracle;
    r->first_err = err / b->qdd_ref_max;
    if (r->first_err > eps) {
        fprintf(stderr,
                "adaptive_bench: N_f = %d, eps = 2^-%d: the first solve's true error %.3e "
                "exceeds eps (certified bound %.3e)\n",
                (int)nf, eps_log2, r->first_err, st.error_bound);
        return 1;
    }
    json_line(b, nf, eps, eps_log2, dt, r, *exact_s, 0);
    return 0;
}

static void print_row(const bench *b, int32_t nf, int eps_log2, const run_result *r,
                      double exact_s)
{
    const double denom = r->mean_ne + nf * log2_of((double)b->joints);
    printf("%6d  2^-%-3d %6d %9.3f %9.3f %9.1f %9.1f %9.1f %6.2f %8.1f %9.2e %9.2e %7d "
           "%7d %9.2e\n",
           (int)nf, eps_log2, (int)r->steps, 1e3 * r->median_s, 1e3 * exact_s, r->mean_ne,
           r->mean_nu, r->mean_np, r->median_s / (denom * exact_s / b->tree_nodes),
           exact_s / r->median_s, r->disp_err, r->max_bound, (int)r->first_ne,
           (int)r->oracle_ne, r->first_err);
    fflush(stdout);
}

static void print_header(void)
{
    printf("%6s  %-6s %6s %9s %9s %9s %9s %9s %6s %8s %9s %9s %7s %7s %9s\n", "N_f", "eps",
           "steps", "ms/step", "exact ms", "N_E", "updated", "processed", "R", "speedup",
           "disp err", "max bound", "N_E(1)", "min(1)", "err(1)");
}

static int parse_options(int argc, char **argv, options *opt)
{
    int i;
    opt->joints = 50000;
    opt->steps = 30;
    opt->run_steps = 200;
    opt->out = "docs/bench/adaptive.jsonl";
    opt->profile = 0;
    opt->forces = 1;
    opt->eps_log2 = TABLE_EPS_LOG2;
    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--joints") == 0 && i + 1 < argc) {
            opt->joints = (int32_t)atol(argv[++i]);
        } else if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
            opt->steps = (int32_t)atol(argv[++i]);
        } else if (strcmp(argv[i], "--run-steps") == 0 && i + 1 < argc) {
            opt->run_steps = (int32_t)atol(argv[++i]);
        } else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
            opt->out = argv[++i];
        } else if (strcmp(argv[i], "--profile") == 0 && i + 1 < argc &&
                   (strcmp(argv[i + 1], "exact") == 0 || strcmp(argv[i + 1], "adaptive") == 0)) {
            opt->profile = strcmp(argv[++i], "exact") == 0 ? 1 : 2;
        } else if (strcmp(argv[i], "--forces") == 0 && i + 1 < argc) {
            opt->forces = (int32_t)atol(argv[++i]);
        } else if (strcmp(argv[i], "--eps-log2") == 0 && i + 1 < argc) {
            opt->eps_log2 = atoi(argv[++i]);
        } else {
            fprintf(stderr,
                    "usage: %s [--joints N] [--steps K] [--run-steps S] [--out PATH]\n"
                    "       %s --profile exact|adaptive [--joints N] [--steps K] [--forces F]\n"
                    "          [--eps-log2 I]\n"
                    "  --joints N     molecule size (default 50000)\n"
                    "  --steps K      exact steps timed for the time per node (default 30); with\n"
                    "                 --profile, the steps of the one run\n"
                    "  --run-steps S  steps of each exact/adaptive run for N_f <= 10 (default\n"
                    "                 200; S/2 for 100 forces, S/4 for 1,000)\n"
                    "  --out PATH     JSON lines appended here (default "
                    "docs/bench/adaptive.jsonl; '-' for none)\n"
                    "  --profile M    one linkage, one run of K steps, exact or adaptive\n"
                    "                 (eps = 2^-I, default I = 19), F forces (default 1), for\n"
                    "                 a profiler: valgrind --tool=callgrind\n"
                    "                 --toggle-collect=aqs_linkage_step\n",
                    argv[0], argv[0]);
            return 1;
        }
    }
    if (opt->forces < 1 || opt->forces > MAX_FORCES || opt->eps_log2 < 0 ||
        opt->eps_log2 > 60) {
        fprintf(stderr, "adaptive_bench: --forces must be in 1..%d, --eps-log2 in 0..60\n",
                MAX_FORCES);
        return 1;
    }
    if (opt->joints < 2 * MAX_FORCES || opt->steps < 1 || opt->run_steps < 1) {
        fprintf(stderr, "adaptive_bench: --joints must be >= %d, --steps and --run-steps >= 1\n",
                2 * MAX_FORCES);
        return 1;
    }
    return 0;
}

static int setup(bench *b, const options *opt)
{
    aqs_linkage **ls[2];
    double t0;
    int i;
    ls[0] = &b->exact;
    ls[1] = &b->adapt;
    for (i = 0; i < (opt->profile ? 1 : 2); ++i) {
        aqs_status st = aqs_linkage_create(ls[i]);
        if (st != AQS_OK) {
            fprintf(stderr, "adaptive_bench: aqs_linkage_create failed: %s\n",
                    aqs_status_string(st));
            return 1;
        }
        t0 = bench_now();
        if (failed(bench_build_molecule(*ls[i], opt->joints, BENCH_MOLECULE_SEED), *ls[i],
                   "bench_build_molecule") ||
            failed(aqs_linkage_finalize(*ls[i]), *ls[i], "aqs_linkage_finalize")) {
            return 1;
        }
        if (i == 0) {
            printf("molecule: %d joints, built and finalized in %.3f s\n", (int)opt->joints,
                   bench_now() - t0);
        }
    }
    if (failed(aqs_linkage_get_sizes(b->exact, &b->bodies, &b->joints, &b->nq, &b->nv), b->exact,
               "aqs_linkage_get_sizes") ||
        failed(aqs_linkage_get_tree_stats(b->exact, &b->tree_nodes, &b->tree_height,
                                          &b->mean_handles, &b->max_handles),
               b->exact, "aqs_linkage_get_tree_stats")) {
        return 1;
    }
    b->q0 = (double *)malloc(sizeof(double) * (size_t)b->nq);
    b->poses0 = (double *)malloc(sizeof(double) * 7 * (size_t)b->bodies);
    b->poses = (double *)malloc(sizeof(double) * 7 * (size_t)b->bodies);
    b->disp_ref = (double *)malloc(sizeof(double) * 3 * (size_t)b->bodies);
    b->qdd = (double *)malloc(sizeof(double) * (size_t)b->nv);
    b->qdd_ref = (double *)malloc(sizeof(double) * (size_t)b->nv);
    {
        const size_t most = (size_t)(opt->steps > opt->run_steps ? opt->steps : opt->run_steps);
        b->times = (double *)malloc(sizeof(double) * most);
        b->times2 = (double *)malloc(sizeof(double) * most);
    }
    if (b->q0 == NULL || b->poses0 == NULL || b->poses == NULL || b->disp_ref == NULL ||
        b->qdd == NULL || b->qdd_ref == NULL || b->times == NULL || b->times2 == NULL ||
        draw_forces(b) != 0) {
        fprintf(stderr, "adaptive_bench: out of memory\n");
        return 1;
    }
    if (failed(aqs_linkage_get_positions(b->exact, b->q0, (size_t)b->nq), b->exact,
               "aqs_linkage_get_positions") ||
        failed(aqs_linkage_get_body_poses_world(b->exact, b->poses0, 7 * (size_t)b->bodies),
               b->exact, "aqs_linkage_get_body_poses_world")) {
        return 1;
    }
    if (b->nv != b->joints) {
        fprintf(stderr, "adaptive_bench: expected one acceleration per joint\n");
        return 1;
    }
    printf("assembly tree: %d nodes (%d internal), height %d (log2 N = %.1f), handles mean "
           "%.2f max %d\n",
           (int)b->tree_nodes, (int)((b->tree_nodes - 1) / 2), (int)b->tree_height,
           log2_of((double)b->joints), b->mean_handles, (int)b->max_handles);
    return 0;
}

/* --profile: one linkage, one run, nothing written. */
static int profile_run(bench *b, const options *opt)
{
    run_result r;
    double dt;
    if (choose_dt(b, opt->forces, &dt) != 0) {
        return 1;
    }
    if (opt->profile == 2 &&
        failed(aqs_linkage_set_tolerance(b->exact, AQS_METRIC_REL_JOINT,
                                         ldexp(1.0, -opt->eps_log2)),
               b->exact, "aqs_linkage_set_tolerance")) {
        return 1;
    }
    if (reset(b, b->exact, opt->forces) != 0 ||
        run_steps(b, b->exact, dt, opt->steps, &r) != 0) {
        return 1;
    }
    printf("profile: %s, %d forces, %d steps: median %.3f ms/step; mean N_E %.1f, nodes "
           "updated %.1f, processed %.1f\n",
           opt->profile == 1 ? "exact" : "adaptive", (int)opt->forces, (int)r.steps,
           1e3 * r.median_s, r.mean_ne, r.mean_nu, r.mean_np);
    return 0;
}

/* N_E of the first solve at the initial state for one linkage, tolerance
 * and joint bound. */
static int first_ne(bench *b, aqs_linkage *L, int32_t nf, int eps_log2, int32_t bound,
                    int32_t *ne)
{
    aqs_solve_stats st;
    st.size = sizeof st;
    if (reset(b, L, nf) != 0 ||
        failed(aqs_linkage_set_joint_bound(L, bound), L, "aqs_linkage_set_joint_bound") ||
        failed(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -eps_log2)), L,
               "aqs_linkage_set_tolerance") ||
        failed(aqs_linkage_solve(L), L, "aqs_linkage_solve") ||
        failed(aqs_linkage_get_stats(L, &st), L, "aqs_linkage_get_stats")) {
        return 1;
    }
    *ne = st.computed_joints;
    return failed(aqs_linkage_set_joint_bound(L, AQS_JOINT_BOUND_HEAP_TOP), L,
                  "aqs_linkage_set_joint_bound");
}

/* (d) What the heap-top bound and the tree's shape do to N_E: the first
 * solve's N_E with the paper's sqrt(sum) bound and with the heap top, on the
 * contraction tree and on a recursive-bisection tree of the same molecule. */
static int shape_and_bound(bench *b, const options *opt)
{
    static const int eps_list[] = {10, 19};
    aqs_linkage *bis = NULL;
    int32_t nodes, height, maxh, c, e;
    double meanh;
    int rc = 1;
    if (failed(aqs_linkage_create(&bis), NULL, "aqs_linkage_create") ||
        failed(aqs_linkage_set_tree_builder(bis, AQS_TREE_BISECTION), bis,
               "aqs_linkage_set_tree_builder") ||
        failed(bench_build_molecule(bis, opt->joints, BENCH_MOLECULE_SEED), bis,
               "bench_build_molecule") ||
        failed(aqs_linkage_finalize(bis), bis, "aqs_linkage_finalize") ||
        failed(aqs_linkage_get_tree_stats(bis, &nodes, &height, &meanh, &maxh), bis,
               "aqs_linkage_get_tree_stats")) {
        goto out;
    }
    printf("\n(d) N_E of the first solve (rel. joint error): joint bound and tree shape\n"
           "contraction tree: height %d, handles mean %.2f max %d; bisection tree: height %d, "
           "handles mean %.2f max %d\n",
           (int)b->tree_height, b->mean_handles, (int)b->max_handles, (int)height, meanh,
           (int)maxh);
    printf("%6s %6s %14s %14s %16s\n", "N_f", "eps", "contr. heap", "contr. sum", "bisect. heap");
    for (c = 0; c < 3; ++c) {
        const int32_t nf = force_counts[c];
        for (e = 0; e < 2; ++e) {
            int32_t ne_top, ne_sum, ne_bis;
            if (first_ne(b, b->adapt, nf, eps_list[e], AQS_JOINT_BOUND_HEAP_TOP, &ne_top) ||
                first_ne(b, b->adapt, nf, eps_list[e], AQS_JOINT_BOUND_SUM, &ne_sum) ||
                first_ne(b, bis, nf, eps_list[e], AQS_JOINT_BOUND_HEAP_TOP, &ne_bis)) {
                goto out;
            }
            printf("%6d %3s-%-2d %14d %14d %16d\n", (int)nf, "2^", eps_list[e], (int)ne_top,
                   (int)ne_sum, (int)ne_bis);
            if (b->json != NULL) {
                fprintf(b->json,
                        "{\"scene\":\"molecule\",\"joints\":%d,\"forces\":%d,\"metric\":"
                        "\"rel_joint\",\"eps\":%.17g,\"first_solve_computed_joints\":{"
                        "\"contraction_heap_top\":%d,\"contraction_sum\":%d,"
                        "\"bisection_heap_top\":%d},\"date\":\"%s\"}\n",
                        (int)b->joints, (int)nf, ldexp(1.0, -eps_list[e]), (int)ne_top,
                        (int)ne_sum, (int)ne_bis, b->stamp);
            }
        }
    }
    rc = 0;
out:
    aqs_linkage_destroy(bis);
    return rc;
}

int main(int argc, char **argv)
{
    options opt;
    bench b;
    run_result ex, ref[NCOUNTS], ad[NCOUNTS], sw[NSWEEPCOUNTS][NSWEEP];
    double dts[NCOUNTS], exact_s[NCOUNTS], ref_max[NCOUNTS];
    double t_start = bench_now();
    int rc = 1, c, i;

    if (parse_options(argc, argv, &opt) != 0) {
        return 2;
    }
    if (aqs_version() != AQS_VERSION_NUMBER) {
        fprintf(stderr, "adaptive_bench: header version %d but library version %d\n",
                (int)AQS_VERSION_NUMBER, (int)aqs_version());
        return 1;
    }
    memset(&b, 0, sizeof b);
    memset(sw, 0, sizeof sw);
    bench_utc_stamp(b.stamp, sizeof b.stamp);
    printf("aqs %s adaptive solver benchmark (molecule, relative joint-acceleration error), "
           "%s\n",
           aqs_version_string(), b.stamp);
    printf("loads: gravity off; N_f distinct seeded random bodies, each pulled at its atom "
           "(= centre of mass) by %.0f N in a random world direction; dt: the fastest joint "
           "turns %.0e rad in the first exact step\n",
           FORCE_MAGNITUDE, FIRST_STEP_MOVE);
    if (!opt.profile) {
        printf("two linkages from the same seed: one stepped exactly only, one adaptively; "
               "each run starts at the built positions; medians of per-step times\n");
    }
    printf("\n");
    if (setup(&b, &opt) != 0) {
        goto done;
    }
    if (opt.profile) {
        rc = profile_run(&b, &opt);
        goto done;
    }
    if (strcmp(opt.out, "-") != 0) {
        b.json = fopen(opt.out, "a");
        if (b.json == NULL) {
            fprintf(stderr, "adaptive_bench: cannot open %s: %s\n", opt.out, strerror(errno));
            goto done;
        }
    }

    /* (a) the exact step, one force. */
    {
        double dt;
        if (choose_dt(&b, 1, &dt) != 0 || reset(&b, b.exact, 1) != 0 ||
            run_steps(&b, b.exact, dt, opt.steps, &ex) != 0) {
            goto done;
        }
        printf("\n(a) exact step, 1 force, %d steps: median %.3f ms (mean %.3f ms) = %.4f us "
               "per joint = %.4f us per tree node (%.4f us per internal node); %d nodes "
               "updated per step\n",
               (int)ex.steps, 1e3 * ex.median_s, 1e3 * ex.mean_s, 1e6 * ex.median_s / b.joints,
               1e6 * ex.median_s / b.tree_nodes, 1e6 * ex.median_s / ((b.tree_nodes - 1) / 2.0),
               (int)ex.mean_nu);
        json_line(&b, 1, 0.0, -1, dt, &ex, ex.median_s, 1);
    }

    /* (b) adaptive at 2^-19 against exact, N_f = 1 .. 1000; (c) the sweep. */
    printf("\n(b) eps = 2^-%d; (c) sweep at N_f = 1 and 100. Each N_f: the exact run ('exact ms') "
           "and the 2^-%d run alternate in chunks of %d steps; same steps and dt for all runs "
           "of an N_f.\n"
           "R = t / ((N_E + N_f log2 N) t_node), t_node = exact ms / %d tree nodes; disp err = "
           "max_i |d_i - d_i^exact| / max_i |d_i^exact| after the run;\n"
           "N_E(1), min(1), err(1): at the initial state, the joints computed, the joints with "
           "|qdd| > eps max|qdd| (the fewest possible), the true error\n",
           TABLE_EPS_LOG2, TABLE_EPS_LOG2, RUN_CHUNK, (int)b.tree_nodes);
    print_header();
    for (c = 0; c < NCOUNTS; ++c) {
        const int32_t nf = force_counts[c];
        if (choose_dt(&b, nf, &dts[c]) != 0 ||
            adaptive_run(&b, &opt, nf, TABLE_EPS_LOG2, dts[c], &ref[c], &exact_s[c],
                         &ref_max[c], &ad[c]) != 0) {
            goto done;
        }
        print_row(&b, nf, TABLE_EPS_LOG2, &ad[c], exact_s[c]);
        for (i = 0; i < NSWEEPCOUNTS; ++i) {
            int k;
            if (sweep_counts[i] != nf) {
                continue;
            }
            for (k = 0; k < NSWEEP; ++k) {
                if (sweep_log2[k] == TABLE_EPS_LOG2) {
                    sw[i][k] = ad[c];
                    continue;
                }
                if (adaptive_run(&b, &opt, nf, sweep_log2[k], dts[c], NULL, &exact_s[c],
                                 &ref_max[c], &sw[i][k]) != 0) {
                    goto done;
                }
                print_row(&b, nf, sweep_log2[k], &sw[i][k], exact_s[c]);
            }
        }
    }

    if (shape_and_bound(&b, &opt) != 0) {
        goto done;
    }

    printf("\nsummary at eps = 2^-%d (target R <= 3):\n", TABLE_EPS_LOG2);
    printf("%6s %6s %10s %10s %9s %9s %9s %9s %7s %10s\n", "N_f", "steps", "ms/step",
           "exact ms", "speedup", "N_E", "updated", "processed", "R", "disp err");
    for (c = 0; c < NCOUNTS; ++c) {
        const double denom = ad[c].mean_ne + force_counts[c] * log2_of((double)b.joints);
        printf("%6d %6d %10.3f %10.3f %9.1f %9.1f %9.1f %9.1f %7.2f %10.2e\n",
               (int)force_counts[c], (int)ad[c].steps, 1e3 * ad[c].median_s, 1e3 * exact_s[c],
               exact_s[c] / ad[c].median_s, ad[c].mean_ne, ad[c].mean_nu, ad[c].mean_np,
               ad[c].median_s / (denom * exact_s[c] / b.tree_nodes), ad[c].disp_err);
    }
    printf("\nsweep (eps = 2^-i): N_E and ms/step\n%6s", "N_f");
    for (i = 0; i < NSWEEP; ++i) {
        printf("   i=%-2d N_E   ms  ", sweep_log2[i]);
    }
    printf("\n");
    for (c = 0; c < NSWEEPCOUNTS; ++c) {
        printf("%6d", (int)sweep_counts[c]);
        for (i = 0; i < NSWEEP; ++i) {
            printf(" %9.1f %7.3f", sw[c][i].mean_ne, 1e3 * sw[c][i].median_s);
        }
        printf("\n");
    }
    printf("\npeak RSS %.1f MB (both linkages); total %.1f s; %s%s\n",
           peak_rss_bytes() / 1048576.0, bench_now() - t_start,
           b.json != NULL ? "results appended to " : "no JSON written",
           b.json != NULL ? opt.out : "");
    rc = 0;
done:
    if (b.json != NULL && fclose(b.json) != 0) {
        rc = 1;
    }
    aqs_linkage_destroy(b.exact);
    aqs_linkage_destroy(b.adapt);
    free(b.q0);
    free(b.poses0);
    free(b.poses);
    free(b.disp_ref);
    free(b.qdd);
    free(b.qdd_ref);
    free(b.times);
    free(b.times2);
    return rc;
}
