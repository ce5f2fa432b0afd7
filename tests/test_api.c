/* test_api.c -- src/api/api.c: the error paths of every public function.
 * NULL linkage and NULL pointers (AQS_EINVAL), bad indices (AQS_ERANGE),
 * NaN and +-Inf in every double argument (AQS_EINVAL), wrong phase
 * (AQS_ESTATE), wrong sizes (AQS_ESIZE / AQS_EINVAL as documented),
 * non-finite results (AQS_ENUMERIC). After every failed call the linkage is
 * exactly as it was: its outputs are unchanged bit for bit, a new solve
 * recomputes nothing and gives the same bits, and a full recomputation from
 * its inputs gives the same bits too (which catches a failed call that
 * wrote an input without marking it). Also: status strings, versions, and
 * last_error naming the function and the argument. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The reference linkage: every joint type, a floating base, a welded body.
 *   j0 free      world -> b0        j4 planar      b3 -> b4
 *   j1 revolute  b0 -> b1           j5 universal   b4 -> b5
 *   j2 spherical b1 -> b2           j6 prismatic   b2 -> b6
 *   j3 fixed     b0 -> b3           j7 cylindrical b6 -> b7 */
#define NB 8
#define NJ 8
#define NQ 20
#define NV 18

static const double zero3[3] = {0, 0, 0}, unit_quat[4] = {1, 0, 0, 0}, zaxis[3] = {0, 0, 1};
static const double bad_values[3] = {NAN, INFINITY, -INFINITY};

/* Positions whose quaternions are exactly unit in floating point (entries
 * +-0.5), so that storing them again is the identity, bit for bit. */
static const double ref_q[NQ] = {0.3, -0.2, 0.1, 0.5, 0.5, -0.5, 0.5, /* j0 free */
                                 0.4,                                /* j1 */
                                 0.5, -0.5, 0.5, 0.5,                /* j2 */
                                 0.1, -0.3, 0.7,                     /* j4 */
                                 -0.6, 0.2,                          /* j5 */
                                 0.25,                               /* j6 */
                                 1.1, -0.15};                        /* j7 */

static void build(aqs_linkage *L)
{
    static const int32_t type[NJ] = {AQS_JOINT_FREE,   AQS_JOINT_REVOLUTE,  AQS_JOINT_SPHERICAL,
                                     AQS_JOINT_FIXED,  AQS_JOINT_PLANAR,    AQS_JOINT_UNIVERSAL,
                                     AQS_JOINT_PRISMATIC, AQS_JOINT_CYLINDRICAL};
    static const int32_t parent[NJ] = {AQS_WORLD, 0, 1, 0, 3, 4, 2, 6};
    int32_t i;
    for (i = 0; i < NB; i++) {
        double com[3] = {0.1 * i, 0.2, -0.1}, I[9] = {0.3, 0.01, 0, 0.01, 0.2, 0, 0, 0, 0.25};
        int32_t b = -1;
        assert_int_equal(aqs_body_add(L, 1.0 + 0.25 * i, com, I, &b), AQS_OK);
        assert_int_equal(b, i);
    }
    for (i = 0; i < NJ; i++) {
        double pos[3] = {0.5, 0.1 * i, 0}, axis[3] = {0.2 * i, 1, 0.5};
        int32_t j = -1;
        assert_int_equal(aqs_joint_add(L, type[i], parent[i], i, pos, unit_quat, axis, &j), AQS_OK);
        assert_int_equal(j, i);
    }
}

/* Loads of the reference state: gravity, two body loads, two joint forces. */
static void set_loads(aqs_linkage *L)
{
    double g[3] = {0.1, -9.81, 0.3}, F[3] = {1, -2, 0.5}, P[3] = {0.1, 0, 0.2}, T[3] = {0.3, 0.1, -0.2};
    double tau1 = 0.7, tau4[3] = {0.1, -0.2, 0.05};
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, 2, F, P, T), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, 5, T, NULL, F), AQS_OK);
    assert_int_equal(aqs_joint_set_force(L, 1, &tau1, 1), AQS_OK);
    assert_int_equal(aqs_joint_set_force(L, 4, tau4, 3), AQS_OK);
}

typedef struct {
    double q[NQ], qdd[NV], f[6 * NJ], poses[7 * NB];
} snapshot;

static void take(const aqs_linkage *L, snapshot *s)
{
    assert_int_equal(aqs_linkage_get_positions(L, s->q, NQ), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, s->qdd, NV), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, s->f, 6 * NJ), AQS_OK);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, s->poses, 7 * NB), AQS_OK);
}

static void assert_same(const snapshot *a, const snapshot *b)
{
    assert_memory_equal(a->q, b->q, sizeof a->q);
    assert_memory_equal(a->qdd, b->qdd, sizeof a->qdd);
    assert_memory_equal(a->f, b->f, sizeof a->f);
    assert_memory_equal(a->poses, b->poses, sizeof a->poses);
}

/* A finalized, solved linkage in the reference state, and its snapshot. */
static aqs_linkage *reference(snapshot *ref)
{
    aqs_linkage *L = test_new_linkage();
    build(L);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    set_loads(L);
    assert_int_equal(aqs_linkage_set_positions(L, ref_q, NQ), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    take(L, ref);
    assert_memory_equal(ref->q, ref_q, sizeof ref_q);
    return L;
}

/* The linkage is exactly as in ref (see the file comment). */
static void assert_unchanged(aqs_linkage *L, const snapshot *ref)
{
    snapshot now;
    aqs_solve_stats st;
    /* nothing invalidated the last solve */
    assert_int_equal(aqs_linkage_refine(L, 0.0), AQS_OK);
    take(L, &now);
    assert_same(&now, ref);
    /* nothing is stale: a solve recomputes no node, and gives the same */
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_int_equal(st.nodes_updated, 0);
    take(L, &now);
    assert_same(&now, ref);
    /* and from scratch: the stored inputs are those of the reference */
    assert_int_equal(aqs_linkage_set_positions(L, ref_q, NQ), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    take(L, &now);
    assert_same(&now, ref);
}

/* A call that must fail with status, naming fn and text in last_error,
 * and leave the linkage unchanged. */
#define FAILS(L, ref, call, status, fn, text)                                                       \
    do {                                                                                           \
        assert_int_equal((call), (status));                                                        \
        test_assert_contains(aqs_linkage_last_error(L), (fn));                                     \
        test_assert_contains(aqs_linkage_last_error(L), (text));                                   \
        assert_unchanged((L), (ref));                                                              \
    } while (0)

/* ------------------------------------------------------ statics, version */

static void test_status_and_version(void **state)
{
    static const aqs_status codes[] = {AQS_OK, AQS_EINVAL, AQS_ERANGE, AQS_ESTATE,
                                       AQS_ENOMEM, AQS_EMODEL, AQS_ENUMERIC, AQS_ESIZE};
    static const aqs_status unknown[] = {1, -8, 7, 100, -1000, INT32_MAX, INT32_MIN};
    char expect[32];
    size_t i, j;
    (void)state;
    /* the fixed values of the header */
    assert_int_equal(AQS_OK, 0);
    assert_int_equal(AQS_EINVAL, -1);
    assert_int_equal(AQS_ERANGE, -2);
    assert_int_equal(AQS_ESTATE, -3);
    assert_int_equal(AQS_ENOMEM, -4);
    assert_int_equal(AQS_EMODEL, -5);
    assert_int_equal(AQS_ENUMERIC, -6);
    assert_int_equal(AQS_ESIZE, -7);
    for (i = 0; i < sizeof codes / sizeof codes[0]; i++) {
        const char *s = aqs_status_string(codes[i]);
        assert_non_null(s);
        assert_true(strlen(s) > 0);
        assert_string_not_equal(s, "unknown status");
        assert_ptr_equal(s, aqs_status_string(codes[i])); /* static text */
        for (j = 0; j < i; j++) assert_string_not_equal(s, aqs_status_string(codes[j]));
    }
    for (i = 0; i < sizeof unknown / sizeof unknown[0]; i++)
        assert_string_equal(aqs_status_string(unknown[i]), "unknown status");
    assert_int_equal(aqs_version(), AQS_VERSION_NUMBER);
    assert_int_equal(AQS_VERSION_NUMBER, AQS_VERSION_MAJOR * 10000 + AQS_VERSION_MINOR * 100 + AQS_VERSION_PATCH);
    snprintf(expect, sizeof expect, "%d.%d.%d", AQS_VERSION_MAJOR, AQS_VERSION_MINOR, AQS_VERSION_PATCH);
    assert_string_equal(aqs_version_string(), expect);
}

/* Every function with a NULL linkage: AQS_EINVAL, no crash. */
static void test_null_linkage(void **state)
{
    double v[64] = {0}, q4[4] = {1, 0, 0, 0};
    int32_t i32 = 0;
    int k;
    aqs_solve_stats st;
    const char *msg = aqs_linkage_last_error(NULL);
    (void)state;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    assert_non_null(msg);
    assert_true(strlen(msg) > 0);
    aqs_linkage_destroy(NULL); /* accepted */
    assert_int_equal(aqs_linkage_create(NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_inertia_check(NULL, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_tree_builder(NULL, AQS_TREE_BISECTION), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_tree_builder(NULL, 99), AQS_EINVAL);
    assert_int_equal(aqs_body_add(NULL, 1, v, v, NULL), AQS_EINVAL);
    assert_int_equal(aqs_joint_add(NULL, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, v, q4, zaxis, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_finalize(NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_sizes(NULL, &i32, &i32, &i32, &i32), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_layout(NULL, 0, &i32, &i32, &i32, &i32), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_tree_stats(NULL, &i32, &i32, v, &i32), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_gravity(NULL, v), AQS_EINVAL);
    assert_int_equal(aqs_body_set_force(NULL, 0, v, NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_body_clear_force(NULL, 0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_clear_forces(NULL), AQS_EINVAL);
    assert_int_equal(aqs_joint_set_force(NULL, 0, v, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_solve(NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_step(NULL, 0.1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_tolerance(NULL, AQS_METRIC_ABS_LINKAGE, 0.1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_max_computed(NULL, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_refine(NULL, 0.1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_stats(NULL, &st), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_computed(NULL, 0, &i32), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_positions(NULL, v, 64), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_positions(NULL, v, 0), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_position(NULL, 0, v, 1), AQS_EINVAL);
    assert_int_equal(aqs_joint_set_position(NULL, 0, v, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_accelerations(NULL, v, 64), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_acceleration(NULL, 0, v, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_constraint_forces(NULL, v, 64), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_constraint_force(NULL, 0, v), AQS_EINVAL);
    assert_int_equal(aqs_body_get_pose_world(NULL, 0, v, v + 3), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_body_poses_world(NULL, v, 64), AQS_EINVAL);
    /* nothing was written through the out pointers */
    assert_int_equal(i32, 0);
    for (k = 0; k < 64; k++) assert_true(v[k] == 0.0);
    /* without a linkage there is nowhere to keep a message: the fixed text
     * names the argument */
    assert_string_equal(aqs_linkage_last_error(NULL), msg);
    test_assert_contains(msg, "linkage is NULL");
}

static void *plain_alloc(void *user, size_t size)
{
    (void)user;
    return malloc(size);
}

static void plain_free(void *user, void *p)
{
    (void)user;
    free(p);
}

static void test_create(void **state)
{
    aqs_linkage *L = (aqs_linkage *)&L; /* a non-NULL value that must not be kept */
    int32_t nb = -1, nj = -1, nq = -1, nv = -1;
    (void)state;
    assert_int_equal(aqs_linkage_create_with_allocator(NULL, plain_free, NULL, &L), AQS_EINVAL);
    assert_int_equal(aqs_linkage_create_with_allocator(plain_alloc, NULL, NULL, &L), AQS_EINVAL);
    assert_int_equal(aqs_linkage_create_with_allocator(plain_alloc, plain_free, NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_create_with_allocator(plain_alloc, plain_free, NULL, &L), AQS_OK);
    assert_non_null(L);
    assert_string_equal(aqs_linkage_last_error(L), ""); /* no failure yet */
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, &nq, &nv), AQS_OK);
    assert_true(nb == 0 && nj == 0 && nq == 0 && nv == 0);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, NULL, NULL), AQS_OK); /* NULL outs */
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------------ building */

/* Build the reference model while, before each successful add, calling
 * the adds with every kind of bad argument; each must fail, name the
 * function and the argument, and add nothing. */
static void build_with_failures(aqs_linkage *L)
{
    static const char bf[] = "aqs_body_add", jf[] = "aqs_joint_add";
    double com[3] = {0, 0.2, -0.1}, I[9] = {0.3, 0.01, 0, 0.01, 0.2, 0, 0, 0, 0.25};
    double pos[3] = {0.5, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 1, 0.5};
    int32_t nb, nj, k, out = 12345;
    size_t v;
    for (v = 0; v < 3; v++) {
        double x = bad_values[v];
        char text[32];
        assert_int_equal(aqs_body_add(L, x, com, I, &out), AQS_EINVAL);
        test_assert_contains(aqs_linkage_last_error(L), bf);
        test_assert_contains(aqs_linkage_last_error(L), "mass");
        for (k = 0; k < 3; k++) {
            double c[3];
            memcpy(c, com, sizeof c);
            c[k] = x;
            assert_int_equal(aqs_body_add(L, 1.0, c, I, &out), AQS_EINVAL);
            snprintf(text, sizeof text, "com[%d]", (int)k);
            test_assert_contains(aqs_linkage_last_error(L), text);
        }
        for (k = 0; k < 9; k++) {
            double J[9];
            memcpy(J, I, sizeof J);
            J[k] = x;
            assert_int_equal(aqs_body_add(L, 1.0, com, J, &out), AQS_EINVAL);
            snprintf(text, sizeof text, "inertia[%d]", (int)k);
            test_assert_contains(aqs_linkage_last_error(L), text);
        }
    }
    assert_int_equal(aqs_body_add(L, 1.0, NULL, I, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "com is NULL");
    assert_int_equal(aqs_body_add(L, 1.0, com, NULL, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "inertia is NULL");
    assert_int_equal(out, 12345); /* out_body untouched on failure */
    assert_int_equal(aqs_linkage_set_inertia_check(L, -1), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_set_inertia_check");
    test_assert_contains(aqs_linkage_last_error(L), "physical = -1");
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, NULL, NULL), AQS_OK);
    assert_true(nb == 0 && nj == 0);

    build(L); /* the real model, then bad joints on top of it */

    for (v = 0; v < 3; v++) {
        double x = bad_values[v];
        char text[32];
        for (k = 0; k < 3; k++) {
            double p[3];
            memcpy(p, pos, sizeof p);
            p[k] = x;
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 1, p, quat, axis, &out), AQS_EINVAL);
            snprintf(text, sizeof text, "pos[%d]", (int)k);
            test_assert_contains(aqs_linkage_last_error(L), jf);
            test_assert_contains(aqs_linkage_last_error(L), text);
        }
        for (k = 0; k < 4; k++) {
            double qq[4];
            memcpy(qq, quat, sizeof qq);
            qq[k] = x;
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, pos, qq, NULL, &out), AQS_EINVAL);
            snprintf(text, sizeof text, "quat[%d]", (int)k);
            test_assert_contains(aqs_linkage_last_error(L), text);
        }
        for (k = 0; k < 3; k++) {
            double a[3];
            memcpy(a, axis, sizeof a);
            a[k] = x;
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_PRISMATIC, 0, 1, pos, quat, a, &out), AQS_EINVAL);
            snprintf(text, sizeof text, "axis[%d]", (int)k);
            test_assert_contains(aqs_linkage_last_error(L), text);
        }
    }
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 1, NULL, quat, axis, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "pos is NULL");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 1, pos, NULL, axis, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "quat is NULL");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 1, pos, quat, NULL, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "axis is NULL");
    /* indices */
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, NB, 1, pos, quat, axis, &out), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "parent = 8");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, -2, 1, pos, quat, axis, &out), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "parent = -2");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, NB, pos, quat, axis, &out), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "child = 8");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, -1, pos, quat, axis, &out), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "child = -1");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, INT32_MIN, INT32_MAX, pos, quat, axis, &out), AQS_ERANGE);
    assert_int_equal(aqs_joint_add(L, 99, 0, 1, pos, quat, axis, &out), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "type = 99");
    assert_int_equal(out, 12345);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, NULL, NULL), AQS_OK);
    assert_true(nb == NB && nj == NJ);
}

/* The building-phase failures change nothing: the linkage built among them
 * solves to the same bits as the clean one. Loads, positions, gravity set
 * before finalize persist (any phase) and give the same bits as when set
 * after it. */
static void test_building_failures(void **state)
{
    snapshot ref, now;
    aqs_linkage *R = reference(&ref), *L = test_new_linkage();
    (void)state;
    build_with_failures(L);
    set_loads(L); /* before finalize this time */
    assert_int_equal(aqs_linkage_set_positions(L, ref_q, NQ), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    take(L, &now);
    assert_same(&now, &ref);
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(R);
}

/* ----------------------------------------------------------- phases */

static void test_phases(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double v[64], q4[4] = {1, 0, 0, 0}, com[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    int32_t i32;
    aqs_solve_stats st;
    snapshot ref;
    (void)state;
    memset(&st, 0, sizeof st);
    st.size = sizeof st;
    build(L);
    /* before finalize: solving, reading results, world poses, tree stats
     * and the adaptive controls are phase errors naming the function */
#define NOT_FINALIZED(call, fn)                                                                    \
    do {                                                                                           \
        assert_int_equal((call), AQS_ESTATE);                                                      \
        test_assert_contains(aqs_linkage_last_error(L), fn);                                       \
        test_assert_contains(aqs_linkage_last_error(L), "not finalized");                          \
    } while (0)
    NOT_FINALIZED(aqs_linkage_solve(L), "aqs_linkage_solve");
    NOT_FINALIZED(aqs_linkage_step(L, 0.01), "aqs_linkage_step");
    NOT_FINALIZED(aqs_linkage_get_tree_stats(L, &i32, &i32, v, &i32), "aqs_linkage_get_tree_stats");
    NOT_FINALIZED(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_LINKAGE, 0.1), "aqs_linkage_set_tolerance");
    NOT_FINALIZED(aqs_linkage_set_max_computed(L, 3), "aqs_linkage_set_max_computed");
    NOT_FINALIZED(aqs_linkage_refine(L, 0.1), "aqs_linkage_refine");
    NOT_FINALIZED(aqs_linkage_get_stats(L, &st), "aqs_linkage_get_stats");
    NOT_FINALIZED(aqs_joint_get_computed(L, 0, &i32), "aqs_joint_get_computed");
    NOT_FINALIZED(aqs_linkage_get_accelerations(L, v, 64), "aqs_linkage_get_accelerations");
    NOT_FINALIZED(aqs_joint_get_acceleration(L, 1, v, 1), "aqs_joint_get_acceleration");
    NOT_FINALIZED(aqs_linkage_get_constraint_forces(L, v, 64), "aqs_linkage_get_constraint_forces");
    NOT_FINALIZED(aqs_joint_get_constraint_force(L, 1, v), "aqs_joint_get_constraint_force");
    NOT_FINALIZED(aqs_body_get_pose_world(L, 0, v, v + 3), "aqs_body_get_pose_world");
    NOT_FINALIZED(aqs_linkage_get_body_poses_world(L, v, 64), "aqs_linkage_get_body_poses_world");
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    /* finalized, not solved: the results are phase errors */
#define NOT_SOLVED(call, fn)                                                                       \
    do {                                                                                           \
        assert_int_equal((call), AQS_ESTATE);                                                      \
        test_assert_contains(aqs_linkage_last_error(L), fn);                                       \
        test_assert_contains(aqs_linkage_last_error(L), "nothing solved");                         \
    } while (0)
    NOT_SOLVED(aqs_linkage_get_accelerations(L, v, 64), "aqs_linkage_get_accelerations");
    NOT_SOLVED(aqs_joint_get_acceleration(L, 1, v, 1), "aqs_joint_get_acceleration");
    NOT_SOLVED(aqs_linkage_get_constraint_forces(L, v, 64), "aqs_linkage_get_constraint_forces");
    NOT_SOLVED(aqs_joint_get_constraint_force(L, 1, v), "aqs_joint_get_constraint_force");
    NOT_SOLVED(aqs_linkage_get_stats(L, &st), "aqs_linkage_get_stats");
    NOT_SOLVED(aqs_joint_get_computed(L, 1, &i32), "aqs_joint_get_computed");
    NOT_SOLVED(aqs_linkage_refine(L, 0.1), "aqs_linkage_refine");
    /* world poses and tree statistics need only finalize */
    assert_int_equal(aqs_body_get_pose_world(L, 0, v, v + 3), AQS_OK);
    assert_int_equal(aqs_linkage_get_tree_stats(L, &i32, NULL, NULL, NULL), AQS_OK);
    aqs_linkage_destroy(L);

    /* after finalize (and solve): building is a phase error that changes
     * nothing */
    L = reference(&ref);
#define FINALIZED(call, fn) FAILS(L, &ref, call, AQS_ESTATE, fn, "finalized")
    FINALIZED(aqs_body_add(L, 1.0, com, I, NULL), "aqs_body_add");
    FINALIZED(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 1, com, q4, zaxis, NULL), "aqs_joint_add");
    FINALIZED(aqs_linkage_set_inertia_check(L, 0), "aqs_linkage_set_inertia_check");
    FINALIZED(aqs_linkage_finalize(L), "aqs_linkage_finalize");
    /* a change of positions invalidates refine (documented), not reading */
    assert_int_equal(aqs_linkage_set_positions(L, ref_q, NQ), AQS_OK);
    assert_int_equal(aqs_linkage_refine(L, 0.0), AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_refine");
    assert_int_equal(aqs_linkage_get_accelerations(L, v, 64), AQS_OK);
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------- tree builder */

typedef struct {
    int32_t nodes, height, max_handles;
    double mean_handles;
} tree_shape;

/* A 12-body revolute chain, all joints but the last (joint 11, body 11 to
 * its parent) unless complete. On this chain the two builders give
 * different trees (mean handles 1.60 for contraction, 1.64 for bisection),
 * so the shape of the tree tells which builder was in force. */
static aqs_linkage *chain12(int complete)
{
    aqs_linkage *L = test_new_linkage();
    int32_t i;
    for (i = 0; i < 12; i++) test_add_body(L, 1.0, 0.2, 0, 0, 0.1);
    for (i = 0; i < (complete ? 12 : 11); i++) test_add_joint(L, AQS_JOINT_REVOLUTE, i - 1, i, 0.5, 0, 0, 0, 0, 1);
    return L;
}

static void finalize_shape(aqs_linkage *L, tree_shape *t)
{
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_tree_stats(L, &t->nodes, &t->height, &t->mean_handles, &t->max_handles), AQS_OK);
}

static void assert_same_shape(const tree_shape *a, const tree_shape *b)
{
    assert_int_equal(a->nodes, b->nodes);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->max_handles, b->max_handles);
    assert_true(a->mean_handles == b->mean_handles);
}

/* aqs_linkage_set_tree_builder: a value that is not AQS_TREE_* is
 * AQS_EINVAL naming the function and the value, and the builder in force
 * (default or set) stays; a NULL linkage is AQS_EINVAL; after finalize
 * every value is AQS_ESTATE (the phase is checked first) and the linkage is
 * unchanged; after a failed finalize the linkage is still editable. */
static void test_tree_builder_errors(void **state)
{
    static const char fn[] = "aqs_linkage_set_tree_builder";
    static const int32_t bad[] = {2, -1, 99, INT32_MAX, INT32_MIN};
    static const int32_t first[] = {-100, AQS_TREE_CONTRACTION, AQS_TREE_BISECTION}; /* -100: none */
    tree_shape contraction, bisection, t;
    snapshot ref;
    aqs_linkage *L;
    size_t i, k;
    (void)state;
    /* the references: default and bisection differ on this chain */
    L = chain12(1);
    finalize_shape(L, &contraction);
    aqs_linkage_destroy(L);
    L = chain12(1);
    assert_int_equal(aqs_linkage_set_tree_builder(L, AQS_TREE_BISECTION), AQS_OK);
    finalize_shape(L, &bisection);
    aqs_linkage_destroy(L);
    assert_true(contraction.mean_handles != bisection.mean_handles);
    L = chain12(1);
    assert_int_equal(aqs_linkage_set_tree_builder(L, AQS_TREE_CONTRACTION), AQS_OK);
    finalize_shape(L, &t);
    assert_same_shape(&t, &contraction);
    aqs_linkage_destroy(L);
    /* bad values, after no setting, contraction or bisection */
    for (i = 0; i < sizeof first / sizeof first[0]; i++) {
        L = chain12(1);
        if (first[i] >= 0) assert_int_equal(aqs_linkage_set_tree_builder(L, first[i]), AQS_OK);
        for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
            char text[48];
            assert_int_equal(aqs_linkage_set_tree_builder(L, bad[k]), AQS_EINVAL);
            snprintf(text, sizeof text, "builder = %d", (int)bad[k]);
            test_assert_contains(aqs_linkage_last_error(L), fn);
            test_assert_contains(aqs_linkage_last_error(L), text);
            test_assert_contains(aqs_linkage_last_error(L), "AQS_TREE_");
        }
        finalize_shape(L, &t);
        assert_same_shape(&t, first[i] == AQS_TREE_BISECTION ? &bisection : &contraction);
        aqs_linkage_destroy(L);
    }
    /* a failed finalize leaves the linkage editable: the builder can still be set */
    L = chain12(0);
    assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
    assert_int_equal(aqs_linkage_set_tree_builder(L, AQS_TREE_BISECTION), AQS_OK);
    test_add_joint(L, AQS_JOINT_REVOLUTE, 10, 11, 0.5, 0, 0, 0, 0, 1);
    finalize_shape(L, &t);
    assert_same_shape(&t, &bisection);
    /* after finalize: a phase error for every value (also a bad one: the
     * phase is checked first), and the tree is kept */
    for (k = 0; k < 3; k++) {
        static const int32_t late[3] = {AQS_TREE_CONTRACTION, AQS_TREE_BISECTION, 7};
        assert_int_equal(aqs_linkage_set_tree_builder(L, late[k]), AQS_ESTATE);
        test_assert_contains(aqs_linkage_last_error(L), fn);
        test_assert_contains(aqs_linkage_last_error(L), "finalized");
        assert_int_equal(aqs_linkage_get_tree_stats(L, &t.nodes, &t.height, &t.mean_handles, &t.max_handles), AQS_OK);
        assert_same_shape(&t, &bisection);
    }
    aqs_linkage_destroy(L);
    /* and on the reference linkage: nothing else changes either */
    L = reference(&ref);
    FAILS(L, &ref, aqs_linkage_set_tree_builder(L, AQS_TREE_CONTRACTION), AQS_ESTATE, fn, "finalized");
    FAILS(L, &ref, aqs_linkage_set_tree_builder(L, AQS_TREE_BISECTION), AQS_ESTATE, fn, "finalized");
    FAILS(L, &ref, aqs_linkage_set_tree_builder(L, -1), AQS_ESTATE, fn, "finalized");
    aqs_linkage_destroy(L);
    /* NULL linkage */
    assert_int_equal(aqs_linkage_set_tree_builder(NULL, AQS_TREE_BISECTION), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_tree_builder(NULL, 2), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(NULL), "linkage is NULL");
}

/* -------------------------------------------- loads and joint forces */

static void test_load_errors(void **state)
{
    snapshot ref;
    aqs_linkage *L = reference(&ref);
    static const char sf[] = "aqs_body_set_force", jf[] = "aqs_joint_set_force";
    double F[3] = {1, 2, 3}, P[3] = {0.1, 0.2, 0.3}, T[3] = {-1, 0, 1}, tau[6] = {1, 2, 3, 4, 5, 6};
    size_t v;
    int k;
    (void)state;
    for (v = 0; v < 3; v++) {
        double x = bad_values[v];
        char text[32];
        for (k = 0; k < 3; k++) {
            double g[3] = {0, -9.81, 0}, a[3], b[3], c[3];
            g[k] = x;
            snprintf(text, sizeof text, "gravity[%d]", k);
            FAILS(L, &ref, aqs_linkage_set_gravity(L, g), AQS_EINVAL, "aqs_linkage_set_gravity", text);
            memcpy(a, F, sizeof a);
            memcpy(b, P, sizeof b);
            memcpy(c, T, sizeof c);
            a[k] = x;
            snprintf(text, sizeof text, "force[%d]", k);
            /* body 2 already has a load, body 7 has none: neither changes */
            FAILS(L, &ref, aqs_body_set_force(L, 2, a, P, T), AQS_EINVAL, sf, text);
            FAILS(L, &ref, aqs_body_set_force(L, 7, a, P, T), AQS_EINVAL, sf, text);
            b[k] = x;
            snprintf(text, sizeof text, "point[%d]", k);
            FAILS(L, &ref, aqs_body_set_force(L, 2, F, b, T), AQS_EINVAL, sf, text);
            b[k] = P[k];
            c[k] = x;
            snprintf(text, sizeof text, "torque[%d]", k);
            FAILS(L, &ref, aqs_body_set_force(L, 5, F, P, c), AQS_EINVAL, sf, text);
            FAILS(L, &ref, aqs_body_set_force(L, 7, F, NULL, c), AQS_EINVAL, sf, text);
        }
        /* every value of a joint force, on joints of 1, 3 and 6 dofs */
        for (k = 0; k < 6; k++) {
            double t[6];
            memcpy(t, tau, sizeof t);
            t[k] = x;
            snprintf(text, sizeof text, "tau[%d]", k);
            FAILS(L, &ref, aqs_joint_set_force(L, 0, t, 6), AQS_EINVAL, jf, text);
            if (k < 3) FAILS(L, &ref, aqs_joint_set_force(L, 4, t, 3), AQS_EINVAL, jf, text);
            if (k < 1) FAILS(L, &ref, aqs_joint_set_force(L, 1, t, 1), AQS_EINVAL, jf, text);
        }
    }
    FAILS(L, &ref, aqs_linkage_set_gravity(L, NULL), AQS_EINVAL, "aqs_linkage_set_gravity", "gravity is NULL");
    FAILS(L, &ref, aqs_body_set_force(L, 2, NULL, P, T), AQS_EINVAL, sf, "force is NULL");
    FAILS(L, &ref, aqs_body_set_force(L, -1, F, P, T), AQS_ERANGE, sf, "body = -1");
    FAILS(L, &ref, aqs_body_set_force(L, NB, F, P, T), AQS_ERANGE, sf, "body = 8");
    FAILS(L, &ref, aqs_body_set_force(L, INT32_MIN, F, P, T), AQS_ERANGE, sf, "body = -2147483648");
    FAILS(L, &ref, aqs_body_clear_force(L, -1), AQS_ERANGE, "aqs_body_clear_force", "body = -1");
    FAILS(L, &ref, aqs_body_clear_force(L, NB), AQS_ERANGE, "aqs_body_clear_force", "body = 8");
    FAILS(L, &ref, aqs_joint_set_force(L, -1, tau, 1), AQS_ERANGE, jf, "joint = -1");
    FAILS(L, &ref, aqs_joint_set_force(L, NJ, tau, 1), AQS_ERANGE, jf, "joint = 8");
    /* n must equal the joint's nv (documented AQS_EINVAL) */
    FAILS(L, &ref, aqs_joint_set_force(L, 1, tau, 2), AQS_ESIZE, jf, "n = 2");
    FAILS(L, &ref, aqs_joint_set_force(L, 1, tau, 0), AQS_ESIZE, jf, "n = 0");
    FAILS(L, &ref, aqs_joint_set_force(L, 0, tau, 5), AQS_ESIZE, jf, "n = 5");
    FAILS(L, &ref, aqs_joint_set_force(L, 3, tau, 1), AQS_ESIZE, jf, "n = 1"); /* fixed: 0 */
    FAILS(L, &ref, aqs_joint_set_force(L, 1, tau, -1), AQS_ESIZE, jf, "n = -1");
    FAILS(L, &ref, aqs_joint_set_force(L, 4, NULL, 3), AQS_EINVAL, jf, "tau is NULL");
    /* accepted: a fixed joint's empty force; NULL point and torque mean the
     * origin and zero (the same bits as explicit zeros) */
    assert_int_equal(aqs_joint_set_force(L, 3, NULL, 0), AQS_OK);
    assert_unchanged(L, &ref);
    {
        snapshot a, b;
        assert_int_equal(aqs_body_set_force(L, 7, F, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        take(L, &a);
        assert_int_equal(aqs_body_set_force(L, 7, F, zero3, zero3), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        take(L, &b);
        assert_same(&a, &b);
        assert_true(memcmp(a.qdd, ref.qdd, sizeof a.qdd) != 0); /* the load did act */
        /* clearing it restores the reference exactly */
        assert_int_equal(aqs_body_clear_force(L, 7), AQS_OK);
        assert_int_equal(aqs_body_clear_force(L, 7), AQS_OK); /* twice: no-op */
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        take(L, &a);
        assert_same(&a, &ref);
    }
    aqs_linkage_destroy(L);
}

/* -------------------------------------------------- solving, stepping */

static void test_solve_errors(void **state)
{
    snapshot ref;
    aqs_linkage *L = reference(&ref);
    static const char sf[] = "aqs_linkage_step";
    aqs_solve_stats st;
    union {
        aqs_solve_stats s; /* for the alignment */
        unsigned char b[sizeof(aqs_solve_stats) + 16];
    } u;
    unsigned char *raw = u.b;
    (void)state;
    /* dt: finite and > 0 */
    FAILS(L, &ref, aqs_linkage_step(L, 0.0), AQS_EINVAL, sf, "dt = 0");
    FAILS(L, &ref, aqs_linkage_step(L, -0.0), AQS_EINVAL, sf, "dt = -0");
    FAILS(L, &ref, aqs_linkage_step(L, -1e-3), AQS_EINVAL, sf, "dt = -0.001");
    FAILS(L, &ref, aqs_linkage_step(L, NAN), AQS_EINVAL, sf, "dt = nan");
    FAILS(L, &ref, aqs_linkage_step(L, INFINITY), AQS_EINVAL, sf, "dt = inf");
    FAILS(L, &ref, aqs_linkage_step(L, -INFINITY), AQS_EINVAL, sf, "dt = -inf");
    /* the adaptive controls */
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, -1, 0.1), AQS_EINVAL, "aqs_linkage_set_tolerance", "metric = -1");
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, 6, 0.1), AQS_EINVAL, "aqs_linkage_set_tolerance", "metric = 6");
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, -0.1), AQS_EINVAL,
          "aqs_linkage_set_tolerance", "eps = -0.1");
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, NAN), AQS_EINVAL,
          "aqs_linkage_set_tolerance", "eps = nan");
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_JOINT, INFINITY), AQS_EINVAL,
          "aqs_linkage_set_tolerance", "eps = inf");
    FAILS(L, &ref, aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_JOINT, -INFINITY), AQS_EINVAL,
          "aqs_linkage_set_tolerance", "eps = -inf");
    FAILS(L, &ref, aqs_linkage_set_max_computed(L, -1), AQS_EINVAL, "aqs_linkage_set_max_computed",
          "max_joints = -1");
    FAILS(L, &ref, aqs_linkage_refine(L, NAN), AQS_EINVAL, "aqs_linkage_refine", "eps = nan");
    FAILS(L, &ref, aqs_linkage_refine(L, INFINITY), AQS_EINVAL, "aqs_linkage_refine", "eps = inf");
    FAILS(L, &ref, aqs_linkage_refine(L, -1.0), AQS_EINVAL, "aqs_linkage_refine", "eps = -1");
    /* statistics: NULL, a size too small; a short size gets only its part */
    FAILS(L, &ref, aqs_linkage_get_stats(L, NULL), AQS_EINVAL, "aqs_linkage_get_stats", "stats is NULL");
    memset(&st, 0xAB, sizeof st);
    st.size = 7;
    FAILS(L, &ref, aqs_linkage_get_stats(L, &st), AQS_EINVAL, "aqs_linkage_get_stats", "stats->size = 7");
    assert_int_equal(st.size, 7);
    st.size = 0;
    FAILS(L, &ref, aqs_linkage_get_stats(L, &st), AQS_EINVAL, "aqs_linkage_get_stats", "stats->size = 0");
    memset(raw, 0xAB, sizeof u.b);
    {
        uint32_t size = 8;
        int32_t metric;
        size_t i;
        memcpy(raw, &size, sizeof size);
        assert_int_equal(aqs_linkage_get_stats(L, &u.s), AQS_OK);
        memcpy(&size, raw, sizeof size);
        memcpy(&metric, raw + 4, sizeof metric);
        assert_int_equal(size, 8);
        assert_int_equal(metric, AQS_METRIC_ABS_LINKAGE);
        for (i = 8; i < sizeof u.b; i++) assert_int_equal(raw[i], 0xAB); /* nothing beyond */
        /* a larger size than the library knows: it fills its own struct only */
        size = (uint32_t)sizeof u.b;
        memset(raw, 0xAB, sizeof u.b);
        memcpy(raw, &size, sizeof size);
        assert_int_equal(aqs_linkage_get_stats(L, &u.s), AQS_OK);
        for (i = sizeof(aqs_solve_stats); i < sizeof u.b; i++) assert_int_equal(raw[i], 0xAB);
        memcpy(&st, raw, sizeof st);
        assert_int_equal(st.computed_joints, st.counted_joints); /* exact: all computed */
        /* the moving joints but the free one (the fixed joint has no
         * acceleration to count) */
        assert_int_equal(st.counted_joints, NJ - 2);
        assert_true(st.error_bound == 0.0 && st.capped == 0);
    }
    /* joint_get_computed */
    {
        int32_t c = -5;
        FAILS(L, &ref, aqs_joint_get_computed(L, -1, &c), AQS_ERANGE, "aqs_joint_get_computed", "joint = -1");
        FAILS(L, &ref, aqs_joint_get_computed(L, NJ, &c), AQS_ERANGE, "aqs_joint_get_computed", "joint = 8");
        FAILS(L, &ref, aqs_joint_get_computed(L, 1, NULL), AQS_EINVAL, "aqs_joint_get_computed", "computed is NULL");
        assert_int_equal(c, -5);
        assert_int_equal(aqs_joint_get_computed(L, 1, &c), AQS_OK);
        assert_int_equal(c, 1);
    }
    aqs_linkage_destroy(L);
}

/* A load so large that the accelerations overflow: solve and step report
 * AQS_ENUMERIC and name the joint, the results become unreadable (a phase
 * error rather than non-finite numbers), the positions do not move, and
 * removing the load restores the reference exactly. */
static void test_numeric_failure(void **state)
{
    snapshot ref, now;
    aqs_linkage *L = reference(&ref);
    double huge[3] = {1e308, -1e308, 1e308}, v[NV], q[NQ];
    (void)state;
    assert_int_equal(aqs_body_set_force(L, 7, huge, NULL, huge), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_ENUMERIC);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_solve");
    test_assert_contains(aqs_linkage_last_error(L), "non-finite");
    assert_int_equal(aqs_linkage_get_accelerations(L, v, NV), AQS_ESTATE);
    assert_int_equal(aqs_joint_get_acceleration(L, 1, v, 1), AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "nothing solved");
    assert_int_equal(aqs_joint_get_constraint_force(L, 1, v), AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_joint_get_constraint_force");
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_ENUMERIC);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_step");
    assert_int_equal(aqs_linkage_get_positions(L, q, NQ), AQS_OK);
    assert_memory_equal(q, ref.q, sizeof q);
    assert_int_equal(aqs_body_clear_force(L, 7), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    take(L, &now);
    assert_same(&now, &ref);
    /* The DCA, exact and adaptive: its node update finds the joint's
     * acceleration term non-finite from finite inertias, and says that the
     * loads overflowed (not "numerically singular"), in a message that names
     * the call like every other. */
    {
        int k;
        for (k = 0; k < 2; k++) {
            if (k == 0) {
                assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
            } else {
                assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
                assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
            }
            assert_int_equal(aqs_body_set_force(L, 7, huge, NULL, huge), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_ENUMERIC);
            test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_solve: the loads across joint ");
            test_assert_contains(aqs_linkage_last_error(L), "overflowed");
            assert_int_equal(aqs_linkage_step(L, 0.01), AQS_ENUMERIC);
            test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_step: the loads across joint ");
            assert_int_equal(aqs_linkage_get_positions(L, q, NQ), AQS_OK);
            assert_memory_equal(q, ref.q, sizeof q);
            assert_int_equal(aqs_body_clear_force(L, 7), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        }
    }
    aqs_linkage_destroy(L);
}

/* Masses outside [1e-150, 1e150] are refused by the DCA (a tolerance, a cap,
 * AQS_EXACT_DCA), which multiplies masses together: with subnormals flushed a
 * pendulum of 1e-155 kg came out at rest, certified (found from outside,
 * 2026-12-05). The message names the body and its mass, nothing changes (the
 * solve stays the ABA's), and the ABA answers such a pendulum: qdd = m c g_y
 * / (I_zz + m c^2), to 1e-15 relative. */
static void test_dca_mass_range(void **state)
{
    static const double masses[] = {1e-155, 1e-300, 1e151, 1e300};
    size_t k;
    (void)state;
    for (k = 0; k < sizeof masses / sizeof masses[0]; k++) {
        aqs_linkage *L = test_new_linkage();
        const double m = masses[k], com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
        const double zero[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1}, g[3] = {0.3, -9.81, 1.2};
        char text[64];
        double qdd = 0.0;
        aqs_solve_stats st;
        assert_int_equal(aqs_body_add(L, m, com, I, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, zero, quat, axis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
        snprintf(text, sizeof text, "body 0 has mass %g, outside [1e-150, 1e150]", m);
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_EINVAL);
        test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_set_exact_solver: ");
        test_assert_contains(aqs_linkage_last_error(L), text);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_EINVAL);
        test_assert_contains(aqs_linkage_last_error(L), text);
        assert_int_equal(aqs_linkage_set_max_computed(L, 1), AQS_EINVAL);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        st.size = sizeof st;
        assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
        assert_int_equal(st.path, AQS_PATH_EXACT_ABA);
        assert_true(st.eps == 0.0);
        assert_int_equal(aqs_linkage_get_accelerations(L, &qdd, 1), AQS_OK);
        {
            const double want = m * 0.5 * -9.81 / (0.1 + m * 0.25);
            assert_true(fabs(qdd - want) <= 1e-15 * fabs(want));
        }
        aqs_linkage_destroy(L);
    }
    /* a massless body welded to a massive one is not refused */
    {
        aqs_linkage *L = test_new_linkage();
        const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, Z[9] = {0};
        const double zero[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
        assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_OK);
        assert_int_equal(aqs_body_add(L, 0.0, com, Z, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, zero, quat, axis, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, com, quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        aqs_linkage_destroy(L);
    }
}

/* ------------------------------------------------- positions, reading */

static void test_position_errors(void **state)
{
    snapshot ref;
    aqs_linkage *L = reference(&ref);
    static const char sp[] = "aqs_linkage_set_positions", jp[] = "aqs_joint_set_position";
    double q[NQ + 1], buf[64];
    int i, j;
    (void)state;
    /* every position value, NaN and +-Inf: the bulk setter names the joint
     * and the value's index, and writes nothing (not even the joints before
     * the bad one) */
    for (i = 0; i < NQ; i++) {
        size_t v;
        for (v = 0; v < 3; v++) {
            int32_t qo = 0, nq = 0, jj = -1;
            char text[64];
            memcpy(q, ref_q, sizeof ref_q);
            q[i] = bad_values[v];
            for (j = 0; j < NJ; j++) {
                assert_int_equal(aqs_joint_get_layout(L, j, &qo, &nq, NULL, NULL), AQS_OK);
                if (i >= qo && i < qo + nq) {
                    jj = j;
                    break;
                }
            }
            assert_true(jj >= 0);
            snprintf(text, sizeof text, "position value %d of joint %d", i - qo, (int)jj);
            FAILS(L, &ref, aqs_linkage_set_positions(L, q, NQ), AQS_EINVAL, sp, text);
            FAILS(L, &ref, aqs_joint_set_position(L, jj, q + qo, nq), AQS_EINVAL, jp, text);
        }
    }
    /* quaternions off unit by more than 1e-6 */
    memcpy(q, ref_q, sizeof ref_q);
    q[3] = 0.5 * (1 + 1e-5);
    FAILS(L, &ref, aqs_linkage_set_positions(L, q, NQ), AQS_EINVAL, sp, "quaternion of joint 0");
    FAILS(L, &ref, aqs_joint_set_position(L, 0, q, 7), AQS_EINVAL, jp, "quaternion of joint 0");
    memcpy(q, ref_q, sizeof ref_q);
    q[8] = q[9] = q[10] = q[11] = 0.0;
    FAILS(L, &ref, aqs_linkage_set_positions(L, q, NQ), AQS_EINVAL, sp, "quaternion of joint 2");
    FAILS(L, &ref, aqs_joint_set_position(L, 2, q + 8, 4), AQS_EINVAL, jp, "quaternion of joint 2");
    /* sizes: exactly nq (AQS_ESIZE), NULL */
    FAILS(L, &ref, aqs_linkage_set_positions(L, ref_q, NQ - 1), AQS_ESIZE, sp, "n = 19");
    FAILS(L, &ref, aqs_linkage_set_positions(L, q, NQ + 1), AQS_ESIZE, sp, "n = 21");
    FAILS(L, &ref, aqs_linkage_set_positions(L, ref_q, 0), AQS_ESIZE, sp, "n = 0");
    FAILS(L, &ref, aqs_linkage_set_positions(L, NULL, NQ), AQS_EINVAL, sp, "q is NULL");
    FAILS(L, &ref, aqs_joint_set_position(L, 2, ref_q + 8, 3), AQS_ESIZE, jp, "n = 3");
    FAILS(L, &ref, aqs_joint_set_position(L, 1, ref_q + 7, 2), AQS_ESIZE, jp, "n = 2");
    FAILS(L, &ref, aqs_joint_set_position(L, 1, NULL, 1), AQS_EINVAL, jp, "q is NULL");
    FAILS(L, &ref, aqs_joint_set_position(L, -1, ref_q, 1), AQS_ERANGE, jp, "joint = -1");
    FAILS(L, &ref, aqs_joint_set_position(L, NJ, ref_q, 1), AQS_ERANGE, jp, "joint = 8");
    /* a fixed joint has no position: n = 0 (q may be NULL) */
    assert_int_equal(aqs_joint_set_position(L, 3, NULL, 0), AQS_OK);
    FAILS(L, &ref, aqs_joint_set_position(L, 3, ref_q, 1), AQS_ESIZE, jp, "n = 1");

    /* readers: ESIZE writes nothing, NULL and bad indices */
#define SENTINEL 123.25
#define FILL() for (i = 0; i < 64; i++) buf[i] = SENTINEL
#define UNTOUCHED() for (i = 0; i < 64; i++) assert_true(buf[i] == SENTINEL)
    FILL();
    FAILS(L, &ref, aqs_linkage_get_positions(L, buf, NQ - 1), AQS_ESIZE, "aqs_linkage_get_positions", "n = 19");
    UNTOUCHED();
    FAILS(L, &ref, aqs_linkage_get_positions(L, NULL, NQ), AQS_EINVAL, "aqs_linkage_get_positions", "q is NULL");
    FAILS(L, &ref, aqs_linkage_get_accelerations(L, buf, NV - 1), AQS_ESIZE, "aqs_linkage_get_accelerations", "n = 17");
    UNTOUCHED();
    FAILS(L, &ref, aqs_linkage_get_accelerations(L, NULL, NV), AQS_EINVAL, "aqs_linkage_get_accelerations", "qdd is NULL");
    FAILS(L, &ref, aqs_linkage_get_constraint_forces(L, buf, 6 * NJ - 1), AQS_ESIZE,
          "aqs_linkage_get_constraint_forces", "n = 47");
    UNTOUCHED();
    FAILS(L, &ref, aqs_linkage_get_constraint_forces(L, NULL, 6 * NJ), AQS_EINVAL,
          "aqs_linkage_get_constraint_forces", "f is NULL");
    FAILS(L, &ref, aqs_linkage_get_body_poses_world(L, buf, 7 * NB - 1), AQS_ESIZE,
          "aqs_linkage_get_body_poses_world", "n = 55");
    UNTOUCHED();
    FAILS(L, &ref, aqs_linkage_get_body_poses_world(L, NULL, 7 * NB), AQS_EINVAL,
          "aqs_linkage_get_body_poses_world", "poses is NULL");
    /* per-joint readers: n must equal the joint's size */
    FAILS(L, &ref, aqs_joint_get_position(L, 0, buf, 6), AQS_ESIZE, "aqs_joint_get_position", "n = 6");
    FAILS(L, &ref, aqs_joint_get_position(L, 0, buf, 8), AQS_ESIZE, "aqs_joint_get_position", "n = 8");
    UNTOUCHED();
    FAILS(L, &ref, aqs_joint_get_position(L, 0, NULL, 7), AQS_EINVAL, "aqs_joint_get_position", "q is NULL");
    FAILS(L, &ref, aqs_joint_get_position(L, -1, buf, 1), AQS_ERANGE, "aqs_joint_get_position", "joint = -1");
    FAILS(L, &ref, aqs_joint_get_position(L, NJ, buf, 1), AQS_ERANGE, "aqs_joint_get_position", "joint = 8");
    FAILS(L, &ref, aqs_joint_get_acceleration(L, 2, buf, 4), AQS_ESIZE, "aqs_joint_get_acceleration", "n = 4");
    UNTOUCHED();
    FAILS(L, &ref, aqs_joint_get_acceleration(L, 2, NULL, 3), AQS_EINVAL, "aqs_joint_get_acceleration", "qdd is NULL");
    FAILS(L, &ref, aqs_joint_get_acceleration(L, -1, buf, 1), AQS_ERANGE, "aqs_joint_get_acceleration", "joint = -1");
    FAILS(L, &ref, aqs_joint_get_acceleration(L, NJ, buf, 1), AQS_ERANGE, "aqs_joint_get_acceleration", "joint = 8");
    FAILS(L, &ref, aqs_joint_get_constraint_force(L, 1, NULL), AQS_EINVAL, "aqs_joint_get_constraint_force", "f is NULL");
    FAILS(L, &ref, aqs_joint_get_constraint_force(L, -1, buf), AQS_ERANGE, "aqs_joint_get_constraint_force", "joint = -1");
    FAILS(L, &ref, aqs_joint_get_constraint_force(L, NJ, buf), AQS_ERANGE, "aqs_joint_get_constraint_force", "joint = 8");
    FAILS(L, &ref, aqs_body_get_pose_world(L, 0, NULL, buf), AQS_EINVAL, "aqs_body_get_pose_world", "pos is NULL");
    FAILS(L, &ref, aqs_body_get_pose_world(L, 0, buf, NULL), AQS_EINVAL, "aqs_body_get_pose_world", "quat is NULL");
    FAILS(L, &ref, aqs_body_get_pose_world(L, -1, buf, buf + 3), AQS_ERANGE, "aqs_body_get_pose_world", "body = -1");
    FAILS(L, &ref, aqs_body_get_pose_world(L, NB, buf, buf + 3), AQS_ERANGE, "aqs_body_get_pose_world", "body = 8");
    FAILS(L, &ref, aqs_joint_get_layout(L, -1, NULL, NULL, NULL, NULL), AQS_ERANGE, "aqs_joint_get_layout", "joint = -1");
    FAILS(L, &ref, aqs_joint_get_layout(L, NJ, NULL, NULL, NULL, NULL), AQS_ERANGE, "aqs_joint_get_layout", "joint = 8");
    UNTOUCHED();
    /* the accepted readers agree with the bulk arrays (and a fixed joint's
     * zero-sized position and acceleration take n = 0, NULL) */
    {
        int32_t qo, nq, vo, nv, total_q = 0, total_v = 0;
        for (j = 0; j < NJ; j++) {
            assert_int_equal(aqs_joint_get_layout(L, j, &qo, &nq, &vo, &nv), AQS_OK);
            assert_int_equal(qo, total_q);
            assert_int_equal(vo, total_v);
            total_q += nq;
            total_v += nv;
            assert_int_equal(aqs_joint_get_position(L, j, nq ? buf : NULL, nq), AQS_OK);
            if (nq) assert_memory_equal(buf, ref.q + qo, sizeof(double) * (size_t)nq);
            assert_int_equal(aqs_joint_get_acceleration(L, j, nv ? buf : NULL, nv), AQS_OK);
            if (nv) assert_memory_equal(buf, ref.qdd + vo, sizeof(double) * (size_t)nv);
            assert_int_equal(aqs_joint_get_constraint_force(L, j, buf), AQS_OK);
            assert_memory_equal(buf, ref.f + 6 * j, 6 * sizeof(double));
        }
        assert_int_equal(total_q, NQ);
        assert_int_equal(total_v, NV);
        for (j = 0; j < NB; j++) {
            assert_int_equal(aqs_body_get_pose_world(L, j, buf, buf + 3), AQS_OK);
            /* the hierarchical and the one-pass poses agree to rounding */
            for (i = 0; i < 7; i++) assert_true(fabs(buf[i] - ref.poses[7 * j + i]) < 1e-14);
        }
        /* larger arrays than needed are fine */
        assert_int_equal(aqs_linkage_get_accelerations(L, buf, 64), AQS_OK);
        assert_memory_equal(buf, ref.qdd, sizeof ref.qdd);
    }
    assert_unchanged(L, &ref);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_status_and_version),
        cmocka_unit_test(test_null_linkage),
        cmocka_unit_test(test_create),
        cmocka_unit_test(test_building_failures),
        cmocka_unit_test(test_phases),
        cmocka_unit_test(test_tree_builder_errors),
        cmocka_unit_test(test_load_errors),
        cmocka_unit_test(test_solve_errors),
        cmocka_unit_test(test_numeric_failure),
        cmocka_unit_test(test_dca_mass_range),
        cmocka_unit_test(test_position_errors),
    };
    return cmocka_run_group_tests_name("api", tests, NULL, NULL);
}
