/*
 * exact_bench.c -- times the exact solver (eps = 0): aqs_linkage_step on the
 * 50,000-joint chain, the 50,000-joint molecule and the 13,000-link millipede.
 *
 * Each scene runs in its own child process so that its peak RSS is its own.
 * Loads: gravity off; one force of 1 N in a seeded random world direction at
 * the origin of a seeded random body. dt is set so that the fastest joint
 * moves 1e-3 rad (or m) in the first step. Prints a table and appends one
 * JSON line per scene to docs/bench/exact.jsonl (or --out PATH).
 *
 * usage: exact_bench [--joints N] [--budget SECONDS] [--out PATH]
 */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

#define MIN_STEPS 5
#define MAX_STEPS 200
#define FIRST_STEP_MOVE 1e-3
#define FORCE_SEED UINT64_C(0xf0ce5eed)

enum scene_kind { SCENE_CHAIN, SCENE_MOLECULE, SCENE_MILLIPEDE };

typedef struct options {
    int32_t joints;
    double budget; /* seconds of stepping per scene */
    const char *out;
} options;

/* What a child process sends back to the parent through a pipe. */
typedef struct scene_result {
    int ok;
    char name[32];
    int32_t bodies, joints, nv;
    double build_s, finalize_s, first_solve_s;
    int32_t tree_nodes, tree_height, max_handles;
    double mean_handles;
    int32_t force_body;
    double force[3];
    double dt;
    int32_t steps;
    double step_median_s, step_min_s, step_max_s;
    double max_abs_qdd;
    long peak_rss_kb;
    /* molecule geometry (from aqs_linkage_get_body_poses_world) */
    int has_geometry;
    int32_t bonds, angles, backbone;
    double bond_mean, bond_sd, angle_mean_deg, angle_sd_deg, worst_axis_deg;
} scene_result;

static int failed(aqs_status status, const aqs_linkage *linkage, const char *scene,
                  const char *what)
{
    if (status == AQS_OK) {
        return 0;
    }
    fprintf(stderr, "exact_bench [%s]: %s failed: %s (%d): %s\n", scene, what,
            aqs_status_string(status), (int)status, aqs_linkage_last_error(linkage));
    return 1;
}

/* Bond lengths and angles of the molecule measured on the library's world
 * poses, and the angle between each body's z axis (its torsion axis) and its
 * incoming bond. */
static int molecule_geometry(const aqs_linkage *linkage, const int32_t *parents, int32_t n,
                             scene_result *r)
{
    const double rad_to_deg = 180.0 / 3.14159265358979323846;
    double *poses = (double *)malloc(sizeof(double) * 7 * (size_t)n);
    double sum_b = 0.0, sum_bb = 0.0, sum_a = 0.0, sum_aa = 0.0, worst_axis = 0.0;
    int32_t bonds = 0, angles = 0, i;
    if (poses == NULL) {
        fprintf(stderr, "exact_bench [%s]: out of memory for poses\n", r->name);
        return 1;
    }
    if (failed(aqs_linkage_get_body_poses_world(linkage, poses, 7 * (size_t)n), linkage, r->name,
               "aqs_linkage_get_body_poses_world")) {
        free(poses);
        return 1;
    }
    for (i = 0; i < n; ++i) {
        const int32_t p = parents[i];
        const double *c = poses + 7 * (size_t)i;
        double bond[3], length, zaxis[3];
        int k;
        if (p == AQS_WORLD) {
            continue;
        }
        for (k = 0; k < 3; ++k) {
            bond[k] = c[k] - poses[7 * (size_t)p + k];
        }
        length = sqrt(bond[0] * bond[0] + bond[1] * bond[1] + bond[2] * bond[2]);
        sum_b += length;
        sum_bb += length * length;
        ++bonds;
        /* z axis of the body: third column of R(q), q = (w, x, y, z). */
        zaxis[0] = 2.0 * (c[4] * c[6] + c[3] * c[5]);
        zaxis[1] = 2.0 * (c[5] * c[6] - c[3] * c[4]);
        zaxis[2] = 1.0 - 2.0 * (c[4] * c[4] + c[5] * c[5]);
        {
            /* atan2(|z x b|, z . b) stays accurate for tiny angles. */
            const double cx = zaxis[1] * bond[2] - zaxis[2] * bond[1];
            const double cy = zaxis[2] * bond[0] - zaxis[0] * bond[2];
            const double cz = zaxis[0] * bond[1] - zaxis[1] * bond[0];
            const double dot = zaxis[0] * bond[0] + zaxis[1] * bond[1] + zaxis[2] * bond[2];
            const double off = atan2(sqrt(cx * cx + cy * cy + cz * cz), dot) * rad_to_deg;
            worst_axis = off > worst_axis ? off : worst_axis;
        }
        if (parents[p] != AQS_WORLD) {
            const double *pp = poses + 7 * (size_t)p;
            const double *g = poses + 7 * (size_t)parents[p];
            double u[3], dot = 0.0, nu = 0.0, nv = 0.0, angle, cosine;
            for (k = 0; k < 3; ++k) {
                u[k] = g[k] - pp[k];
                dot += u[k] * bond[k];
                nu += u[k] * u[k];
                nv += bond[k] * bond[k];
            }
            cosine = dot / sqrt(nu * nv);
            cosine = cosine > 1.0 ? 1.0 : cosine < -1.0 ? -1.0 : cosine;
            angle = acos(cosine) * rad_to_deg;
            sum_a += angle;
            sum_aa += angle * angle;
            ++angles;
        }
    }
    free(poses);
    r->has_geometry = 1;
    r->bonds = bonds;
    r->angles = angles;
    r->bond_mean = bonds > 0 ? sum_b / bonds : 0.0;
    r->bond_sd = bonds > 1 ? sqrt((sum_bb - bonds * r->bond_mean * r->bond_mean) / (bonds - 1))
                           : 0.0;
    r->angle_mean_deg = angles > 0 ? sum_a / angles : 0.0;
    r->angle_sd_deg =
        angles > 1 ? sqrt((sum_aa - angles * r->angle_mean_deg * r->angle_mean_deg) / (angles - 1))
                   : 0.0;
    r->worst_axis_deg = worst_axis;
    return 0;
}

static int geometry_ok(const scene_result *r)
{
    return fabs(r->bond_mean - BENCH_MOLECULE_BOND_MEAN) < 0.005 &&
           fabs(r->bond_sd - BENCH_MOLECULE_BOND_SD) < 0.005 &&
           fabs(r->angle_mean_deg - BENCH_MOLECULE_ANGLE_MEAN_DEG) < 0.5 &&
           fabs(r->angle_sd_deg - BENCH_MOLECULE_ANGLE_SD_DEG) < 0.5 && r->worst_axis_deg < 1e-3;
}

static aqs_status build(aqs_linkage *linkage, enum scene_kind kind, int32_t joints,
                        int32_t *parents, int32_t *backbone)
{
    switch (kind) {
    case SCENE_CHAIN:
        return bench_build_chain(linkage, joints);
    case SCENE_MOLECULE:
        return bench_build_molecule_ex(linkage, joints, BENCH_MOLECULE_SEED, parents, backbone);
    case SCENE_MILLIPEDE:
        return bench_build_millipede(linkage);
    }
    return AQS_EINVAL;
}

/* Everything after the build: tree, loads, timing. */
static int measure(aqs_linkage *linkage, const options *opt, scene_result *r)
{
    const double zero[3] = {0.0, 0.0, 0.0};
    double *qdd = NULL, *times = NULL;
    double t0, spent = 0.0;
    bench_rng rng;
    int32_t i;
    int rc = 1;

    if (failed(aqs_linkage_get_sizes(linkage, &r->bodies, &r->joints, NULL, &r->nv), linkage,
               r->name, "aqs_linkage_get_sizes") ||
        failed(aqs_linkage_get_tree_stats(linkage, &r->tree_nodes, &r->tree_height,
                                          &r->mean_handles, &r->max_handles),
               linkage, r->name, "aqs_linkage_get_tree_stats")) {
        return 1;
    }
    bench_rng_seed(&rng, FORCE_SEED);
    r->force_body = (int32_t)bench_rng_below(&rng, (uint64_t)r->bodies);
    bench_rng_unit_vector(&rng, r->force);
    if (failed(aqs_linkage_set_gravity(linkage, zero), linkage, r->name,
               "aqs_linkage_set_gravity") ||
        failed(aqs_body_set_force(linkage, r->force_body, r->force, NULL, NULL), linkage,
               r->name, "aqs_body_set_force")) {
        return 1;
    }
    qdd = (double *)malloc(sizeof(double) * (size_t)r->nv);
    times = (double *)malloc(sizeof(double) * MAX_STEPS);
    if (qdd == NULL || times == NULL) {
        fprintf(stderr, "exact_bench [%s]: out of memory\n", r->name);
        goto done;
    }
    t0 = bench_now();
    if (failed(aqs_linkage_solve(linkage), linkage, r->name, "aqs_linkage_solve")) {
        goto done;
    }
    r->first_solve_s = bench_now() - t0;
    if (failed(aqs_linkage_get_accelerations(linkage, qdd, (size_t)r->nv), linkage, r->name,
               "aqs_linkage_get_accelerations")) {
        goto done;
    }
    r->max_abs_qdd = 0.0;
    for (i = 0; i < r->nv; ++i) {
        if (!isfinite(qdd[i])) {
            fprintf(stderr, "exact_bench [%s]: acceleration %d is %g\n", r->name, (int)i, qdd[i]);
            goto done;
        }
        r->max_abs_qdd = fabs(qdd[i]) > r->max_abs_qdd ? fabs(qdd[i]) : r->max_abs_qdd;
    }
    if (!(r->max_abs_qdd > 0.0)) {
        fprintf(stderr, "exact_bench [%s]: the force produced no acceleration\n", r->name);
        goto done;
    }
    r->dt = sqrt(FIRST_STEP_MOVE / r->max_abs_qdd);
    /* One untimed step warms the caches, then step within the budget. */
    if (failed(aqs_linkage_step(linkage, r->dt), linkage, r->name, "aqs_linkage_step")) {
        goto done;
    }
    r->steps = 0;
    while (r->steps < MAX_STEPS && (r->steps < MIN_STEPS || spent < opt->budget)) {
        t0 = bench_now();
        if (failed(aqs_linkage_step(linkage, r->dt), linkage, r->name, "aqs_linkage_step")) {
            goto done;
        }
        times[r->steps] = bench_now() - t0;
        spent += times[r->steps];
        ++r->steps;
    }
    if (failed(aqs_linkage_get_accelerations(linkage, qdd, (size_t)r->nv), linkage, r->name,
               "aqs_linkage_get_accelerations")) {
        goto done;
    }
    for (i = 0; i < r->nv; ++i) {
        if (!isfinite(qdd[i])) {
            fprintf(stderr, "exact_bench [%s]: after %d steps acceleration %d is %g\n", r->name,
                    (int)r->steps, (int)i, qdd[i]);
            goto done;
        }
    }
    r->step_median_s = bench_median(times, (size_t)r->steps);
    r->step_min_s = times[0];
    r->step_max_s = times[r->steps - 1];
    rc = 0;
done:
    free(qdd);
    free(times);
    return rc;
}

/* Run one scene (in the child process). */
static int run_scene(enum scene_kind kind, const char *name, int32_t joints, const options *opt,
                     scene_result *r)
{
    aqs_linkage *linkage = NULL;
    int32_t *parents = NULL;
    double t0;
    int rc = 1;
    aqs_status st;

    memset(r, 0, sizeof *r);
    strncpy(r->name, name, sizeof r->name - 1);
    st = aqs_linkage_create(&linkage);
    if (st != AQS_OK) {
        fprintf(stderr, "exact_bench [%s]: aqs_linkage_create failed: %s\n", name,
                aqs_status_string(st));
        return 1;
    }
    if (kind == SCENE_MOLECULE) {
        parents = (int32_t *)malloc(sizeof(int32_t) * (size_t)joints);
        if (parents == NULL) {
            fprintf(stderr, "exact_bench [%s]: out of memory\n", name);
            goto done;
        }
    }
    t0 = bench_now();
    if (failed(build(linkage, kind, joints, parents, &r->backbone), linkage, name, "build")) {
        goto done;
    }
    r->build_s = bench_now() - t0;
    t0 = bench_now();
    if (failed(aqs_linkage_finalize(linkage), linkage, name, "aqs_linkage_finalize")) {
        goto done;
    }
    r->finalize_s = bench_now() - t0;
    if (kind == SCENE_MOLECULE && molecule_geometry(linkage, parents, joints, r) != 0) {
        goto done;
    }
    if (measure(linkage, opt, r) != 0) {
        goto done;
    }
    r->peak_rss_kb = bench_peak_rss_kb();
    r->ok = 1;
    rc = 0;
done:
    free(parents);
    aqs_linkage_destroy(linkage);
    return rc;
}

static void print_details(const scene_result *r)
{
    printf("[%s] %d bodies, %d joints, nv %d; build %.3f s, finalize %.3f s; "
           "tree: %d nodes, height %d (log2 N = %.1f), handles mean %.2f max %d\n",
           r->name, (int)r->bodies, (int)r->joints, (int)r->nv, r->build_s, r->finalize_s,
           (int)r->tree_nodes, (int)r->tree_height, log((double)r->joints) / log(2.0),
           r->mean_handles, (int)r->max_handles);
    if (r->has_geometry) {
        printf("[%s] geometry from world poses: backbone %d atoms; %d bonds, length mean %.4f "
               "sd %.4f (want %.2f, %.2f); %d bond angles, mean %.2f sd %.2f deg (want %.0f, "
               "%.0f); torsion axis vs bond: worst %.1e deg -> %s\n",
               r->name, (int)r->backbone, (int)r->bonds, r->bond_mean, r->bond_sd,
               BENCH_MOLECULE_BOND_MEAN, BENCH_MOLECULE_BOND_SD, (int)r->angles,
               r->angle_mean_deg, r->angle_sd_deg, BENCH_MOLECULE_ANGLE_MEAN_DEG,
               BENCH_MOLECULE_ANGLE_SD_DEG, r->worst_axis_deg, geometry_ok(r) ? "ok" : "WRONG");
    }
    printf("[%s] force 1 N along (%.3f, %.3f, %.3f) on body %d; first solve %.3f ms, "
           "max |qdd| %.3e, dt %.3e s; %d timed steps\n",
           r->name, r->force[0], r->force[1], r->force[2], (int)r->force_body,
           1e3 * r->first_solve_s, r->max_abs_qdd, r->dt, (int)r->steps);
    fflush(stdout);
}

static int append_json(const options *opt, const scene_result *r, const char *stamp)
{
    FILE *f = fopen(opt->out, "a");
    if (f == NULL) {
        fprintf(stderr, "exact_bench: cannot open %s: %s\n", opt->out, strerror(errno));
        return 1;
    }
    fprintf(f,
            "{\"bench\": \"exact\", \"time\": \"%s\", \"version\": \"%s\", \"scene\": \"%s\", "
            "\"bodies\": %d, \"joints\": %d, \"nv\": %d, \"gravity\": [0, 0, 0], "
            "\"forces\": 1, \"force_body\": %d, \"force\": [%.6f, %.6f, %.6f], \"dt\": %.6e, "
            "\"build_s\": %.6f, \"finalize_s\": %.6f, \"tree_nodes\": %d, \"tree_height\": %d, "
            "\"mean_handles\": %.4f, \"max_handles\": %d, \"first_solve_s\": %.6f, "
            "\"steps\": %d, \"step_median_us\": %.3f, \"step_min_us\": %.3f, "
            "\"step_max_us\": %.3f, \"per_joint_us\": %.5f, \"peak_rss_kb\": %ld",
            stamp, aqs_version_string(), r->name, (int)r->bodies, (int)r->joints, (int)r->nv,
            (int)r->force_body, r->force[0], r->force[1], r->force[2], r->dt, r->build_s,
            r->finalize_s, (int)r->tree_nodes, (int)r->tree_height, r->mean_handles,
            (int)r->max_handles, r->first_solve_s, (int)r->steps, 1e6 * r->step_median_s,
            1e6 * r->step_min_s, 1e6 * r->step_max_s, 1e6 * r->step_median_s / r->joints,
            r->peak_rss_kb);
    if (r->has_geometry) {
        fprintf(f,
                ", \"backbone\": %d, \"bond_mean\": %.5f, \"bond_sd\": %.5f, "
                "\"angle_mean_deg\": %.3f, \"angle_sd_deg\": %.3f",
                (int)r->backbone, r->bond_mean, r->bond_sd, r->angle_mean_deg, r->angle_sd_deg);
    }
    fprintf(f, "}\n");
    return fclose(f) == 0 ? 0 : 1;
}

/* Fork, run the scene in the child, read its result through a pipe. */
static int run_isolated(enum scene_kind kind, const char *name, int32_t joints,
                        const options *opt, scene_result *r)
{
    int fds[2], status = 0;
    pid_t pid;
    size_t got = 0;
    memset(r, 0, sizeof *r);
    strncpy(r->name, name, sizeof r->name - 1);
    fflush(stdout);
    fflush(stderr);
    if (pipe(fds) != 0) {
        fprintf(stderr, "exact_bench: pipe: %s\n", strerror(errno));
        return 1;
    }
    pid = fork();
    if (pid < 0) {
        fprintf(stderr, "exact_bench: fork: %s\n", strerror(errno));
        close(fds[0]);
        close(fds[1]);
        return 1;
    }
    if (pid == 0) {
        scene_result mine;
        const char *p = (const char *)&mine;
        size_t left = sizeof mine;
        int rc;
        close(fds[0]);
        rc = run_scene(kind, name, joints, opt, &mine);
        if (rc == 0) {
            print_details(&mine);
        }
        while (left > 0) {
            const ssize_t n = write(fds[1], p, left);
            if (n <= 0) {
                break;
            }
            p += n;
            left -= (size_t)n;
        }
        close(fds[1]);
        fflush(stdout);
        _exit(rc);
    }
    close(fds[1]);
    while (got < sizeof *r) {
        const ssize_t n = read(fds[0], (char *)r + got, sizeof *r - got);
        if (n <= 0) {
            break;
        }
        got += (size_t)n;
    }
    close(fds[0]);
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (got != sizeof *r || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || !r->ok) {
        fprintf(stderr, "exact_bench [%s]: the scene failed%s\n", name,
                WIFSIGNALED(status) ? " (killed by a signal)" : "");
        r->ok = 0;
        return 1;
    }
    return 0;
}

static int parse_options(int argc, char **argv, options *opt)
{
    int i;
    opt->joints = 50000;
    opt->budget = 20.0;
    opt->out = "docs/bench/exact.jsonl";
    for (i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--joints") == 0 && i + 1 < argc) {
            opt->joints = (int32_t)atol(argv[++i]);
        } else if (strcmp(argv[i], "--budget") == 0 && i + 1 < argc) {
            opt->budget = atof(argv[++i]);
        } else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
            opt->out = argv[++i];
        } else {
            fprintf(stderr, "usage: %s [--joints N] [--budget SECONDS] [--out PATH]\n", argv[0]);
            return 1;
        }
    }
    if (opt->joints < 2 || !(opt->budget >= 0.0)) {
        fprintf(stderr, "exact_bench: --joints must be >= 2 and --budget >= 0\n");
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    options opt;
    scene_result results[3];
    const char *names[3] = {"chain", "molecule", "millipede"};
    const enum scene_kind kinds[3] = {SCENE_CHAIN, SCENE_MOLECULE, SCENE_MILLIPEDE};
    char stamp[32];
    int i, failures = 0;

    if (parse_options(argc, argv, &opt) != 0) {
        return 2;
    }
    if (aqs_version() != AQS_VERSION_NUMBER) {
        fprintf(stderr, "exact_bench: header version %d but library version %d\n",
                (int)AQS_VERSION_NUMBER, (int)aqs_version());
        return 1;
    }
    bench_utc_stamp(stamp, sizeof stamp);
    printf("aqs %s exact solver benchmark (eps = 0, every joint computed), %s\n",
           aqs_version_string(), stamp);
    printf("loads: gravity off, one 1 N force in a random world direction on a random body; "
           "median of up to %d steps or %.0f s per scene\n\n",
           MAX_STEPS, opt.budget);
    for (i = 0; i < 3; ++i) {
        const int32_t joints = kinds[i] == SCENE_MILLIPEDE ? BENCH_MILLIPEDE_LINKS : opt.joints;
        if (run_isolated(kinds[i], names[i], joints, &opt, &results[i]) != 0) {
            ++failures;
            continue;
        }
        if (results[i].has_geometry && !geometry_ok(&results[i])) {
            fprintf(stderr, "exact_bench [%s]: geometry does not match the specification\n",
                    names[i]);
            ++failures;
        }
        if (append_json(&opt, &results[i], stamp) != 0) {
            ++failures;
        }
    }

    printf("\n%-10s %8s %9s %9s %7s %8s %8s %6s %11s %11s %9s\n", "scene", "joints", "build s",
           "final. s", "height", "handles", "max hdl", "steps", "step ms", "us/joint",
           "peak MB");
    for (i = 0; i < 3; ++i) {
        const scene_result *r = &results[i];
        if (!r->ok) {
            printf("%-10s FAILED\n", names[i]);
            continue;
        }
        printf("%-10s %8d %9.3f %9.3f %7d %8.2f %8d %6d %11.3f %11.4f %9.1f\n", r->name,
               (int)r->joints, r->build_s, r->finalize_s, (int)r->tree_height, r->mean_handles,
               (int)r->max_handles, (int)r->steps, 1e3 * r->step_median_s,
               1e6 * r->step_median_s / r->joints, r->peak_rss_kb / 1024.0);
    }
    printf("\nresults appended to %s\n", opt.out);
    return failures == 0 ? 0 : 1;
}
