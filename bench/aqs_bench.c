/*
 * aqs_bench.c -- aqs-bench: the adaptive solver against the exact one on the
 * paper's scenes, for given forces, error measure, eps list and steps.
 *
 * One process builds the scene twice: linkage E is only ever stepped exactly
 * (so its steps cost what an exact user pays) and linkage A is stepped with
 * the tolerance of each configuration. For each N_f:
 *  - dt: the fastest joint of E's exact solve at the initial state moves
 *    --first-move (1e-3) in the first step;
 *  - the exact reference run: E takes K steps from the initial state; the
 *    displacements of the bodies' centres of mass are the reference;
 *  - for each eps: A takes K steps from the same initial state; after every
 *    chunk of C adaptive steps (--exact-every, at least 3 chunks) E takes one
 *    timed exact step by each exact solver (the articulated-body algorithm,
 *    the default, then the DCA after an untimed solve that brings its tree
 *    up to date), so all medians see the same machine load. Repeated
 *    --repeats times; ms_per_step, exact_ms_per_step (articulated-body) and
 *    exact_dca_ms_per_step are medians over the repeats of each repeat's
 *    median step time. speedup is against the articulated-body step, R (per
 *    tree node) against the DCA step.
 * displacement_error = max_i |d_i - d_i^exact| / max_i |d_i^exact| over the
 * bodies' centres of mass after K steps (DESIGN.md); 0 for eps = 0. The
 * paper's "average relative displacement error per time step" is read two
 * ways as well (docs/bench.md): displacement_error_per_step = that / K, and
 * displacement_error_mean = the mean over the steps k of the same relative
 * error after k steps (over displacement_checkpoints evenly spaced steps,
 * every step unless the reference positions would take more than 256 MB).
 *
 * Loads (seeded by --seed): gravity off; N_f distinct bodies, the first N_f
 * of one seeded sequence (so the sets are nested), each pulled at its centre
 * of mass by 1 N in a seeded uniform random world direction. chain30: force
 * 0 is the constant (0, 1, 0) N at the far end of the last link (paper
 * Figure 1); millipede: the bodies are drawn from the legs only (DESIGN.md:
 * "a single force on one leg").
 *
 * Usage: aqs-bench --help. Options are parsed by a table (options[] below):
 * one row per option, so new options are one row and one case each.
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"
#include "urdf.h"

#define BENCH_MAX_LIST 64
#define BENCH_FORCE_N 1.0 /* N, per force */

typedef struct bench_options {
    int scene;
    int32_t size;
    int32_t forces[BENCH_MAX_LIST];
    int nforces;
    int32_t metric;  /* the one in force (the current item of metrics) */
    int32_t metrics[BENCH_MAX_LIST];
    int nmetrics;
    double eps[BENCH_MAX_LIST];
    int eps_log2[BENCH_MAX_LIST]; /* -1: not a power of two */
    int neps;
    int32_t steps, repeats, exact_every, tip_every;
    uint64_t seed;
    double first_move;
    double fallback; /* aqs_linkage_set_exact_fallback on the adaptive linkage (0: off) */
    double prediction; /* aqs_linkage_set_prediction on the adaptive linkage (0: off) */
    int32_t dca_form;  /* aqs_linkage_set_dca_form on both linkages */
    int32_t autopath;  /* aqs_linkage_set_auto on the adaptive linkage (default 0: off) */
    const char *out, *tip_path, *export_urdf;
    int append, quiet;
} bench_options;

typedef struct bench_state {
    const bench_options *opt;
    aqs_linkage *exact, *adapt;
    int32_t bodies, joints, nq, nv;
    int32_t tree_nodes, tree_height, max_handles;
    double mean_handles, build_s, finalize_s;
    long exact_bytes, adaptive_bytes; /* held (aqs_linkage_get_memory) */
    long exact_rss, adaptive_rss;     /* growth of the resident set */
    double *q0, *com_local, *com0, *com_now, *poses, *disp_ref, *qdd;
    double *ck_ref;  /* the exact run's centres of mass at the checkpoint steps */
    int32_t *ck_step; /* checkpoint i is after step ck_step[i] (increasing, the last is K) */
    int32_t nck;
    double *times, *times_exact, *times_dca;
    int32_t *force_body;
    double (*force_dir)[3];
    FILE *json, *tip;
    char run_id[48], stamp[32];
    int progress;           /* 1 when stderr is a terminal */
    long work_done, work_total;
    double last_progress;
} bench_state;

/* One configuration's run (one repeat). */
typedef struct bench_run {
    int32_t steps;
    double median_s, mean_s, exact_median_s, dca_median_s;
    double mean_ne, mean_nu, mean_np, mean_npred, mean_nf, max_bound;
    double mean_cost_ad, mean_cost_ex; /* the automatic path's predicted costs, per step */
    int32_t max_ne, fallback_steps, auto_exact_steps;
    double disp_err, max_disp;
    double disp_mean; /* mean over the checkpoints of the relative error after that step */
} bench_run;

static const char *const metric_names[] = {"abs_linkage", "rel_linkage", "abs_joint",
                                           "rel_joint",   "abs_world",   "rel_world"};
#define BENCH_NMETRICS ((int)(sizeof metric_names / sizeof metric_names[0]))

static int failed(aqs_status status, const aqs_linkage *linkage, const char *what)
{
    if (status == AQS_OK) {
        return 0;
    }
    fprintf(stderr, "aqs-bench: %s failed: %s (%d): %s\n", what, aqs_status_string(status),
            (int)status, linkage != NULL ? aqs_linkage_last_error(linkage) : "");
    return 1;
}

/* ------------------------------------------------------------------------
 * Options
 * ---------------------------------------------------------------------- */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: aqs-bench [options]\n"
            "  --scene NAME       chain30 | chain | molecule | millipede (default molecule)\n"
            "  --joints N         size of chain and molecule (default 50000)\n"
            "  --forces LIST      N_f values, e.g. 1,10,100,1000 (default 1)\n"
            "  --metric LIST      rel_joint | abs_joint | rel_linkage | abs_linkage |\n"
            "                     rel_world | abs_world, or several separated by commas\n"
            "                     (each eps is run for each, against one exact reference)\n"
            "                     (default rel_joint)\n"
            "  --eps LIST         eps values: numbers, 2^-I, or ranges 2^-I..J\n"
            "                     (default 2^-19); 0 is exact on the adaptive linkage\n"
            "  --steps K          steps per run (default 100)\n"
            "  --repeats R        runs of each configuration; medians over them (default 1)\n"
            "  --seed S           seed of the force bodies and directions (default 1)\n"
            "  --first-move X     dt: the fastest joint of the exact first solve moves X\n"
            "                     (rad or m) in the first step (default 1e-3)\n"
            "  --prediction M     aqs_linkage_set_prediction(M) on the adaptive linkage\n"
            "                     (default AQS_PREDICTION_MARGIN = 1024; 0: off)\n"
            "  --dca-form NAME    sqrt | phi: aqs_linkage_set_dca_form on both linkages\n"
            "                     (default sqrt, the library's)\n"
            "  --fallback F       aqs_linkage_set_exact_fallback(F) on the adaptive linkage:\n"
            "                     exact steps after one that computed more than F of the\n"
            "                     joints (default 0: off)\n"
            "  --auto on|off      aqs_linkage_set_auto on the adaptive linkage: each step\n"
            "                     takes the cheaper of the adaptive and the exact path\n"
            "                     (default off: the adaptive solver alone)\n"
            "  --exact-every C    one timed exact step after every C adaptive steps\n"
            "                     (default 10; at least 3 per run)\n"
            "  --out PATH         JSON Lines, one object per configuration (overwritten)\n"
            "  --append           append to --out instead of overwriting\n"
            "  --tip-path PATH    CSV of the last body's far end (chain30, chain) every\n"
            "                     --tip-every M steps (default 1): run,forces,eps,step,x,y,z\n"
            "  --quiet            no table on stdout\n"
            "  --export-urdf FILE write the scene (--scene, --joints) as URDF to FILE and\n"
            "                     exit without benchmarking\n"
            "  --help\n");
}

static int parse_long(const char *opt, const char *s, long lo, long hi, long *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "aqs-bench: %s: '%s' is not a whole number in %ld..%ld\n", opt, s, lo,
                hi);
        return 1;
    }
    *out = v;
    return 0;
}

static int parse_double(const char *opt, const char *s, double *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !isfinite(v) || v < 0.0) {
        fprintf(stderr, "aqs-bench: %s: '%s' is not a finite number >= 0\n", opt, s);
        return 1;
    }
    *out = v;
    return 0;
}

/* A number option with a condition on its value beyond parse_double's:
 * ok(v), else the message "OPT must be WHAT". */
static int positive(double v) { return v > 0.0; }
static int unit_interval(double v) { return v <= 1.0; }
static int zero_or_at_least_one(double v) { return v == 0.0 || v >= 1.0; }

static int parse_double_where(const char *opt, const char *s, double *out, int (*ok)(double),
                              const char *what)
{
    if (parse_double(opt, s, out) != 0) {
        return 1;
    }
    if (!ok(*out)) {
        fprintf(stderr, "aqs-bench: %s must be %s\n", opt, what);
        return 1;
    }
    return 0;
}

static int add_eps(bench_options *o, double eps, int log2i)
{
    if (o->neps == BENCH_MAX_LIST) {
        fprintf(stderr, "aqs-bench: --eps: more than %d values\n", BENCH_MAX_LIST);
        return 1;
    }
    o->eps[o->neps] = eps;
    o->eps_log2[o->neps++] = log2i;
    return 0;
}

/* One --forces item: a whole number >= 1. */
static int parse_force_item(char *tok, bench_options *o)
{
    long v;
    if (o->nforces == BENCH_MAX_LIST) {
        fprintf(stderr, "aqs-bench: --forces: more than %d values\n", BENCH_MAX_LIST);
        return 1;
    }
    if (parse_long("--forces", tok, 1, 1000000, &v) != 0) {
        return 1;
    }
    o->forces[o->nforces++] = (int32_t)v;
    return 0;
}

/* One --eps item: a number, 2^-I, or 2^-I..J (I to J). */
static int parse_eps_item(char *tok, bench_options *o)
{
    if (strncmp(tok, "2^-", 3) == 0) {
        char *dots = strstr(tok, "..");
        long a, b, i;
        if (dots != NULL) {
            *dots = '\0';
        }
        if (parse_long("--eps", tok + 3, 0, 60, &a) != 0 ||
            parse_long("--eps", dots != NULL ? dots + 2 : tok + 3, a, 60, &b) != 0) {
            return 1;
        }
        for (i = a; i <= b; ++i) {
            if (add_eps(o, ldexp(1.0, -(int)i), (int)i) != 0) {
                return 1;
            }
        }
    } else {
        double v;
        int e;
        if (parse_double("--eps", tok, &v) != 0) {
            return 1;
        }
        /* A power of two keeps its exponent for the tables. */
        e = (v > 0.0 && frexp(v, &e) == 0.5 && 1 - e >= 0) ? 1 - e : -1;
        return add_eps(o, v, e);
    }
    return 0;
}

/* A comma-separated list, every item non-empty, each handed to item(). */
static int parse_list(const char *opt, const char *s, bench_options *o,
                      int (*item)(char *, bench_options *))
{
    char buf[512], *tok = buf;
    if (strlen(s) >= sizeof buf) {
        fprintf(stderr, "aqs-bench: %s: list too long\n", opt);
        return 1;
    }
    strcpy(buf, s);
    for (;;) {
        char *comma = strchr(tok, ',');
        if (comma != NULL) {
            *comma = '\0';
        }
        if (*tok == '\0') {
            fprintf(stderr, "aqs-bench: %s: empty item in '%s'\n", opt, s);
            return 1;
        }
        if (item(tok, o) != 0) {
            return 1;
        }
        if (comma == NULL) {
            return 0;
        }
        tok = comma + 1;
    }
}

enum { OPT_SCENE, OPT_JOINTS, OPT_FORCES, OPT_METRIC, OPT_EPS, OPT_STEPS, OPT_REPEATS,
       OPT_SEED, OPT_FIRST_MOVE, OPT_FALLBACK, OPT_PREDICTION, OPT_DCA_FORM, OPT_AUTO, OPT_EXACT_EVERY, OPT_OUT, OPT_APPEND, OPT_TIP_PATH,
       OPT_TIP_EVERY, OPT_QUIET, OPT_EXPORT_URDF, OPT_HELP };

static const struct {
    const char *name;
    int id, takes_value;
} bench_option_table[] = {
    {"--scene", OPT_SCENE, 1},       {"--joints", OPT_JOINTS, 1},
    {"--forces", OPT_FORCES, 1},     {"--metric", OPT_METRIC, 1},
    {"--eps", OPT_EPS, 1},           {"--steps", OPT_STEPS, 1},
    {"--repeats", OPT_REPEATS, 1},   {"--seed", OPT_SEED, 1},
    {"--first-move", OPT_FIRST_MOVE, 1}, {"--exact-every", OPT_EXACT_EVERY, 1},
    {"--fallback", OPT_FALLBACK, 1}, {"--prediction", OPT_PREDICTION, 1},
    {"--dca-form", OPT_DCA_FORM, 1}, {"--auto", OPT_AUTO, 1},
    {"--out", OPT_OUT, 1},           {"--append", OPT_APPEND, 0},
    {"--tip-path", OPT_TIP_PATH, 1}, {"--tip-every", OPT_TIP_EVERY, 1},
    {"--quiet", OPT_QUIET, 0},       {"--help", OPT_HELP, 0},
    {"--export-urdf", OPT_EXPORT_URDF, 1},
};
#define BENCH_NOPTIONS ((int)(sizeof bench_option_table / sizeof bench_option_table[0]))

/* Returns 0 to run, 1 for an error (message printed), 2 after --help. */
static int parse_options(int argc, char **argv, bench_options *o)
{
    int i, k;
    long v;
    memset(o, 0, sizeof *o);
    o->scene = BENCH_SCENE_MOLECULE;
    o->size = 50000;
    o->forces[0] = 1;
    o->nforces = 1;
    o->metric = AQS_METRIC_REL_JOINT;
    o->metrics[0] = AQS_METRIC_REL_JOINT;
    o->nmetrics = 1;
    o->eps[0] = ldexp(1.0, -19);
    o->eps_log2[0] = 19;
    o->neps = 1;
    o->steps = 100;
    o->repeats = 1;
    o->exact_every = 10;
    o->tip_every = 1;
    o->seed = 1;
    o->first_move = 1e-3;
    o->prediction = AQS_PREDICTION_MARGIN;
    for (i = 1; i < argc; ++i) {
        const char *val = NULL;
        int id = -1;
        for (k = 0; k < BENCH_NOPTIONS; ++k) {
            if (strcmp(argv[i], bench_option_table[k].name) == 0) {
                id = bench_option_table[k].id;
                break;
            }
        }
        if (id < 0) {
            fprintf(stderr, "aqs-bench: unknown option '%s' (aqs-bench --help)\n", argv[i]);
            return 1;
        }
        if (bench_option_table[k].takes_value) {
            if (i + 1 >= argc) {
                fprintf(stderr, "aqs-bench: %s needs a value\n", argv[i]);
                return 1;
            }
            val = argv[++i];
        }
        switch (id) {
        case OPT_SCENE:
            o->scene = bench_scene_from_name(val);
            if (o->scene < 0) {
                fprintf(stderr, "aqs-bench: --scene: unknown scene '%s'\n", val);
                return 1;
            }
            break;
        case OPT_JOINTS:
            if (parse_long("--joints", val, 1, 100000000, &v) != 0) {
                return 1;
            }
            o->size = (int32_t)v;
            break;
        case OPT_FORCES:
        case OPT_EPS:
            *(id == OPT_FORCES ? &o->nforces : &o->neps) = 0;
            if (parse_list(argv[i - 1], val, o,
                           id == OPT_FORCES ? parse_force_item : parse_eps_item) != 0) {
                return 1;
            }
            break;
        case OPT_METRIC: {
            /* a comma-separated list: each eps is run for each measure,
             * against one exact reference run */
            const char *p = val;
            o->nmetrics = 0;
            for (;;) {
                size_t len = strcspn(p, ",");
                for (k = 0; k < BENCH_NMETRICS && (strlen(metric_names[k]) != len ||
                                                   strncmp(p, metric_names[k], len) != 0); ++k) {
                }
                if (k == BENCH_NMETRICS || o->nmetrics == BENCH_MAX_LIST) {
                    fprintf(stderr, "aqs-bench: --metric: unknown measure in '%s'\n", val);
                    return 1;
                }
                o->metrics[o->nmetrics++] = (int32_t)k;
                if (p[len] == '\0') {
                    break;
                }
                p += len + 1;
            }
            o->metric = o->metrics[0];
            break;
        }
        case OPT_STEPS:
        case OPT_REPEATS:
        case OPT_EXACT_EVERY:
        case OPT_TIP_EVERY:
            if (parse_long(argv[i - 1], val, 1, 100000000, &v) != 0) {
                return 1;
            }
            *(id == OPT_STEPS     ? &o->steps
              : id == OPT_REPEATS ? &o->repeats
              : id == OPT_TIP_EVERY ? &o->tip_every
                                  : &o->exact_every) = (int32_t)v;
            break;
        case OPT_SEED:
            if (parse_long("--seed", val, 0, 0x7fffffffL, &v) != 0) {
                return 1;
            }
            o->seed = (uint64_t)v;
            break;
        case OPT_FIRST_MOVE:
            if (parse_double_where("--first-move", val, &o->first_move, positive, "> 0") != 0) {
                return 1;
            }
            break;
        case OPT_FALLBACK:
            if (parse_double_where("--fallback", val, &o->fallback, unit_interval, "in [0, 1]") != 0) {
                return 1;
            }
            break;
        case OPT_DCA_FORM:
            if (strcmp(val, "sqrt") == 0) o->dca_form = AQS_DCA_FORM_SQRT;
            else if (strcmp(val, "phi") == 0) o->dca_form = AQS_DCA_FORM_PHI;
            else {
                fprintf(stderr, "aqs-bench: --dca-form: '%s' is not sqrt or phi\n", val);
                return 1;
            }
            break;
        case OPT_AUTO:
            if (strcmp(val, "on") == 0) o->autopath = 1;
            else if (strcmp(val, "off") == 0) o->autopath = 0;
            else {
                fprintf(stderr, "aqs-bench: --auto: '%s' is not on or off\n", val);
                return 1;
            }
            break;
        case OPT_PREDICTION:
            if (parse_double_where("--prediction", val, &o->prediction, zero_or_at_least_one,
                                   "0 or a finite number >= 1") != 0) {
                return 1;
            }
            break;
        case OPT_OUT:
        case OPT_TIP_PATH:
            *(id == OPT_OUT ? &o->out : &o->tip_path) = val;
            break;
        case OPT_EXPORT_URDF:
            o->export_urdf = val;
            break;
        case OPT_APPEND:
        case OPT_QUIET:
            *(id == OPT_APPEND ? &o->append : &o->quiet) = 1;
            break;
        default:
            usage(stdout);
            return 2;
        }
    }
    if (!bench_scene_has_size((bench_scene_kind)o->scene)) {
        o->size = bench_scene_default_size((bench_scene_kind)o->scene);
    }
    if (o->tip_path != NULL && o->scene != BENCH_SCENE_CHAIN30 && o->scene != BENCH_SCENE_CHAIN) {
        fprintf(stderr, "aqs-bench: --tip-path is for the chain30 and chain scenes\n");
        return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------
 * Scene, loads, runs
 * ---------------------------------------------------------------------- */

static void progress(bench_state *b, long add)
{
    double now;
    b->work_done += add;
    if (!b->progress) {
        return;
    }
    now = bench_now();
    if (now - b->last_progress < 0.2 && b->work_done < b->work_total) {
        return;
    }
    b->last_progress = now;
    {
        const int width = 40;
        const double f = b->work_total > 0 ? (double)b->work_done / (double)b->work_total : 1.0;
        const int filled = (int)(f * width + 0.5);
        int i;
        fputs("\r[", stderr);
        for (i = 0; i < width; ++i) {
            fputc(i < filled ? '#' : ' ', stderr);
        }
        fprintf(stderr, "] %5.1f %%", 100.0 * f);
        fflush(stderr);
    }
}

/* Force bodies: the first N_f distinct ones of one seeded sequence. */
static int draw_forces(bench_state *b, int32_t max_forces)
{
    const bench_scene_kind kind = (bench_scene_kind)b->opt->scene;
    const int32_t lo = kind == BENCH_SCENE_MILLIPEDE ? BENCH_MILLIPEDE_SPINE : 0;
    const int32_t pool = b->bodies - lo;
    bench_rng rng;
    unsigned char *used = (unsigned char *)calloc((size_t)b->bodies, 1);
    int32_t k = 0;
    if (max_forces > pool) {
        fprintf(stderr, "aqs-bench: %d forces but the %s scene has %d bodies to pull\n",
                (int)max_forces, bench_scene_name(kind), (int)pool);
        free(used);
        return 1;
    }
    b->force_body = (int32_t *)malloc(sizeof(int32_t) * (size_t)max_forces);
    b->force_dir = (double(*)[3])malloc(sizeof(double[3]) * (size_t)max_forces);
    if (used == NULL || b->force_body == NULL || b->force_dir == NULL) {
        free(used);
        return 1;
    }
    bench_rng_seed(&rng, b->opt->seed);
    if (kind == BENCH_SCENE_CHAIN30) {
        b->force_body[0] = bench_chain30_tip_body();
        b->force_dir[0][0] = 0.0;
        b->force_dir[0][1] = 1.0;
        b->force_dir[0][2] = 0.0;
        used[b->force_body[0]] = 1;
        k = 1;
    }
    while (k < max_forces) {
        const int32_t body = lo + (int32_t)bench_rng_below(&rng, (uint64_t)pool);
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

/* The force of force k is applied here: the far end of chain30's tip link
 * for its canonical force, else the body's centre of mass. */
static void force_point(const bench_state *b, int32_t k, double p[3])
{
    if (b->opt->scene == BENCH_SCENE_CHAIN30 && k == 0) {
        p[0] = BENCH_CHAIN30_LINK_LENGTH;
        p[1] = p[2] = 0.0;
        return;
    }
    memcpy(p, b->com_local + 3 * (size_t)b->force_body[k], 3 * sizeof(double));
}

/* Initial positions, the first nf forces, no gravity, one untimed solve (the
 * full coefficient update after setting every position). */
static int reset(bench_state *b, aqs_linkage *L, int32_t nf)
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
        double f[3], p[3];
        int i;
        for (i = 0; i < 3; ++i) {
            f[i] = BENCH_FORCE_N * b->force_dir[k][i];
        }
        force_point(b, k, p);
        if (failed(aqs_body_set_force(L, b->force_body[k], f, p, NULL), L,
                   "aqs_body_set_force")) {
            return 1;
        }
    }
    return failed(aqs_linkage_solve(L), L, "aqs_linkage_solve");
}

/* dt for nf forces: the fastest joint of the exact solve at the initial
 * state moves first_move in the first step (q += dt^2 qdd). */
static int choose_dt(bench_state *b, int32_t nf, double *dt)
{
    double max_abs = 0.0;
    int32_t i;
    if (reset(b, b->exact, nf) != 0 ||
        failed(aqs_linkage_get_accelerations(b->exact, b->qdd, (size_t)b->nv), b->exact,
               "aqs_linkage_get_accelerations")) {
        return 1;
    }
    for (i = 0; i < b->nv; ++i) {
        max_abs = fabs(b->qdd[i]) > max_abs ? fabs(b->qdd[i]) : max_abs;
    }
    if (!(max_abs > 0.0) || !isfinite(max_abs)) {
        fprintf(stderr, "aqs-bench: the forces produce no finite acceleration\n");
        return 1;
    }
    *dt = sqrt(b->opt->first_move / max_abs);
    return 0;
}

/* World positions of every body's centre of mass into out (3 per body). */
static int com_world(bench_state *b, aqs_linkage *L, double *out)
{
    int32_t i;
    if (failed(aqs_linkage_get_body_poses_world(L, b->poses, 7 * (size_t)b->bodies), L,
               "aqs_linkage_get_body_poses_world")) {
        return 1;
    }
    for (i = 0; i < b->bodies; ++i) {
        const double *p = b->poses + 7 * (size_t)i, *c = b->com_local + 3 * (size_t)i;
        const double w = p[3], x = p[4], y = p[5], z = p[6];
        /* p + R(q) c, R of the unit quaternion (w, x, y, z) */
        out[3 * (size_t)i + 0] = p[0] + (1 - 2 * (y * y + z * z)) * c[0] +
                                 2 * (x * y - w * z) * c[1] + 2 * (x * z + w * y) * c[2];
        out[3 * (size_t)i + 1] = p[1] + 2 * (x * y + w * z) * c[0] +
                                 (1 - 2 * (x * x + z * z)) * c[1] + 2 * (y * z - w * x) * c[2];
        out[3 * (size_t)i + 2] = p[2] + 2 * (x * z - w * y) * c[0] +
                                 2 * (y * z + w * x) * c[1] + (1 - 2 * (x * x + y * y)) * c[2];
    }
    return 0;
}

/* Displacements of the centres of mass since the initial state: stored as
 * the reference (ref = 1), or compared with it (r->disp_err). */
static int displacement(bench_state *b, aqs_linkage *L, int ref, bench_run *r)
{
    double *now = b->com_now;
    double max_d = 0.0, max_ref = 0.0, max_err = 0.0;
    int32_t i;
    if (com_world(b, L, now) != 0) {
        return 1;
    }
    for (i = 0; i < b->bodies; ++i) {
        double d2 = 0.0, r2 = 0.0, e2 = 0.0;
        int k;
        for (k = 0; k < 3; ++k) {
            const size_t j = 3 * (size_t)i + (size_t)k;
            const double d = now[j] - b->com0[j];
            if (ref) {
                b->disp_ref[j] = d;
            }
            d2 += d * d;
            r2 += b->disp_ref[j] * b->disp_ref[j];
            e2 += (d - b->disp_ref[j]) * (d - b->disp_ref[j]);
        }
        max_d = d2 > max_d ? d2 : max_d;
        max_ref = r2 > max_ref ? r2 : max_ref;
        max_err = e2 > max_err ? e2 : max_err;
    }
    r->max_disp = sqrt(max_d);
    r->disp_err = max_ref > 0.0 ? sqrt(max_err) / sqrt(max_ref) : 0.0;
    return 0;
}

/* The relative displacement error of the adaptive linkage after checkpoint
 * ck's step: max_i |c_i - c_i^exact| / max_i |c_i^exact - c_i^0| (-1 when
 * the exact run has not moved). */
static int checkpoint_error(bench_state *b, int32_t ck, double *e)
{
    const double *ref = b->ck_ref + 3 * (size_t)b->bodies * (size_t)ck;
    double max_ref = 0.0, max_err = 0.0;
    int32_t i;
    if (com_world(b, b->adapt, b->com_now) != 0) {
        return 1;
    }
    for (i = 0; i < b->bodies; ++i) {
        double r2 = 0.0, e2 = 0.0;
        int k;
        for (k = 0; k < 3; ++k) {
            const size_t j = 3 * (size_t)i + (size_t)k;
            r2 += (ref[j] - b->com0[j]) * (ref[j] - b->com0[j]);
            e2 += (b->com_now[j] - ref[j]) * (b->com_now[j] - ref[j]);
        }
        max_ref = r2 > max_ref ? r2 : max_ref;
        max_err = e2 > max_err ? e2 : max_err;
    }
    *e = max_ref > 0.0 ? sqrt(max_err) / sqrt(max_ref) : -1.0;
    return 0;
}

static int record_tip(bench_state *b, aqs_linkage *L, const char *run, int32_t nf, double eps,
                      int32_t step)
{
    const double far_end[3] = {1.0, 0.0, 0.0};
    double pos[3], q[4], x[3];
    if (b->tip == NULL || step % b->opt->tip_every != 0) {
        return 0;
    }
    if (failed(aqs_body_get_pose_world(L, b->bodies - 1, pos, q), L, "aqs_body_get_pose_world")) {
        return 1;
    }
    {
        const double w = q[0], qx = q[1], qy = q[2], qz = q[3];
        x[0] = pos[0] + (1 - 2 * (qy * qy + qz * qz)) * far_end[0];
        x[1] = pos[1] + 2 * (qx * qy + w * qz) * far_end[0];
        x[2] = pos[2] + 2 * (qx * qz - w * qy) * far_end[0];
    }
    fprintf(b->tip, "%s,%d,%.9g,%d,%.9g,%.9g,%.9g\n", run, (int)nf, eps, (int)step, x[0], x[1],
            x[2]);
    return 0;
}

/* One timed step of L, its solver statistics added to r's sums. */
static int timed_step(bench_state *b, aqs_linkage *L, double dt, double *t, bench_run *sums)
{
    aqs_solve_stats st;
    const double t0 = bench_now();
    if (failed(aqs_linkage_step(L, dt), L, "aqs_linkage_step")) {
        return 1;
    }
    *t = bench_now() - t0;
    progress(b, 1);
    if (sums == NULL) {
        return 0;
    }
    st.size = (uint32_t)sizeof st;
    if (failed(aqs_linkage_get_stats(L, &st), L, "aqs_linkage_get_stats")) {
        return 1;
    }
    sums->mean_s += *t;
    sums->mean_ne += st.computed_joints;
    sums->mean_nu += st.nodes_updated;
    sums->mean_np += st.nodes_processed;
    sums->mean_npred += st.nodes_predicted;
    sums->mean_nf += st.factors_updated;
    sums->mean_cost_ad += st.cost_adaptive;
    sums->mean_cost_ex += st.cost_exact;
    sums->max_ne = st.computed_joints > sums->max_ne ? st.computed_joints : sums->max_ne;
    sums->fallback_steps += st.fallback;
    sums->auto_exact_steps += st.auto_chosen && st.path != AQS_PATH_ADAPTIVE;
    sums->max_bound = st.error_bound > sums->max_bound ? st.error_bound : sums->max_bound;
    return 0;
}

static void finish_sums(bench_run *r, int32_t n)
{
    r->steps = n;
    r->mean_s /= n;
    r->mean_ne /= n;
    r->mean_nu /= n;
    r->mean_np /= n;
    r->mean_npred /= n;
    r->mean_nf /= n;
    r->mean_cost_ad /= n;
    r->mean_cost_ex /= n;
}

/* The exact reference run of nf forces: its displacements become the
 * reference (record = 1) and its median step time is returned in r. */
static int exact_reference(bench_state *b, int32_t nf, double dt, int record, bench_run *r)
{
    int32_t s, ck;
    memset(r, 0, sizeof *r);
    if (reset(b, b->exact, nf) != 0 || (record && record_tip(b, b->exact, "exact", nf, 0.0, 0))) {
        return 1;
    }
    for (s = 0, ck = 0; s < b->opt->steps; ++s) {
        if (timed_step(b, b->exact, dt, &b->times[s], r) != 0 ||
            (record && record_tip(b, b->exact, "exact", nf, 0.0, s + 1) != 0)) {
            return 1;
        }
        if (record && ck < b->nck && b->ck_step[ck] == s + 1 &&
            com_world(b, b->exact, b->ck_ref + 3 * (size_t)b->bodies * (size_t)ck++) != 0) {
            return 1;
        }
    }
    finish_sums(r, b->opt->steps);
    r->median_s = bench_median(b->times, (size_t)b->opt->steps);
    r->exact_median_s = r->median_s;
    return record ? displacement(b, b->exact, 1, r) : 0;
}

/* One repeat of configuration (nf, eps): A steps K times from the initial
 * state, E takes one timed exact step after every chunk. */
static int adaptive_run(bench_state *b, int32_t nf, double eps, double dt, int record,
                        bench_run *r)
{
    const int32_t K = b->opt->steps;
    int32_t chunk = b->opt->exact_every, s, ne = 0, ck = 0, nmean = 0;
    memset(r, 0, sizeof *r);
    if (K >= 3 && chunk > K / 3) {
        chunk = K / 3;
    }
    if (chunk < 1) {
        chunk = 1;
    }
    if (failed(aqs_linkage_set_tolerance(b->adapt, b->opt->metric, eps), b->adapt,
               "aqs_linkage_set_tolerance") ||
        failed(aqs_linkage_set_exact_fallback(b->adapt, b->opt->fallback), b->adapt,
               "aqs_linkage_set_exact_fallback") ||
        failed(aqs_linkage_set_prediction(b->adapt, b->opt->prediction), b->adapt,
               "aqs_linkage_set_prediction") ||
        failed(aqs_linkage_set_auto(b->adapt, b->opt->autopath), b->adapt, "aqs_linkage_set_auto") ||
        reset(b, b->adapt, nf) != 0 || reset(b, b->exact, nf) != 0 ||
        (record && record_tip(b, b->adapt, "adaptive", nf, eps, 0) != 0)) {
        return 1;
    }
    for (s = 0; s < K; ++s) {
        if (timed_step(b, b->adapt, dt, &b->times[s], r) != 0 ||
            (record && record_tip(b, b->adapt, "adaptive", nf, eps, s + 1) != 0)) {
            return 1;
        }
        if (record && ck < b->nck && b->ck_step[ck] == s + 1) {
            double e;
            if (checkpoint_error(b, ck++, &e) != 0) {
                return 1;
            }
            if (e >= 0.0) {
                r->disp_mean += e;
                ++nmean;
            }
        }
        if ((s + 1) % chunk == 0 || s + 1 == K) {
            /* One exact step by each solver: the articulated-body algorithm
             * (the default, what an exact user pays) and the DCA (whose time
             * per tree node is R's reference). The untimed solve brings the
             * tree, left stale by the articulated-body steps, up to date, so
             * that the DCA step costs what it costs in a DCA-only run. */
            if (failed(aqs_linkage_set_exact_solver(b->exact, AQS_EXACT_DCA), b->exact,
                       "aqs_linkage_set_exact_solver") ||
                failed(aqs_linkage_solve(b->exact), b->exact, "aqs_linkage_solve") ||
                timed_step(b, b->exact, dt, &b->times_dca[ne], NULL) != 0 ||
                failed(aqs_linkage_set_exact_solver(b->exact, AQS_EXACT_ABA), b->exact,
                       "aqs_linkage_set_exact_solver") ||
                timed_step(b, b->exact, dt, &b->times_exact[ne], NULL) != 0) {
                return 1;
            }
            ++ne;
        }
    }
    finish_sums(r, K);
    r->disp_mean = nmean > 0 ? r->disp_mean / nmean : 0.0;
    r->median_s = bench_median(b->times, (size_t)K);
    r->exact_median_s = bench_median(b->times_exact, (size_t)ne);
    r->dca_median_s = bench_median(b->times_dca, (size_t)ne);
    return displacement(b, b->adapt, 0, r);
}

static double loadavg1(void)
{
    double l = -1.0;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f != NULL) {
        if (fscanf(f, "%lf", &l) != 1) {
            l = -1.0;
        }
        fclose(f);
    }
    return l;
}

static void write_json(bench_state *b, int32_t nf, int ei, double dt, const bench_run *r,
                       double ms, double exact_ms, double dca_ms, double ref_ms)
{
    const bench_options *o = b->opt;
    const double t_node = dca_ms / b->tree_nodes;
    const double denom = (r->mean_ne + nf * (log((double)b->joints) / log(2.0))) * t_node;
    /* the same against the articulated-body step's time per joint */
    const double denom_aba = denom / t_node * (exact_ms / b->joints);
    const long kb = bench_peak_rss_kb();
    if (b->json == NULL) {
        return;
    }
    fprintf(b->json,
            "{\"bench\":\"aqs-bench\",\"run_id\":\"%s\",\"time\":\"%s\",\"version\":\"%s\","
            "\"scene\":\"%s\",\"joints\":%d,\"bodies\":%d,\"nv\":%d,\"tree_nodes\":%d,"
            "\"tree_height\":%d,\"handles_mean\":%.4f,\"handles_max\":%d,"
            "\"build_s\":%.6f,\"finalize_s\":%.6f,"
            "\"forces\":%d,\"force_seed\":%llu,\"metric\":\"%s\",\"eps\":%.17g,",
            b->run_id, b->stamp, aqs_version_string(), bench_scene_name(
                (bench_scene_kind)o->scene),
            (int)b->joints, (int)b->bodies, (int)b->nv, (int)b->tree_nodes, (int)b->tree_height,
            b->mean_handles, (int)b->max_handles, b->build_s, b->finalize_s, (int)nf,
            (unsigned long long)o->seed, metric_names[o->metric], o->eps[ei]);
    if (o->eps_log2[ei] >= 0) {
        fprintf(b->json, "\"eps_log2\":%d,", o->eps_log2[ei]);
    } else {
        fprintf(b->json, "\"eps_log2\":null,");
    }
    fprintf(b->json,
            "\"dt\":%.9g,\"first_move\":%.9g,\"steps\":%d,\"repeats\":%d,"
            "\"ms_per_step\":%.9g,\"mean_ms_per_step\":%.9g,\"exact_ms_per_step\":%.9g,"
            "\"exact_us_per_joint\":%.9g,\"exact_dca_ms_per_step\":%.9g,"
            "\"exact_ref_ms_per_step\":%.9g,\"exact_us_per_node\":%.9g,\"speedup\":%.9g,"
            "\"speedup_dca\":%.9g,"
            "\"computed_joints\":%.4f,\"max_computed_joints\":%d,\"nodes_updated\":%.4f,"
            "\"nodes_processed\":%.4f,\"max_error_bound\":%.9g,\"ratio_R\":%.9g,"
            "\"displacement_error\":%.9g,\"max_displacement\":%.9g,"
            "\"displacement_error_per_step\":%.9g,\"displacement_error_mean\":%.9g,"
            "\"displacement_checkpoints\":%d,"
            "\"exact_linkage_bytes\":%ld,\"adaptive_linkage_bytes\":%ld,"
            "\"exact_rss_bytes\":%ld,\"adaptive_rss_bytes\":%ld,"
            "\"peak_rss_bytes\":%ld,\"loadavg1\":%.2f,\"fallback\":%.9g,\"fallback_steps\":%d,"
            "\"prediction\":%.9g,\"nodes_predicted\":%.4f,\"factors_updated\":%.4f,"
            "\"ratio_R_aba\":%.9g,\"dca_form\":\"%s\",\"auto\":%s,\"auto_exact_steps\":%d,"
            "\"auto_cost_adaptive\":%.6g,\"auto_cost_exact\":%.6g}\n",
            dt, o->first_move, (int)o->steps, (int)o->repeats, ms, 1e3 * r->mean_s, exact_ms,
            1e3 * exact_ms / b->joints, dca_ms, ref_ms, 1e3 * t_node, exact_ms / ms, dca_ms / ms, r->mean_ne, (int)r->max_ne, r->mean_nu,
            r->mean_np, r->max_bound, ms / denom, r->disp_err, r->max_disp,
            r->disp_err / o->steps, r->disp_mean, (int)b->nck, b->exact_bytes,
            b->adaptive_bytes, b->exact_rss, b->adaptive_rss, kb < 0 ? -1L : 1024L * kb, loadavg1(), o->fallback, (int)r->fallback_steps,
            o->prediction, r->mean_npred, r->mean_nf, ms / denom_aba,
            o->dca_form == AQS_DCA_FORM_PHI ? "phi" : "sqrt", o->autopath ? "true" : "false",
            (int)r->auto_exact_steps, r->mean_cost_ad, r->mean_cost_ex);
    fflush(b->json);
}

static void print_row(bench_state *b, int32_t nf, int ei, const bench_run *r, double ms,
                      double exact_ms, double dca_ms)
{
    const bench_options *o = b->opt;
    const double t_node = dca_ms / b->tree_nodes;
    const double denom = (r->mean_ne + nf * (log((double)b->joints) / log(2.0))) * t_node;
    char eps[24];
    if (o->quiet) {
        return;
    }
    if (o->eps_log2[ei] >= 0) {
        snprintf(eps, sizeof eps, "2^-%d", o->eps_log2[ei]);
    } else {
        snprintf(eps, sizeof eps, "%.3g", o->eps[ei]);
    }
    if (b->progress) {
        fputs("\r\033[K", stderr);
    }
    printf("%6d %7s %6d %10.4f %10.3f %9.1f %10.3f %9.1f %10.1f %10.1f %6.2f %10.2e %10.2e %10.2e %10.2e\n",
           (int)nf, eps, (int)r->steps, ms, exact_ms, exact_ms / ms, dca_ms, dca_ms / ms, r->mean_ne,
           r->mean_nu, ms / denom, r->disp_err, r->disp_err / r->steps, r->disp_mean, r->max_bound);
    fflush(stdout);
}

/* Bytes a linkage holds by its own count. */
static long linkage_bytes(const aqs_linkage *L)
{
    aqs_memory_stats m;
    memset(&m, 0, sizeof m);
    m.size = sizeof m;
    return aqs_linkage_get_memory(L, &m) == AQS_OK ? (long)m.bytes : -1L;
}

static int setup(bench_state *b)
{
    const bench_options *o = b->opt;
    const bench_scene_kind kind = (bench_scene_kind)o->scene;
    long rss0;
    double t0;
    int32_t i, max_forces = 0;
    rss0 = bench_current_rss_bytes();
    /* the DCA step is R's reference for the adaptive step's nodes: the
     * back-substitution as it is, without the exact solve's refinement
     * (docs/math.md 13a), as the adaptive solve processes them */
    if (failed(aqs_linkage_create(&b->exact), NULL, "aqs_linkage_create") ||
        failed(aqs_linkage_set_dca_form(b->exact, o->dca_form), b->exact, "aqs_linkage_set_dca_form") ||
        failed(aqs_linkage_set_exact_refinement(b->exact, 0), b->exact, "aqs_linkage_set_exact_refinement")) {
        return 1;
    }
    t0 = bench_now();
    if (failed(bench_build_scene(b->exact, kind, o->size), b->exact, "building the scene")) {
        return 1;
    }
    b->build_s = bench_now() - t0;
    t0 = bench_now();
    if (failed(aqs_linkage_finalize(b->exact), b->exact, "aqs_linkage_finalize")) {
        return 1;
    }
    b->finalize_s = bench_now() - t0;
    if (failed(aqs_linkage_get_sizes(b->exact, &b->bodies, &b->joints, &b->nq, &b->nv),
               b->exact, "aqs_linkage_get_sizes") ||
        failed(aqs_linkage_get_tree_stats(b->exact, &b->tree_nodes, &b->tree_height,
                                          &b->mean_handles, &b->max_handles),
               b->exact, "aqs_linkage_get_tree_stats")) {
        return 1;
    }
    for (i = 0; i < o->nforces; ++i) {
        max_forces = o->forces[i] > max_forces ? o->forces[i] : max_forces;
    }
    b->q0 = (double *)malloc(sizeof(double) * (size_t)b->nq);
    b->qdd = (double *)malloc(sizeof(double) * (size_t)b->nv);
    b->poses = (double *)malloc(sizeof(double) * 7 * (size_t)b->bodies);
    b->com_local = (double *)malloc(sizeof(double) * 3 * (size_t)b->bodies);
    b->com0 = (double *)malloc(sizeof(double) * 3 * (size_t)b->bodies);
    b->com_now = (double *)malloc(sizeof(double) * 3 * (size_t)b->bodies);
    b->disp_ref = (double *)calloc(3 * (size_t)b->bodies, sizeof(double));
    {
        /* checkpoints of the per-step error: every step within 256 MB */
        const double per = 24.0 * (double)b->bodies, budget = 256.0 * 1024 * 1024;
        int32_t k;
        b->nck = per * o->steps <= budget ? o->steps : (int32_t)(budget / per);
        if (b->nck < 1) {
            b->nck = 1;
        }
        b->ck_step = (int32_t *)malloc(sizeof(int32_t) * (size_t)b->nck);
        b->ck_ref = (double *)malloc(3 * sizeof(double) * (size_t)b->bodies * (size_t)b->nck);
        if (b->ck_step == NULL || b->ck_ref == NULL) {
            fprintf(stderr, "aqs-bench: out of memory\n");
            return 1;
        }
        for (k = 0; k < b->nck; ++k) {
            b->ck_step[k] = (int32_t)(((int64_t)(k + 1) * o->steps) / b->nck);
        }
    }
    b->times = (double *)malloc(sizeof(double) * (size_t)o->steps);
    b->times_exact = (double *)malloc(sizeof(double) * (size_t)o->steps);
    b->times_dca = (double *)malloc(sizeof(double) * (size_t)o->steps);
    if (b->q0 == NULL || b->qdd == NULL || b->poses == NULL || b->com_local == NULL ||
        b->com0 == NULL || b->com_now == NULL || b->disp_ref == NULL || b->times == NULL || b->times_exact == NULL ||
        b->times_dca == NULL) {
        fprintf(stderr, "aqs-bench: out of memory\n");
        return 1;
    }
    for (i = 0; i < b->bodies; ++i) {
        bench_scene_body_com(kind, i, b->com_local + 3 * (size_t)i);
    }
    if (draw_forces(b, max_forces) != 0 ||
        failed(aqs_linkage_get_positions(b->exact, b->q0, (size_t)b->nq), b->exact,
               "aqs_linkage_get_positions") ||
        com_world(b, b->exact, b->com0) != 0 || reset(b, b->exact, 1) != 0) {
        return 1;
    }
    /* Memory of one exact linkage (built, finalized, solved once), then of
     * one adaptive linkage once its total-acceleration factors exist: what
     * each holds by its own count (aqs_linkage_get_memory), and the growth of
     * the resident set. */
    b->exact_bytes = linkage_bytes(b->exact);
    b->exact_rss = bench_current_rss_bytes() - rss0;
    rss0 = bench_current_rss_bytes();
    if (failed(aqs_linkage_create(&b->adapt), NULL, "aqs_linkage_create") ||
        failed(aqs_linkage_set_dca_form(b->adapt, o->dca_form), b->adapt, "aqs_linkage_set_dca_form") ||
        failed(bench_build_scene(b->adapt, kind, o->size), b->adapt, "building the scene") ||
        failed(aqs_linkage_finalize(b->adapt), b->adapt, "aqs_linkage_finalize") ||
        failed(aqs_linkage_set_tolerance(b->adapt, o->metric, ldexp(1.0, -19)), b->adapt,
               "aqs_linkage_set_tolerance") ||
        reset(b, b->adapt, 1) != 0) {
        return 1;
    }
    b->adaptive_bytes = linkage_bytes(b->adapt);
    b->adaptive_rss = bench_current_rss_bytes() - rss0;
    printf("scene %s: %d bodies, %d joints (nq %d, nv %d); built in %.3f s, finalized in "
           "%.3f s\n"
           "assembly tree: %d nodes, height %d (log2 N = %.1f), handles per node mean %.2f "
           "max %d\n"
           "memory: exact linkage %.0f B/joint, adaptive linkage %.0f B/joint (held, "
           "aqs_linkage_get_memory; resident growth %.0f and %.0f)\n",
           bench_scene_name(kind), (int)b->bodies, (int)b->joints, (int)b->nq, (int)b->nv,
           b->build_s, b->finalize_s, (int)b->tree_nodes, (int)b->tree_height,
           log((double)b->joints) / log(2.0), b->mean_handles, (int)b->max_handles,
           (double)b->exact_bytes / b->joints, (double)b->adaptive_bytes / b->joints,
           (double)b->exact_rss / b->joints, (double)b->adaptive_rss / b->joints);
    return 0;
}

static int open_outputs(bench_state *b)
{
    const bench_options *o = b->opt;
    if (o->out != NULL) {
        b->json = fopen(o->out, o->append ? "a" : "w");
        if (b->json == NULL) {
            fprintf(stderr, "aqs-bench: cannot open %s: %s\n", o->out, strerror(errno));
            return 1;
        }
    }
    if (o->tip_path != NULL) {
        b->tip = fopen(o->tip_path, "w");
        if (b->tip == NULL) {
            fprintf(stderr, "aqs-bench: cannot open %s: %s\n", o->tip_path, strerror(errno));
            return 1;
        }
        fprintf(b->tip, "run,forces,eps,step,x,y,z\n");
    }
    return 0;
}

/* All configurations of one N_f. */
static int run_forces(bench_state *b, int32_t nf)
{
    const bench_options *o = b->opt;
    const int32_t R = o->repeats;
    double dt, *ms = NULL, *ex = NULL, *dc = NULL, *ref = NULL;
    bench_run first, r, ref_run;
    int32_t rep;
    int ei, rc = 1;
    ms = (double *)malloc(sizeof(double) * (size_t)R);
    ex = (double *)malloc(sizeof(double) * (size_t)R);
    dc = (double *)malloc(sizeof(double) * (size_t)R);
    ref = (double *)malloc(sizeof(double) * (size_t)R);
    if (ms == NULL || ex == NULL || dc == NULL || ref == NULL || choose_dt(b, nf, &dt) != 0) {
        goto out;
    }
    for (rep = 0; rep < R; ++rep) {
        if (exact_reference(b, nf, dt, rep == 0, &ref_run) != 0) {
            goto out;
        }
        ref[rep] = 1e3 * ref_run.median_s;
    }
    for (ei = 0; ei < o->neps * o->nmetrics; ++ei) {
        double ms_med, ex_med, dc_med, ref_med;
        ((bench_options *)o)->metric = o->metrics[ei / o->neps];
        if (o->nmetrics > 1 && ei % o->neps == 0 && !o->quiet) {
            printf("-- metric %s\n", metric_names[o->metric]);
        }
        for (rep = 0; rep < R; ++rep) {
            if (adaptive_run(b, nf, o->eps[ei % o->neps], dt, rep == 0, rep == 0 ? &first : &r) != 0) {
                goto out;
            }
            ms[rep] = 1e3 * (rep == 0 ? first.median_s : r.median_s);
            ex[rep] = 1e3 * (rep == 0 ? first.exact_median_s : r.exact_median_s);
            dc[rep] = 1e3 * (rep == 0 ? first.dca_median_s : r.dca_median_s);
        }
        ms_med = bench_median(ms, (size_t)R);
        ex_med = bench_median(ex, (size_t)R);
        dc_med = bench_median(dc, (size_t)R);
        memcpy(ms, ref, sizeof(double) * (size_t)R);
        ref_med = bench_median(ms, (size_t)R);
        write_json(b, nf, ei % o->neps, dt, &first, ms_med, ex_med, dc_med, ref_med);
        print_row(b, nf, ei % o->neps, &first, ms_med, ex_med, dc_med);
    }
    rc = 0;
out:
    free(ms);
    free(ex);
    free(dc);
    free(ref);
    return rc;
}

/* --export-urdf: build the scene alone, write it as URDF, no benchmark. */
static int export_scene(const bench_options *o)
{
    aqs_linkage *L = NULL;
    char msg[256] = "";
    aqs_status st = aqs_linkage_create(&L);
    if (st == AQS_OK) {
        st = bench_build_scene(L, (bench_scene_kind)o->scene, o->size);
    }
    if (st != AQS_OK) {
        fprintf(stderr, "aqs-bench: building the scene failed: %s\n",
                L != NULL ? aqs_linkage_last_error(L) : aqs_status_string(st));
        aqs_linkage_destroy(L);
        return 1;
    }
    st = bench_export_urdf(L, o->export_urdf, bench_scene_name((bench_scene_kind)o->scene), msg,
                           sizeof msg);
    aqs_linkage_destroy(L);
    if (st != AQS_OK) {
        fprintf(stderr, "aqs-bench: --export-urdf %s: %s\n", o->export_urdf, msg);
        return 1;
    }
    printf("wrote %s (scene %s)\n", o->export_urdf, bench_scene_name((bench_scene_kind)o->scene));
    return 0;
}

int main(int argc, char **argv)
{
    bench_options opt;
    bench_state b;
    int rc, i;
    const double t_start = bench_now();

    rc = parse_options(argc, argv, &opt);
    if (rc != 0) {
        return rc == 2 ? 0 : 2;
    }
    if (aqs_version() != AQS_VERSION_NUMBER) {
        fprintf(stderr, "aqs-bench: header version %d but library version %d\n",
                (int)AQS_VERSION_NUMBER, (int)aqs_version());
        return 1;
    }
    if (opt.export_urdf != NULL) {
        return export_scene(&opt);
    }
    memset(&b, 0, sizeof b);
    b.opt = &opt;
    bench_utc_stamp(b.stamp, sizeof b.stamp);
    snprintf(b.run_id, sizeof b.run_id, "%s-%ld", b.stamp, (long)getpid());
    b.progress = isatty(STDERR_FILENO);
    rc = 1;
    printf("aqs %s aqs-bench, %s, load average %.2f\n", aqs_version_string(), b.stamp,
           loadavg1());
    if (open_outputs(&b) != 0 || setup(&b) != 0) {
        goto done;
    }
    /* Work units for the progress bar: steps of E and A. */
    {
        const long K = opt.steps;
        const long chunks = (K + 2) / 3 > K / opt.exact_every ? (K + 2) / 3 : K / opt.exact_every;
        b.work_total = (long)opt.nforces * opt.repeats * (K + (long)opt.neps * opt.nmetrics * (K + 2 * chunks + 1));
    }
    if (!opt.quiet) {
        printf("metric %s%s; %d steps per run, %d repeat(s); force seed %llu; dt: the fastest "
               "joint moves %.3g in the first exact step\n"
               "ms/step, exact ms (articulated-body algorithm, the default exact solver) and DCA ms "
               "(exact by the DCA): medians (exact steps interleaved with the adaptive run); "
               "R = t / ((N_E + N_f log2 N) t_node), t_node = DCA ms / tree nodes; disp err = "
               "max_i |d_i - d_i^exact| / max_i |d_i^exact| (centres of mass) after the run; err/steps = "
               "that / steps; mean err = its mean over the steps (the paper's 'per time step', two "
               "readings)\n",
               metric_names[opt.metric], opt.nmetrics > 1 ? " (and the others of --metric)" : "", (int)opt.steps, (int)opt.repeats,
               (unsigned long long)opt.seed, opt.first_move);
        printf("%6s %7s %6s %10s %10s %9s %10s %9s %10s %10s %6s %10s %10s %10s %10s\n", "N_f", "eps",
               "steps", "ms/step", "exact ms", "speedup", "DCA ms", "vs DCA", "N_E", "updated", "R",
               "disp err", "err/steps", "mean err", "max bound");
    }
    for (i = 0; i < opt.nforces; ++i) {
        if (run_forces(&b, opt.forces[i]) != 0) {
            goto done;
        }
    }
    if (b.progress) {
        fputs("\r\033[K", stderr);
    }
    printf("peak RSS %.1f MB (both linkages); %.1f s; %s%s\n", bench_peak_rss_kb() / 1024.0,
           bench_now() - t_start, b.json != NULL ? "JSON lines in " : "no JSON written",
           b.json != NULL ? opt.out : "");
    rc = 0;
done:
    if (b.json != NULL && fclose(b.json) != 0) {
        rc = 1;
    }
    if (b.tip != NULL && fclose(b.tip) != 0) {
        rc = 1;
    }
    aqs_linkage_destroy(b.exact);
    aqs_linkage_destroy(b.adapt);
    free(b.q0);
    free(b.qdd);
    free(b.poses);
    free(b.com_local);
    free(b.com0);
    free(b.com_now);
    free(b.disp_ref);
    free(b.ck_ref);
    free(b.ck_step);
    free(b.times);
    free(b.times_exact);
    free(b.times_dca);
    free(b.force_body);
    free(b.force_dir);
    return rc;
}
