/*
 * demo.c -- `make demo`: the bicycle chain of the paper pulled at its tip.
 *
 * Builds chain30 (30 unit links, parallel revolute axes, fixed base), turns
 * gravity off, applies a constant world-frame force of (0, 1, 0) N at the far
 * end of the last link and takes 200 exact quasi-static steps. Prints the
 * scene, the tip's path, the joint accelerations of the first solve and the
 * time per step. Any failure prints the library's message and exits 1.
 */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "aqs.h"
#include "scenes.h"
#include "timing.h"

#define DEMO_STEPS 200
#define DEMO_PRINT_EVERY 20
/* dt is chosen so that the fastest joint turns this much in the first step. */
#define DEMO_FIRST_STEP_RAD 0.1

static int failed(aqs_status status, const aqs_linkage *linkage, const char *what)
{
    if (status == AQS_OK) {
        return 0;
    }
    fprintf(stderr, "demo: %s failed: %s (%d): %s\n", what, aqs_status_string(status),
            (int)status, aqs_linkage_last_error(linkage));
    return 1;
}

/* World position of a body-frame point of a body. */
static aqs_status point_world(const aqs_linkage *linkage, int32_t body, const double local[3],
                              double out[3])
{
    double pos[3], q[4];
    const aqs_status st = aqs_body_get_pose_world(linkage, body, pos, q);
    if (st == AQS_OK) {
        const double w = q[0], x = q[1], y = q[2], z = q[3];
        const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                             2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                             2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
        int i;
        for (i = 0; i < 3; ++i) {
            out[i] = pos[i] + r[3 * i] * local[0] + r[3 * i + 1] * local[1] +
                     r[3 * i + 2] * local[2];
        }
    }
    return st;
}

/* The tip of a planar chain with z axes, from its joint angles alone. */
static void tip_from_angles(const double *q, int n, double out[3])
{
    double angle = 0.0;
    int i;
    out[0] = out[1] = out[2] = 0.0;
    for (i = 0; i < n; ++i) {
        angle += q[i];
        out[0] += BENCH_CHAIN30_LINK_LENGTH * cos(angle);
        out[1] += BENCH_CHAIN30_LINK_LENGTH * sin(angle);
    }
}

static int run(aqs_linkage *linkage)
{
    const double zero[3] = {0.0, 0.0, 0.0};
    const double force[3] = {0.0, 1.0, 0.0};
    const double tip_point[3] = {BENCH_CHAIN30_LINK_LENGTH, 0.0, 0.0};
    const int32_t tip = bench_chain30_tip_body();
    const double rad_to_deg = 180.0 / 3.14159265358979323846;
    double qdd[BENCH_CHAIN30_LINKS], q[BENCH_CHAIN30_LINKS];
    double step_seconds[DEMO_STEPS];
    double start[3], tip_end[3], from_angles[3];
    double t0, finalize_seconds, max_qdd = 0.0, dt, worst_mismatch = 0.0;
    double mean_handles = 0.0;
    int32_t bodies = 0, joints = 0, nq = 0, nv = 0, nodes = 0, height = 0, max_handles = 0;
    int i, step;

    if (failed(bench_build_chain30(linkage), linkage, "bench_build_chain30")) {
        return 1;
    }
    t0 = bench_now();
    if (failed(aqs_linkage_finalize(linkage), linkage, "aqs_linkage_finalize")) {
        return 1;
    }
    finalize_seconds = bench_now() - t0;
    if (failed(aqs_linkage_get_sizes(linkage, &bodies, &joints, &nq, &nv), linkage,
               "aqs_linkage_get_sizes") ||
        failed(aqs_linkage_get_tree_stats(linkage, &nodes, &height, &mean_handles, &max_handles),
               linkage, "aqs_linkage_get_tree_stats")) {
        return 1;
    }
    printf("aqs %s -- quasi-statics demo: the bicycle chain (chain30)\n\n", aqs_version_string());
    printf("scene     %d bodies, %d revolute joints (axes all along z), fixed base at the "
           "origin,\n          links of %.1f m along +x, 1 kg each; gravity off\n",
           (int)bodies, (int)joints, BENCH_CHAIN30_LINK_LENGTH);
    printf("sizes     nq = %d, nv = %d\n", (int)nq, (int)nv);
    printf("tree      %d nodes, height %d (log2 %d = %.1f), handles per node: mean %.2f, max %d\n",
           (int)nodes, (int)height, (int)joints, log((double)joints) / log(2.0), mean_handles,
           (int)max_handles);
    printf("finalize  %.1f us\n", 1e6 * finalize_seconds);

    if (failed(aqs_linkage_set_gravity(linkage, zero), linkage, "aqs_linkage_set_gravity") ||
        failed(aqs_body_set_force(linkage, tip, force, tip_point, NULL), linkage,
               "aqs_body_set_force") ||
        failed(aqs_linkage_solve(linkage), linkage, "aqs_linkage_solve") ||
        failed(aqs_linkage_get_accelerations(linkage, qdd, BENCH_CHAIN30_LINKS), linkage,
               "aqs_linkage_get_accelerations") ||
        failed(point_world(linkage, tip, tip_point, start), linkage, "aqs_body_get_pose_world")) {
        return 1;
    }
    printf("load      force (%.0f, %.0f, %.0f) N, world frame, at the far end of link %d\n\n",
           force[0], force[1], force[2], (int)tip);

    printf("joint accelerations of the first solve, rad/s^2 (joint 0 at the base):\n");
    for (i = 0; i < BENCH_CHAIN30_LINKS; ++i) {
        if (!isfinite(qdd[i])) {
            fprintf(stderr, "demo: joint %d acceleration is not finite\n", i);
            return 1;
        }
        if (fabs(qdd[i]) > max_qdd) {
            max_qdd = fabs(qdd[i]);
        }
        printf("%s%+10.3e", i % 6 == 0 ? "  " : " ", qdd[i]);
        if (i % 6 == 5 || i == BENCH_CHAIN30_LINKS - 1) {
            printf("   (%d-%d)\n", i - i % 6, i);
        }
    }
    if (!(max_qdd > 0.0)) {
        fprintf(stderr, "demo: the force produced no acceleration\n");
        return 1;
    }
    dt = sqrt(DEMO_FIRST_STEP_RAD / max_qdd);
    printf("\ndt = %.4g s: the fastest joint moves %.2f rad in the first step "
           "(q <- q + dt^2 qdd)\n\n",
           dt, DEMO_FIRST_STEP_RAD);

    printf(" step   tip end x   tip end y   tip end z   moved   bent   q29 (tip)\n");
    printf("                 m           m           m       m  > 1 deg       deg\n");
    for (step = 0; step <= DEMO_STEPS; ++step) {
        if (step > 0) {
            const double s0 = bench_now();
            if (failed(aqs_linkage_step(linkage, dt), linkage, "aqs_linkage_step")) {
                return 1;
            }
            step_seconds[step - 1] = bench_now() - s0;
        }
        if (step % DEMO_PRINT_EVERY == 0) {
            double moved;
            int bent = 0;
            if (failed(point_world(linkage, tip, tip_point, tip_end), linkage,
                       "aqs_body_get_pose_world") ||
                failed(aqs_linkage_get_positions(linkage, q, BENCH_CHAIN30_LINKS), linkage,
                       "aqs_linkage_get_positions")) {
                return 1;
            }
            moved = sqrt((tip_end[0] - start[0]) * (tip_end[0] - start[0]) +
                         (tip_end[1] - start[1]) * (tip_end[1] - start[1]) +
                         (tip_end[2] - start[2]) * (tip_end[2] - start[2]));
            for (i = 0; i < BENCH_CHAIN30_LINKS; ++i) {
                bent += fabs(q[i]) * rad_to_deg > 1.0;
            }
            printf("%5d  %10.4f  %10.4f  %10.4f  %6.3f  %7d  %9.3f\n", step, tip_end[0],
                   tip_end[1], tip_end[2], moved, bent, q[BENCH_CHAIN30_LINKS - 1] * rad_to_deg);
            /* The poses must agree with planar kinematics of the angles. */
            tip_from_angles(q, BENCH_CHAIN30_LINKS, from_angles);
            for (i = 0; i < 3; ++i) {
                const double d = fabs(from_angles[i] - tip_end[i]);
                worst_mismatch = d > worst_mismatch ? d : worst_mismatch;
            }
        }
    }
    printf("\ncheck     tip from aqs_body_get_pose_world vs planar kinematics of q: "
           "max difference %.1e m\n",
           worst_mismatch);
    {
        const double median = bench_median(step_seconds, DEMO_STEPS);
        printf("time      %d steps, median %.2f us per step (%.3f us per joint), fastest %.2f us\n",
               DEMO_STEPS, 1e6 * median, 1e6 * median / (double)joints, 1e6 * step_seconds[0]);
    }
    if (worst_mismatch > 1e-9) {
        fprintf(stderr, "demo: world poses disagree with the joint angles by %.3e m\n",
                worst_mismatch);
        return 1;
    }
    return 0;
}

int main(void)
{
    aqs_linkage *linkage = NULL;
    int rc;
    const aqs_status st = aqs_linkage_create(&linkage);
    if (st != AQS_OK) {
        fprintf(stderr, "demo: aqs_linkage_create failed: %s (%d)\n", aqs_status_string(st),
                (int)st);
        return 1;
    }
    if (aqs_version() != AQS_VERSION_NUMBER) {
        fprintf(stderr, "demo: header version %d but library version %d\n",
                (int)AQS_VERSION_NUMBER, (int)aqs_version());
        aqs_linkage_destroy(linkage);
        return 1;
    }
    rc = run(linkage);
    aqs_linkage_destroy(linkage);
    return rc;
}
