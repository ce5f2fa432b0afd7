/*
 * urdf_export.c -- export a scene as URDF together with the exact solve of
 * the C-built linkage under seeded loads, for the round-trip test
 * (tests/python/test_urdf_bench.py loads the URDF with aqs.load_urdf, applies
 * the same loads and compares accelerations).
 *
 *   urdf_export SCENE [JOINTS] OUT.urdf OUT.json
 *
 * SCENE: chain30, chain, molecule (JOINTS: 2000 by default) or millipede.
 * Loads: gravity (0.5, -9.81, 0.25); 3 seeded bodies pulled by a seeded
 * force at a seeded body point plus a seeded torque (world frame); 3 seeded
 * joints (always joint 0, the millipede's free joint) with seeded joint
 * forces. OUT.json: {"scene", "bodies", "joints", "gravity", "body_forces":
 * [{"body", "force", "point", "torque"}], "joint_forces": [{"joint", "tau"}],
 * "qdd"} with every number printed %.17g.
 *
 *   urdf_export --check-errors DIR
 *
 * checks bench_export_urdf's failures instead (exit 0 when all behave): a
 * NULL linkage or path, a file that cannot be opened, and a spherical joint
 * (no URDF equivalent) each give AQS_EINVAL and a message naming the
 * problem, and leave no file behind.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "scenes.h"
#include "urdf.h"

#define LOADS 3

static void put_vec(FILE *f, const double *v, int n)
{
    int i;
    fputc('[', f);
    for (i = 0; i < n; i++) fprintf(f, "%s%.17g", i ? ", " : "", v[i]);
    fputc(']', f);
}

static int failed(aqs_status st, const aqs_linkage *L, const char *what)
{
    if (st == AQS_OK) return 0;
    fprintf(stderr, "urdf_export: %s: %s: %s\n", what, aqs_status_string(st),
            aqs_linkage_last_error(L));
    return 1;
}

static aqs_status build(aqs_linkage *L, const char *scene, int32_t joints)
{
    if (!strcmp(scene, "chain30")) return bench_build_chain30(L);
    if (!strcmp(scene, "chain")) return bench_build_chain(L, joints);
    if (!strcmp(scene, "molecule")) return bench_build_molecule(L, joints, BENCH_MOLECULE_SEED);
    if (!strcmp(scene, "millipede")) return bench_build_millipede(L);
    return AQS_EINVAL;
}

static int expect(int ok, const char *what)
{
    if (!ok) fprintf(stderr, "urdf_export --check-errors: %s\n", what);
    return ok ? 0 : 1;
}

static int check_errors(const char *dir)
{
    const double com[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    char path[1024], message[256];
    aqs_linkage *L = NULL;
    FILE *f;
    int bad = 0;
    snprintf(path, sizeof path, "%s/spherical.urdf", dir);
    if (aqs_linkage_create(&L) != AQS_OK) return 1;
    aqs_body_add(L, 1.0, com, I, NULL);
    aqs_body_add(L, 1.0, com, I, NULL);
    aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL);
    aqs_joint_add(L, AQS_JOINT_SPHERICAL, 0, 1, pos, quat, NULL, NULL);
    message[0] = 0;
    bad += expect(bench_export_urdf(NULL, path, NULL, message, sizeof message) == AQS_EINVAL &&
                      strstr(message, "NULL") != NULL, "NULL linkage not refused");
    bad += expect(bench_export_urdf(L, NULL, NULL, NULL, 0) == AQS_EINVAL, "NULL path not refused");
    message[0] = 0;
    bad += expect(bench_export_urdf(L, "/nonexistent-dir/x.urdf", NULL, message, sizeof message) ==
                          AQS_EINVAL && strstr(message, "/nonexistent-dir/x.urdf") != NULL,
                  "unwritable path not refused by name");
    message[0] = 0;
    bad += expect(bench_export_urdf(L, path, NULL, message, sizeof message) == AQS_EINVAL &&
                      strstr(message, "joint 1 has type 2") != NULL,
                  "spherical joint not refused by index and type");
    f = fopen(path, "r");
    bad += expect(f == NULL, "partial file left behind");
    if (f) fclose(f);
    aqs_linkage_destroy(L);
    return bad ? 1 : 0;
}

int main(int argc, char **argv)
{
    const double gravity[3] = {0.5, -9.81, 0.25};
    const char *scene, *urdf_path, *json_path;
    aqs_linkage *L = NULL;
    bench_rng rng;
    int32_t joints = 2000, bodies = 0, njoints = 0, nv = 0, i;
    double *qdd;
    char message[512];
    FILE *f;
    aqs_status st;
    if (argc == 3 && !strcmp(argv[1], "--check-errors")) return check_errors(argv[2]);
    if (argc != 4 && argc != 5) {
        fprintf(stderr, "usage: urdf_export SCENE [JOINTS] OUT.urdf OUT.json\n");
        return 2;
    }
    scene = argv[1];
    if (argc == 5) joints = (int32_t)atoi(argv[2]);
    urdf_path = argv[argc - 2];
    json_path = argv[argc - 1];
    if (aqs_linkage_create(&L) != AQS_OK) return 1;
    st = build(L, scene, joints);
    if (st == AQS_EINVAL && !*aqs_linkage_last_error(L)) {
        fprintf(stderr, "urdf_export: unknown scene %s or bad size %d\n", scene, (int)joints);
        aqs_linkage_destroy(L);
        return 2;
    }
    if (failed(st, L, "build") || failed(aqs_linkage_finalize(L), L, "finalize")) goto error;
    st = bench_export_urdf(L, urdf_path, scene, message, sizeof message);
    if (st != AQS_OK) {
        fprintf(stderr, "urdf_export: %s\n", message);
        goto error;
    }
    aqs_linkage_get_sizes(L, &bodies, &njoints, NULL, &nv);
    f = fopen(json_path, "w");
    if (!f) {
        fprintf(stderr, "urdf_export: cannot write %s\n", json_path);
        goto error;
    }
    fprintf(f, "{\"scene\": \"%s\", \"bodies\": %d, \"joints\": %d, \"gravity\": ", scene,
            (int)bodies, (int)njoints);
    put_vec(f, gravity, 3);
    if (failed(aqs_linkage_set_gravity(L, gravity), L, "gravity")) goto error_file;
    bench_rng_seed(&rng, 4242);
    fputs(", \"body_forces\": [", f);
    for (i = 0; i < LOADS; i++) {
        const int32_t b = (int32_t)bench_rng_below(&rng, (uint64_t)bodies);
        double force[3], point[3], torque[3];
        int k;
        bench_rng_unit_vector(&rng, force);
        for (k = 0; k < 3; k++) {
            point[k] = bench_rng_normal(&rng, 0.0, 0.5);
            torque[k] = bench_rng_normal(&rng, 0.0, 0.3);
        }
        if (failed(aqs_body_set_force(L, b, force, point, torque), L, "body force"))
            goto error_file;
        fprintf(f, "%s{\"body\": %d, \"force\": ", i ? ", " : "", (int)b);
        put_vec(f, force, 3);
        fputs(", \"point\": ", f);
        put_vec(f, point, 3);
        fputs(", \"torque\": ", f);
        put_vec(f, torque, 3);
        fputc('}', f);
    }
    fputs("], \"joint_forces\": [", f);
    for (i = 0; i < LOADS; i++) {
        const int32_t j = i ? (int32_t)bench_rng_below(&rng, (uint64_t)njoints) : 0;
        double tau[6];
        int32_t n = 0, k;
        aqs_joint_get_layout(L, j, NULL, NULL, NULL, &n);
        for (k = 0; k < n; k++) tau[k] = bench_rng_normal(&rng, 0.0, 0.2);
        if (failed(aqs_joint_set_force(L, j, n ? tau : NULL, n), L, "joint force")) goto error_file;
        fprintf(f, "%s{\"joint\": %d, \"tau\": ", i ? ", " : "", (int)j);
        put_vec(f, tau, (int)n);
        fputc('}', f);
    }
    if (failed(aqs_linkage_solve(L), L, "solve")) goto error_file;
    qdd = malloc(sizeof(double) * ((size_t)nv + 1));
    if (!qdd || failed(aqs_linkage_get_accelerations(L, qdd, (size_t)nv), L, "accelerations")) {
        free(qdd);
        goto error_file;
    }
    fputs("], \"qdd\": ", f);
    put_vec(f, qdd, (int)nv);
    fputs("}\n", f);
    free(qdd);
    if (fclose(f) != 0) goto error;
    aqs_linkage_destroy(L);
    return 0;
error_file:
    fclose(f);
error:
    aqs_linkage_destroy(L);
    return 1;
}
