/* test_stale.c -- what a change or a failure makes stale (src/model/stale.c), on
 * the four defects its absence caused (issue 13):
 *   (a) an adaptive solve failing in the coefficient update leaves no
 *       readable results (AQS_ESTATE, as for the exact path), and the next
 *       successful solve after the cause is removed equals a linkage that
 *       never failed;
 *   (b) with contact stiffness set, a shape_add failing with AQS_ENOMEM keeps
 *       the collision data of the former shapes: later solves equal, bit for
 *       bit, those of a twin that never received the failed call (and differ
 *       from the same linkage without contact, so contact is in them);
 *   (c) a capped or adaptive solve under finite but huge loads never returns
 *       AQS_OK with a NaN bound (reference: the same linkage at gravity 1,
 *       whose bound is finite);
 *   (d) a linkage whose first or only joints are fixed (no position yet):
 *       no arithmetic on a NULL q (clang's UBSan reports it: `make
 *       check-fuzz` runs this file built with -fsanitize=undefined,
 *       pointer-overflow), and the world poses are the joint placements. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, Q1[4] = {1, 0, 0, 0}, ZAX[3] = {0, 0, 1};
static const double O[3] = {0, 0, 0};

/* A chain of n unit bodies 1 m apart along x; joint i revolute about z,
 * or prismatic along x for odd i when mixed is set. */
static aqs_linkage *chain(int32_t n, int mixed, aqs_alloc_fn alloc, aqs_free_fn free_fn, void *user)
{
    aqs_linkage *L;
    int32_t i;
    if (alloc) assert_int_equal(aqs_linkage_create_with_allocator(alloc, free_fn, user, &L), AQS_OK);
    else L = test_new_linkage();
    for (i = 0; i < n; i++) {
        const double com[3] = {0.5, 0, 0}, pos[3] = {i ? 1.0 : 0.0, 0, 0}, xax[3] = {1, 0, 0};
        int prismatic = mixed && (i % 2);
        assert_int_equal(aqs_body_add(L, 1.0, com, I3, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, prismatic ? AQS_JOINT_PRISMATIC : AQS_JOINT_REVOLUTE, i - 1, i,
                                       pos, Q1, prismatic ? xax : ZAX, NULL),
                         AQS_OK);
    }
    return L;
}

/* Every readable result of the last solve, or the status of reading it. */
typedef struct {
    aqs_status st;
    double qdd[64], f[6 * 64], bound;
} results;

static void read_results(aqs_linkage *L, int32_t nv, int32_t nj, results *r)
{
    aqs_solve_stats s;
    memset(r, 0, sizeof *r);
    memset(&s, 0, sizeof s);
    s.size = sizeof s;
    r->st = aqs_linkage_get_accelerations(L, r->qdd, (size_t)nv);
    if (r->st != AQS_OK) return;
    assert_int_equal(aqs_linkage_get_constraint_forces(L, r->f, 6 * (size_t)nj), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &s), AQS_OK);
    r->bound = s.error_bound;
}

/* (a) */
static void test_failed_update_leaves_nothing_readable(void **state)
{
    const double g[3] = {0, -9.81, 0}, far = 1e300;
    aqs_linkage *L = chain(16, 1, NULL, NULL, NULL), *twin = chain(16, 1, NULL, NULL, NULL);
    aqs_linkage *both[2] = {L, twin};
    results before, after, ref;
    double q0;
    int k;
    (void)state;
    for (k = 0; k < 2; k++) {
        assert_int_equal(aqs_linkage_finalize(both[k]), AQS_OK);
        assert_int_equal(aqs_linkage_set_gravity(both[k], g), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(both[k], AQS_METRIC_REL_LINKAGE, 0.1), AQS_OK);
        assert_int_equal(aqs_linkage_solve(both[k]), AQS_OK);
    }
    read_results(L, 16, 16, &before);
    assert_int_equal(before.st, AQS_OK);
    /* a prismatic joint 1e300 m out: the articulated inertia across it
       overflows, the update fails before the adaptive back-substitution */
    assert_int_equal(aqs_joint_get_position(L, 1, &q0, 1), AQS_OK);
    assert_int_equal(aqs_joint_set_position(L, 1, &far, 1), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_ENUMERIC);
    test_assert_contains(aqs_linkage_last_error(L), "numerically singular");
    read_results(L, 16, 16, &after);
    assert_int_equal(after.st, AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "nothing solved");
    assert_int_equal(aqs_linkage_refine(L, 0.01), AQS_ESTATE);
    {
        double f[6];
        aqs_solve_stats s;
        memset(&s, 0, sizeof s);
        s.size = sizeof s;
        assert_int_equal(aqs_joint_get_constraint_force(L, 0, f), AQS_ESTATE);
        assert_int_equal(aqs_linkage_get_stats(L, &s), AQS_ESTATE);
    }
    /* the cause removed: the same numbers as a linkage that never failed */
    assert_int_equal(aqs_joint_set_position(L, 1, &q0, 1), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    read_results(L, 16, 16, &after);
    read_results(twin, 16, 16, &ref);
    assert_int_equal(after.st, AQS_OK);
    assert_true(test_max_abs_diff(after.qdd, ref.qdd, 16) <= 1e-12 * (1.0 + test_max_abs_diff(ref.qdd, O, 1)));
    assert_true(fabs(after.bound - ref.bound) <= 1e-12);
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(twin);
}

/* An allocator that, while armed, fails every allocation from the first one
 * on (a failure that a retry inside the call cannot get around). */
typedef struct {
    int armed;
    long failed;
} failing;

static void *failing_alloc(void *user, size_t size)
{
    failing *f = user;
    if (f->armed) {
        f->failed++;
        return NULL;
    }
    return malloc(size);
}

static void failing_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

/* A 4-body chain hanging along x whose last body's sphere rests 0.05 m deep
 * in a world box: stiffness k gives a contact force. */
static aqs_linkage *contact_scene(failing *f, double k)
{
    const double r[3] = {0.3, 0, 0}, box[3] = {0.5, 0.5, 0.5}, at[3] = {3.0, -0.75, 0};
    const double g[3] = {0, -9.81, 0};
    aqs_linkage *L = chain(4, 0, failing_alloc, failing_free, f);
    assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_BOX, box, at, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, 3, AQS_SHAPE_SPHERE, r, O, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    if (k > 0.0) assert_int_equal(aqs_linkage_set_contact_stiffness(L, k), AQS_OK);
    return L;
}

/* (b) */
static void test_failed_shape_add_keeps_contact(void **state)
{
    failing f = {0, 0}, ft = {0, 0}, fn = {0, 0};
    aqs_linkage *L = contact_scene(&f, 1e4), *twin = contact_scene(&ft, 1e4);
    aqs_linkage *none = contact_scene(&fn, 0.0);
    const double r[3] = {0.1, 0, 0}, away[3] = {0, 5, 0};
    results a, b, c;
    int32_t ns = -1, step;
    (void)state;
    f.armed = 1;
    assert_int_equal(aqs_shape_add(L, 1, AQS_SHAPE_SPHERE, r, away, Q1, NULL), AQS_ENOMEM);
    f.armed = 0;
    assert_true(f.failed > 0);
    test_assert_contains(aqs_linkage_last_error(L), "out of memory");
    assert_int_equal(aqs_linkage_get_shape_count(L, &ns), AQS_OK);
    assert_int_equal(ns, 2);
    for (step = 0; step < 3; step++) {
        if (step > 0) {
            assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
            assert_int_equal(aqs_linkage_step(twin, 0.01), AQS_OK);
            assert_int_equal(aqs_linkage_step(none, 0.01), AQS_OK);
        }
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_solve(twin), AQS_OK);
        assert_int_equal(aqs_linkage_solve(none), AQS_OK);
        read_results(L, 4, 4, &a);
        read_results(twin, 4, 4, &b);
        read_results(none, 4, 4, &c);
        assert_memory_equal(a.qdd, b.qdd, 4 * sizeof(double));
        assert_memory_equal(a.f, b.f, 24 * sizeof(double));
        /* contact is in them: the last joint's acceleration changes by more
           than rounding without it */
        assert_true(fabs(b.qdd[3] - c.qdd[3]) > 1e-3 * (1.0 + fabs(c.qdd[3])));
    }
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(twin);
    aqs_linkage_destroy(none);
}

/* (c) */
static void test_huge_loads_never_nan(void **state)
{
    static const int32_t metrics[4] = {AQS_METRIC_ABS_LINKAGE, AQS_METRIC_REL_LINKAGE,
                                       AQS_METRIC_ABS_JOINT, AQS_METRIC_REL_JOINT};
    int m, cap, huge;
    (void)state;
    for (m = 0; m < 4; m++)
        for (cap = 0; cap < 2; cap++)
            for (huge = 0; huge < 2; huge++) {
                const double g[3] = {0, huge ? -1e160 : -1.0, 0};
                aqs_linkage *L = chain(64, 0, NULL, NULL, NULL);
                aqs_status st;
                results r;
                assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
                assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
                assert_int_equal(aqs_linkage_set_tolerance(L, metrics[m], 1e-3), AQS_OK);
                if (cap) assert_int_equal(aqs_linkage_set_max_computed(L, 5), AQS_OK);
                st = aqs_linkage_solve(L);
                if (st != AQS_OK) test_assert_contains(aqs_linkage_last_error(L), "non-finite");
                read_results(L, 64, 64, &r);
                if (!huge) {
                    /* the reference: moderate loads solve with a finite bound */
                    assert_int_equal(st, AQS_OK);
                    assert_true(isfinite(r.bound));
                } else if (st == AQS_OK) {
                    assert_false(isnan(r.bound));
                } else {
                    assert_int_equal(st, AQS_ENUMERIC);
                    assert_int_equal(r.st, AQS_ESTATE);
                }
                aqs_linkage_destroy(L);
            }
}

/* (d) */
static void test_fixed_joints_only(void **state)
{
    const double p0[3] = {0.5, -1, 2}, p1[3] = {1, 0, 0};
    aqs_linkage *L = test_new_linkage();
    double q[1], poses[14], qdd[1], f[12];
    (void)state;
    test_add_body(L, 1.0, 0, 0, 0, 0.1);
    test_add_body(L, 2.0, 0, 0, 0, 0.1);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, AQS_WORLD, 0, p0, Q1, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, p1, Q1, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, 0), AQS_OK);
    assert_int_equal(aqs_linkage_get_positions(L, q, 0), AQS_OK);
    assert_int_equal(aqs_joint_get_position(L, 0, q, 0), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, 0), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 12), AQS_OK);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, poses, 14), AQS_OK);
    /* the placements compose: body 1 at p0 + p1, identity orientation */
    assert_true(fabs(poses[0] - 0.5) < 1e-15 && fabs(poses[1] + 1) < 1e-15 && fabs(poses[2] - 2) < 1e-15);
    assert_true(fabs(poses[7] - 1.5) < 1e-15 && fabs(poses[8] + 1) < 1e-15 && fabs(poses[9] - 2) < 1e-15);
    assert_true(fabs(poses[3] - 1) < 1e-15 && fabs(poses[10] - 1) < 1e-15);
    assert_int_equal(aqs_linkage_clear_forces(L), AQS_OK);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_failed_update_leaves_nothing_readable),
        cmocka_unit_test(test_failed_shape_add_keeps_contact),
        cmocka_unit_test(test_huge_loads_never_nan),
        cmocka_unit_test(test_fixed_joints_only),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
