/* test_alloc.c -- every allocation of a linkage goes through its allocator
 * (src/base/pool.c and every caller): a counting allocator proves that nothing
 * leaks and that solving and stepping allocate nothing; a failing allocator
 * driven over every allocation index k of a full scenario proves that each
 * failure returns AQS_ENOMEM from the call that allocates, changes nothing
 * (the retried call succeeds and the run ends with the same bits as a run
 * without failure), never crashes, and leaks nothing, whether the run is
 * retried to the end or abandoned at the failure. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NBODIES 40

/* The allocator's free must never see NULL (aqs.h); the user pointer must
 * be the one given at creation. */
static counting_state *expected_user;

static void *alloc_fn(void *user, size_t size)
{
    assert_ptr_equal(user, expected_user);
    assert_true(size > 0);
    return counting_alloc(user, size);
}

static void free_fn(void *user, void *ptr)
{
    assert_ptr_equal(user, expected_user);
    assert_non_null(ptr);
    counting_free(user, ptr);
}

typedef struct {
    double q[128], qdd[128], f[6 * NBODIES], q_adaptive[128];
    int32_t nq, nv;
} results;

enum { RETRY, ABANDON };

typedef struct {
    counting_state *cs;
    int mode;
    int failures; /* AQS_ENOMEM returns seen */
    int abandoned;
} run;

/* Call expr: if the failing allocation happened inside it, it must return
 * AQS_ENOMEM with an out-of-memory message and leave the sizes as they
 * were; then either retry it (it must succeed) or abandon the run.
 * Otherwise it must succeed. */
#define CALL(R, L, expr)                                                                           \
    do {                                                                                           \
        long before_ = (R)->cs->count;                                                             \
        int32_t nb0_, nj0_, nb1_, nj1_;                                                            \
        aqs_status st_;                                                                            \
        assert_int_equal(aqs_linkage_get_sizes((L), &nb0_, &nj0_, NULL, NULL), AQS_OK);            \
        st_ = (expr);                                                                              \
        if ((R)->cs->fail_at > before_ && (R)->cs->fail_at <= (R)->cs->count) {                   \
            assert_int_equal(st_, AQS_ENOMEM);                                                     \
            test_assert_contains(aqs_linkage_last_error(L), "out of memory");                      \
            assert_int_equal(aqs_linkage_get_sizes((L), &nb1_, &nj1_, NULL, NULL), AQS_OK);        \
            assert_true(nb1_ == nb0_ && nj1_ == nj0_);                                             \
            (R)->failures++;                                                                       \
            if ((R)->mode == ABANDON) {                                                            \
                (R)->abandoned = 1;                                                                \
                aqs_linkage_destroy(L);                                                            \
                return;                                                                            \
            }                                                                                      \
            st_ = (expr);                                                                          \
        }                                                                                          \
        assert_int_equal(st_, AQS_OK);                                                             \
    } while (0)

/* Calls that must not allocate at all. */
#define NO_ALLOC(R, expr)                                                                          \
    do {                                                                                           \
        long before_ = (R)->cs->count;                                                             \
        assert_int_equal((expr), AQS_OK);                                                          \
        assert_int_equal((R)->cs->count, before_);                                                 \
    } while (0)

/* A branched linkage with fixed joints (welded groups, a body welded to the
 * world with a moving subtree), 40 bodies so that the body and joint arrays
 * grow several times; finalize; loads; solve and steps; then the adaptive
 * solver (its factors are allocated by aqs_linkage_set_max_computed and
 * aqs_linkage_set_tolerance). */
static void scenario(run *R, results *out)
{
    static const int types[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_FIXED, AQS_JOINT_PRISMATIC,
                                AQS_JOINT_SPHERICAL, AQS_JOINT_UNIVERSAL, AQS_JOINT_FIXED,
                                AQS_JOINT_CYLINDRICAL, AQS_JOINT_PLANAR};
    aqs_linkage *L = NULL;
    uint64_t seed = 51;
    int32_t i;
    aqs_status st;
    long before = R->cs->count;
    expected_user = R->cs;
    st = aqs_linkage_create_with_allocator(alloc_fn, free_fn, R->cs, &L);
    if (R->cs->fail_at > before && R->cs->fail_at <= R->cs->count) {
        assert_int_equal(st, AQS_ENOMEM);
        assert_null(L); /* nothing returned */
        R->failures++;
        if (R->mode == ABANDON) {
            R->abandoned = 1;
            return;
        }
        st = aqs_linkage_create_with_allocator(alloc_fn, free_fn, R->cs, &L);
    }
    assert_int_equal(st, AQS_OK);
    NO_ALLOC(R, aqs_linkage_set_inertia_check(L, 1));
    for (i = 0; i < NBODIES; i++) {
        double com[3] = {0.2, 0.05 * (i % 3), 0}, I[9] = {0.1, 0, 0, 0, 0.12, 0, 0, 0, 0.15};
        double pos[3] = {0.5, 0.1 * (i % 4), 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {i % 2, 1, 0.3};
        int32_t parent = i == 0 ? AQS_WORLD : (int32_t)test_uniform(&seed, i > 3 ? i - 3 : 0, i);
        int32_t type = types[i % 8], b = -1, j = -1;
        if (i == 20) {
            parent = AQS_WORLD; /* a second root, welded to the world */
            type = AQS_JOINT_FIXED;
        }
        CALL(R, L, aqs_body_add(L, 1.0 + 0.01 * i, com, I, &b));
        assert_int_equal(b, i);
        CALL(R, L, aqs_joint_add(L, type, parent, i, pos, quat, axis, &j));
        assert_int_equal(j, i);
    }
    {
        double g[3] = {0, -9.81, 0}, F[3] = {1, 0, 0.5}, tau = 0.3;
        NO_ALLOC(R, aqs_linkage_set_gravity(L, g));
        NO_ALLOC(R, aqs_body_set_force(L, NBODIES - 1, F, NULL, NULL));
        NO_ALLOC(R, aqs_body_set_force(L, 25, F, F, F));
        NO_ALLOC(R, aqs_joint_set_force(L, 0, &tau, 1));
    }
    {
        long b0 = R->cs->count;
        st = aqs_linkage_finalize(L);
        if (R->cs->fail_at > b0 && R->cs->fail_at <= R->cs->count) {
            assert_int_equal(st, AQS_ENOMEM);
            test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_finalize");
            test_assert_contains(aqs_linkage_last_error(L), "out of memory");
            /* still building: not finalized, and editable */
            assert_int_equal(aqs_linkage_get_tree_stats(L, NULL, NULL, NULL, NULL), AQS_ESTATE);
            assert_int_equal(aqs_linkage_solve(L), AQS_ESTATE);
            assert_int_equal(aqs_linkage_set_inertia_check(L, 1), AQS_OK);
            R->failures++;
            if (R->mode == ABANDON) {
                R->abandoned = 1;
                aqs_linkage_destroy(L);
                return;
            }
            st = aqs_linkage_finalize(L);
        }
        assert_int_equal(st, AQS_OK);
    }
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &out->nq, &out->nv), AQS_OK);
    assert_true(out->nq <= 128 && out->nv <= 128);
    {
        /* move every joint a little: positions of the right shapes */
        double q[128];
        NO_ALLOC(R, aqs_linkage_get_positions(L, q, 128));
        for (i = 0; i < out->nq; i++) q[i] += 0.01 * (i % 5);
        for (i = 0; i < NBODIES; i++) {
            int32_t qo, nq;
            assert_int_equal(aqs_joint_get_layout(L, i, &qo, &nq, NULL, NULL), AQS_OK);
            if (nq == 4) { /* spherical: back to a unit quaternion */
                double n = sqrt(q[qo] * q[qo] + q[qo + 1] * q[qo + 1] + q[qo + 2] * q[qo + 2] + q[qo + 3] * q[qo + 3]);
                int k;
                for (k = 0; k < 4; k++) q[qo + k] /= n;
            }
        }
        NO_ALLOC(R, aqs_linkage_set_positions(L, q, (size_t)out->nq));
    }
    /* solving and stepping allocate nothing (STYLE.md: step allocates nothing) */
    NO_ALLOC(R, aqs_linkage_solve(L));
    for (i = 0; i < 3; i++) NO_ALLOC(R, aqs_linkage_step(L, 0.01));
    NO_ALLOC(R, aqs_linkage_solve(L));
    NO_ALLOC(R, aqs_linkage_get_positions(L, out->q, 128));
    NO_ALLOC(R, aqs_linkage_get_accelerations(L, out->qdd, 128));
    NO_ALLOC(R, aqs_linkage_get_constraint_forces(L, out->f, 6 * NBODIES));
    {
        double pos[3], quat[4], poses[7 * NBODIES];
        int32_t nodes;
        NO_ALLOC(R, aqs_body_get_pose_world(L, NBODIES - 1, pos, quat));
        NO_ALLOC(R, aqs_linkage_get_body_poses_world(L, poses, 7 * NBODIES));
        NO_ALLOC(R, aqs_linkage_get_tree_stats(L, &nodes, NULL, NULL, NULL));
    }
    /* The adaptive solver's factors: a cap or a tolerance may allocate them
     * (today the first one does), then solving and stepping allocate
     * nothing again. Only "out of memory" is required of the message: the
     * one of aqs_linkage_set_max_computed names aqs_linkage_set_tolerance. */
    CALL(R, L, aqs_linkage_set_max_computed(L, 1000));
    CALL(R, L, aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3));
    NO_ALLOC(R, aqs_linkage_solve(L));
    NO_ALLOC(R, aqs_linkage_step(L, 0.01));
    NO_ALLOC(R, aqs_linkage_get_positions(L, out->q_adaptive, 128));
    aqs_linkage_destroy(L);
}

static void scenario_tolerance_first(run *R)
{
    aqs_linkage *L = NULL;
    double com[3] = {0.1, 0, 0}, I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    double pos[3] = {1, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    long before;
    int32_t i;
    expected_user = R->cs;
    before = R->cs->count;
    if (aqs_linkage_create_with_allocator(alloc_fn, free_fn, R->cs, &L) != AQS_OK) {
        assert_true(R->cs->fail_at > before && R->cs->fail_at <= R->cs->count);
        R->failures++;
        return;
    }
    for (i = 0; i < 5; i++) {
        CALL(R, L, aqs_body_add(L, 1.0, com, I, NULL));
        CALL(R, L, aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, quat, axis, NULL));
    }
    CALL(R, L, aqs_linkage_finalize(L));
    CALL(R, L, aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_LINKAGE, 0.5));
    NO_ALLOC(R, aqs_linkage_solve(L));
    aqs_linkage_destroy(L);
}

static void test_no_leak(void **state)
{
    counting_state cs;
    results res;
    run R;
    (void)state;
    memset(&cs, 0, sizeof cs);
    memset(&R, 0, sizeof R);
    R.cs = &cs;
    R.mode = RETRY;
    scenario(&R, &res);
    assert_int_equal(R.failures, 0);
    assert_true(cs.count > 30); /* the scenario does allocate, in many places */
    assert_int_equal(cs.allocs, cs.count);
    assert_int_equal(cs.live, 0);
    assert_int_equal(cs.frees, cs.allocs);
}

/* Fail allocation k, for every k of the scenario. */
static void test_every_allocation_fails(void **state)
{
    counting_state cs;
    results ref, res;
    run R;
    long total, k;
    (void)state;
    memset(&cs, 0, sizeof cs);
    memset(&R, 0, sizeof R);
    R.cs = &cs;
    R.mode = RETRY;
    scenario(&R, &ref);
    total = cs.count;
    for (k = 1; k <= total; k++) {
        int mode;
        for (mode = RETRY; mode <= ABANDON; mode++) {
            memset(&cs, 0, sizeof cs);
            memset(&R, 0, sizeof R);
            memset(&res, 0, sizeof res);
            cs.fail_at = k;
            R.cs = &cs;
            R.mode = mode;
            scenario(&R, &res);
            /* exactly one allocation failed, and it was reported */
            assert_int_equal(R.failures, 1);
            assert_int_equal(cs.live, 0); /* nothing leaked */
            assert_int_equal(cs.frees, cs.allocs);
            if (mode == RETRY) {
                /* recovered completely: the same bits as without failure */
                assert_int_equal(res.nq, ref.nq);
                assert_int_equal(res.nv, ref.nv);
                assert_memory_equal(res.q, ref.q, sizeof(double) * (size_t)ref.nq);
                assert_memory_equal(res.qdd, ref.qdd, sizeof(double) * (size_t)ref.nv);
                assert_memory_equal(res.f, ref.f, sizeof res.f);
                assert_memory_equal(res.q_adaptive, ref.q_adaptive, sizeof(double) * (size_t)ref.nq);
            } else {
                assert_int_equal(R.abandoned, 1);
            }
        }
    }
    /* one past the end: no failure at all */
    memset(&cs, 0, sizeof cs);
    memset(&R, 0, sizeof R);
    cs.fail_at = total + 1;
    R.cs = &cs;
    R.mode = RETRY;
    scenario(&R, &res);
    assert_int_equal(R.failures, 0);
    assert_int_equal(cs.live, 0);
}

/* aqs_linkage_set_tolerance allocates the adaptive factors on its own too. */
static void test_tolerance_allocation_fails(void **state)
{
    counting_state cs;
    run R;
    long total, k;
    (void)state;
    memset(&cs, 0, sizeof cs);
    memset(&R, 0, sizeof R);
    R.cs = &cs;
    scenario_tolerance_first(&R);
    total = cs.count;
    assert_int_equal(cs.live, 0);
    for (k = 1; k <= total; k++) {
        memset(&cs, 0, sizeof cs);
        memset(&R, 0, sizeof R);
        cs.fail_at = k;
        R.cs = &cs;
        R.mode = RETRY;
        scenario_tolerance_first(&R);
        assert_int_equal(R.failures, 1);
        assert_int_equal(cs.live, 0);
    }
}

/* ---- Collision (src/api/collide_api.c, src/collide/broadphase.c): shapes, filters and
 * exclusions allocate when added; the first query after finalize allocates
 * the per-node data; later queries, steps and a shapeless scene allocate
 * nothing. A failed call leaves the shape count and the contacts as they
 * were. */

#define NCOLL 14

typedef struct {
    aqs_contact c[64];
    size_t n;
    int32_t nshapes;
} coll_results;

/* Like CALL, and the shape count must be unchanged by a failure. */
#define SHAPE_CALL(R, L, expr)                                                                     \
    do {                                                                                           \
        int32_t ns0_, ns1_;                                                                        \
        long before_ = (R)->cs->count;                                                             \
        aqs_status st_;                                                                            \
        assert_int_equal(aqs_linkage_get_shape_count((L), &ns0_), AQS_OK);                         \
        st_ = (expr);                                                                              \
        if ((R)->cs->fail_at > before_ && (R)->cs->fail_at <= (R)->cs->count) {                   \
            assert_int_equal(st_, AQS_ENOMEM);                                                     \
            test_assert_contains(aqs_linkage_last_error(L), "out of memory");                      \
            assert_int_equal(aqs_linkage_get_shape_count((L), &ns1_), AQS_OK);                     \
            assert_int_equal(ns1_, ns0_);                                                          \
            (R)->failures++;                                                                       \
            st_ = (expr);                                                                          \
        }                                                                                          \
        assert_int_equal(st_, AQS_OK);                                                             \
    } while (0)

static void scenario_collision(run *R, coll_results *out)
{
    aqs_linkage *L = NULL;
    double com[3] = {0.3, 0, 0}, I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    double pos[3] = {0.6, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    double sz[3] = {0.35, 0.2, 0.2}, sp[3] = {0.3, 0, 0}, g[3] = {0, -9.81, 0};
    const double hull[15] = {0.3, 0, 0, -0.2, 0.25, 0, -0.2, -0.25, 0.1, 0, 0, 0.35, 0.05, 0.05, -0.3};
    long before;
    int32_t i, hit;
    size_t n;
    expected_user = R->cs;
    before = R->cs->count;
    if (aqs_linkage_create_with_allocator(alloc_fn, free_fn, R->cs, &L) != AQS_OK) {
        assert_true(R->cs->fail_at > before && R->cs->fail_at <= R->cs->count);
        R->failures++;
        return;
    }
    for (i = 0; i < NCOLL; i++) {
        CALL(R, L, aqs_body_add(L, 1.0, com, I, NULL));
        CALL(R, L, aqs_joint_add(L, i == 5 ? AQS_JOINT_FIXED : AQS_JOINT_REVOLUTE, i - 1, i, pos,
                                 quat, axis, NULL));
        SHAPE_CALL(R, L, aqs_shape_add(L, i, i % 4, sz, sp, quat, NULL));
        if (i % 3 == 0) SHAPE_CALL(R, L, aqs_shape_add_hull(L, i, hull, 5, sp, quat, NULL));
    }
    SHAPE_CALL(R, L, aqs_body_set_collision_filter(L, 3, 2u, 0xFFFFFFFDu));
    for (i = 0; i < 10; i++) SHAPE_CALL(R, L, aqs_collision_exclude_pair(L, i, i + 3));
    CALL(R, L, aqs_linkage_finalize(L));
    /* an obstacle after finalize: rebuilt at the next query */
    {
        double big[3] = {3.0, 0.2, 3.0}, floor[3] = {2.0, -0.3, 0};
        SHAPE_CALL(R, L, aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_BOX, big, floor, quat, NULL));
    }
    NO_ALLOC(R, aqs_linkage_set_gravity(L, g));
    {
        long b0 = R->cs->count;
        aqs_status st = aqs_linkage_collide(L, AQS_COLLIDE_LAZY, out->c, 64, &out->n);
        if (R->cs->fail_at > b0 && R->cs->fail_at <= R->cs->count) {
            assert_int_equal(st, AQS_ENOMEM);
            test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_collide");
            test_assert_contains(aqs_linkage_last_error(L), "out of memory");
            R->failures++;
            st = aqs_linkage_collide(L, AQS_COLLIDE_LAZY, out->c, 64, &out->n);
        }
        assert_int_equal(st, AQS_OK);
    }
    for (i = 0; i < 3; i++) {
        NO_ALLOC(R, aqs_linkage_step(L, 0.05));
        NO_ALLOC(R, aqs_linkage_collide(L, i == 1 ? AQS_COLLIDE_BRUTE : AQS_COLLIDE_LAZY, out->c, 64, &n));
        NO_ALLOC(R, aqs_linkage_any_contact(L, &hit));
    }
    /* penalty contact: set-up may allocate, steps do not; a shape added with
     * penalty on builds at once */
    CALL(R, L, aqs_linkage_set_contact_stiffness(L, 50.0));
    NO_ALLOC(R, aqs_linkage_step(L, 0.05));
    {
        double r[3] = {0.5, 0, 0}, at[3] = {3.0, 0.2, 0};
        SHAPE_CALL(R, L, aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_SPHERE, r, at, quat, NULL));
    }
    NO_ALLOC(R, aqs_linkage_step(L, 0.05));
    NO_ALLOC(R, aqs_linkage_collide(L, AQS_COLLIDE_FULL, out->c, 64, &out->n));
    NO_ALLOC(R, aqs_linkage_get_shape_count(L, &out->nshapes));
    aqs_linkage_destroy(L);
}

static void test_collision_allocation_fails(void **state)
{
    counting_state cs;
    coll_results ref, res;
    run R;
    long total, k;
    (void)state;
    memset(&cs, 0, sizeof cs);
    memset(&R, 0, sizeof R);
    memset(&ref, 0, sizeof ref);
    R.cs = &cs;
    R.mode = RETRY;
    scenario_collision(&R, &ref);
    total = cs.count;
    assert_int_equal(R.failures, 0);
    assert_int_equal(cs.live, 0);
    assert_true(ref.n > 0 && ref.n < 64); /* contacts exist; the array held them all */
    for (k = 1; k <= total; k++) {
        memset(&cs, 0, sizeof cs);
        memset(&R, 0, sizeof R);
        memset(&res, 0, sizeof res);
        cs.fail_at = k;
        R.cs = &cs;
        R.mode = RETRY;
        scenario_collision(&R, &res);
        assert_int_equal(R.failures, 1);
        assert_int_equal(cs.live, 0);
        if (k > 1) { /* the linkage was created: recovered to the same bits */
            assert_int_equal(res.n, ref.n);
            assert_int_equal(res.nshapes, ref.nshapes);
            assert_memory_equal(res.c, ref.c, ref.n * sizeof(aqs_contact));
        }
    }
}

/* A 12-body branched linkage with tilted axes under gravity and a force,
 * penalty contact on, finalized and stepped once (exact solves: the tree's
 * poses neither allocated nor fresh). */
static aqs_linkage *first_shape_linkage(counting_state *cs)
{
    aqs_linkage *L = test_new_linkage_in(cs);
    const double g[3] = {0.3, -9.81, 0.7}, f[3] = {1.5, -0.4, 2.0}, at[3] = {0.2, 0.1, 0};
    uint64_t seed = 7;
    int32_t i;
    for (i = 0; i < 12; i++) {
        const int32_t parent = i == 0 ? AQS_WORLD : (int32_t)test_uniform(&seed, i > 3 ? i - 3 : 0, i);
        const double pos[3] = {0.6, 0.1, 0.05 * i}, axis[3] = {test_uniform(&seed, -1, 1), test_uniform(&seed, -1, 1), 1.0};
        double q[4];
        test_random_quat(&seed, q);
        test_add_body(L, 0.5 + test_uniform(&seed, 0, 2), 0.3, 0.05, 0, 0.05 + test_uniform(&seed, 0, 0.1));
        assert_int_equal(aqs_joint_add(L, i % 3 == 1 ? AQS_JOINT_SPHERICAL : AQS_JOINT_REVOLUTE, parent, i, pos, q,
                                       axis, NULL),
                         AQS_OK);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    for (i = 0; i < 12; i++) assert_int_equal(aqs_body_set_force(L, i, f, at, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, 50.0), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    return L;
}

/* The first shape added with penalty contact on builds the broad phase at
 * once, and refreshes (allocating, the first time) the tree's poses before.
 * When that fails for memory, later solves must give the bits of a linkage
 * that never tried it: with the poses left fresh, a load's world pose came
 * from the tree's poses instead of the kinematic walk, one ulp apart (found
 * by the fuzzer, 2026-12-06: tests/fuzz/seeds/first-shape-oom-poses). For each
 * allocation of the call: fail it, move a joint, step twice, compare. */
static void test_failed_first_shape_changes_nothing(void **state)
{
    const double r[3] = {0.2, 0, 0}, at[3] = {0.1, 0, 0}, quat[4] = {1, 0, 0, 0}, q1[1] = {0.3};
    long k;
    int failed = 0;
    (void)state;
    for (k = 1;; k++) {
        counting_state cs, ct;
        aqs_linkage *S, *T;
        aqs_status st;
        double qs[64], qt[64], as[64], at2[64];
        int i;
        memset(&cs, 0, sizeof cs);
        memset(&ct, 0, sizeof ct);
        S = first_shape_linkage(&cs);
        T = first_shape_linkage(&ct);
        cs.fail_at = cs.count + k;
        st = aqs_shape_add(S, 4, AQS_SHAPE_SPHERE, r, at, quat, NULL);
        cs.fail_at = 0;
        if (st == AQS_OK) { /* past the call's allocations */
            aqs_linkage_destroy(S);
            aqs_linkage_destroy(T);
            break;
        }
        assert_int_equal(st, AQS_ENOMEM);
        failed++;
        assert_int_equal(aqs_joint_set_position(S, 2, q1, 1), AQS_OK);
        assert_int_equal(aqs_joint_set_position(T, 2, q1, 1), AQS_OK);
        for (i = 0; i < 2; i++) {
            assert_int_equal(aqs_linkage_step(S, 0.01), AQS_OK);
            assert_int_equal(aqs_linkage_step(T, 0.01), AQS_OK);
        }
        memset(qs, 0, sizeof qs);
        memset(qt, 0, sizeof qt);
        memset(as, 0, sizeof as);
        memset(at2, 0, sizeof at2);
        assert_int_equal(aqs_linkage_get_positions(S, qs, 64), AQS_OK);
        assert_int_equal(aqs_linkage_get_positions(T, qt, 64), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(S, as, 64), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(T, at2, 64), AQS_OK);
        assert_memory_equal(qs, qt, sizeof qs);
        assert_memory_equal(as, at2, sizeof as);
        aqs_linkage_destroy(S);
        aqs_linkage_destroy(T);
        assert_int_equal(cs.live, 0);
    }
    assert_true(failed >= 2); /* the poses' allocation and the broad phase's among them */
}

/* A scene without shapes pays nothing: no collision state, no allocation by
 * steps or queries. */
static void test_shapeless_scene_allocates_nothing(void **state)
{
    counting_state cs;
    run RR, *R = &RR;
    aqs_linkage *L = NULL;
    double com[3] = {0.3, 0, 0}, I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    double pos[3] = {0.6, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1}, g[3] = {0, -9.81, 0};
    int32_t i, hit = -1, refit = -1;
    size_t n = 99;
    (void)state;
    memset(&cs, 0, sizeof cs);
    memset(R, 0, sizeof *R);
    R->cs = &cs;
    expected_user = &cs;
    assert_int_equal(aqs_linkage_create_with_allocator(alloc_fn, free_fn, &cs, &L), AQS_OK);
    for (i = 0; i < 8; i++) {
        assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, quat, axis, NULL), AQS_OK);
    }
    NO_ALLOC(R, aqs_linkage_set_collide_joined(L, 0)); /* the default: stores nothing */
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    NO_ALLOC(R, aqs_linkage_set_gravity(L, g));
    NO_ALLOC(R, aqs_linkage_step(L, 0.01));
    NO_ALLOC(R, aqs_linkage_collide(L, AQS_COLLIDE_LAZY, NULL, 0, &n));
    assert_int_equal(n, 0);
    NO_ALLOC(R, aqs_linkage_any_contact(L, &hit));
    assert_int_equal(hit, 0);
    NO_ALLOC(R, aqs_linkage_get_collision_stats(L, &refit, NULL, NULL, NULL));
    assert_int_equal(refit, 0);
    aqs_linkage_destroy(L);
    assert_int_equal(cs.live, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_leak),
        cmocka_unit_test(test_every_allocation_fails),
        cmocka_unit_test(test_tolerance_allocation_fails),
        cmocka_unit_test(test_collision_allocation_fails),
        cmocka_unit_test(test_failed_first_shape_changes_nothing),
        cmocka_unit_test(test_shapeless_scene_allocates_nothing),
    };
    return cmocka_run_group_tests_name("alloc", tests, NULL, NULL);
}
