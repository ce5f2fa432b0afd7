/* test_collide.c -- the public collision API (src/api/collide_api.c): bad input
 * (status, message naming the argument and value, linkage unchanged),
 * filters (joined bodies, welded bodies, groups and masks, exclusions),
 * shapes on welded bodies following their rigid group (closed form),
 * obstacles, the capacity protocol and any-contact; NULL linkage and NULL
 * outputs of the getters and setters; penalty contact. */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "collide.h"
#include "linkage.h"

static const double Q1[4] = {1, 0, 0, 0}, O[3] = {0, 0, 0}, ZAX[3] = {0, 0, 1};

/* A chain of n bodies along x, 1 m apart, revolute about z, a sphere of
 * radius r on each at the body origin. */
static aqs_linkage *chain(int32_t n, double r, int finalize)
{
    aqs_linkage *L = test_new_linkage();
    int32_t i;
    for (i = 0; i < n; i++) {
        double pos[3] = {i ? 1.0 : 0.0, 0, 0}, sz[3] = {r, 0, 0};
        test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, Q1, ZAX, NULL), AQS_OK);
        assert_int_equal(aqs_shape_add(L, i, AQS_SHAPE_SPHERE, sz, O, Q1, NULL), AQS_OK);
    }
    if (finalize) assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    return L;
}

static size_t count_contacts(aqs_linkage *L)
{
    size_t n = 0;
    aqs_status st = aqs_linkage_collide(L, AQS_COLLIDE_LAZY, NULL, 0, &n);
    assert_true(st == AQS_OK || st == AQS_ESIZE);
    return n;
}

#define EXPECT_FAIL(L, expr, status, text1, text2)                                                 \
    do {                                                                                           \
        int32_t ns0_, ns1_;                                                                        \
        assert_int_equal(aqs_linkage_get_shape_count((L), &ns0_), AQS_OK);                         \
        assert_int_equal((expr), (status));                                                        \
        test_assert_contains(aqs_linkage_last_error(L), text1);                                    \
        test_assert_contains(aqs_linkage_last_error(L), text2);                                    \
        assert_int_equal(aqs_linkage_get_shape_count((L), &ns1_), AQS_OK);                         \
        assert_int_equal(ns1_, ns0_);                                                              \
    } while (0)

static void test_bad_shapes(void **state)
{
    aqs_linkage *L = chain(2, 0.3, 0);
    const double sz[3] = {0.2, 0.3, 0.4}, nan_sz[3] = {0.2, NAN, 0.4}, neg[3] = {0.2, -1, 0.4};
    const double inf_pos[3] = {0, 0, INFINITY}, qbad[4] = {1, 0.1, 0, 0}, qnan[4] = {NAN, 0, 0, 0};
    const double tiny[3] = {1e-200, 0, 0}, huge[3] = {1, 1, 1e200}, far[3] = {0, -1e151, 0};
    const double cube[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
    double flat[24], nanpts[24], small[24], big[24], tinypts[24];
    int k;
    EXPECT_FAIL(L, aqs_shape_add(L, 2, AQS_SHAPE_BOX, sz, O, Q1, NULL), AQS_ERANGE, "aqs_shape_add", "body = 2");
    EXPECT_FAIL(L, aqs_shape_add(L, -5, AQS_SHAPE_BOX, sz, O, Q1, NULL), AQS_ERANGE, "body = -5", "AQS_WORLD");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, 7, sz, O, Q1, NULL), AQS_EINVAL, "type = 7", "AQS_SHAPE");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_HULL, sz, O, Q1, NULL), AQS_EINVAL, "type = 4", "aqs_shape_add_hull");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, NULL, O, Q1, NULL), AQS_EINVAL, "size", "NULL");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, nan_sz, O, Q1, NULL), AQS_EINVAL, "size[1] = nan", "finite");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_CAPSULE, neg, O, Q1, NULL), AQS_EINVAL, "size[1] = -1", "in [1e-150, 1e150]");
    /* the scale collision geometry is computed at (src/collide/shape.h, SHAPE_MIN, SHAPE_MAX):
     * beyond it a query came out wrong, not failed (a cube of 1e200 around a sphere: no
     * contact; of 1e-200: depth 0.5 for 0.3) */
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_SPHERE, tiny, O, Q1, NULL), AQS_EINVAL, "size[0] = 1e-200", "in [1e-150, 1e150]");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, huge, O, Q1, NULL), AQS_EINVAL, "size[2] = 1e+200", "in [1e-150, 1e150]");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, sz, far, Q1, NULL), AQS_EINVAL, "pos[1] = -1e+151", "beyond 1e150");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, sz, inf_pos, Q1, NULL), AQS_EINVAL, "pos[2] = inf", "finite");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, sz, NULL, Q1, NULL), AQS_EINVAL, "pos", "NULL");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, sz, O, qbad, NULL), AQS_EINVAL, "quat has norm 1.00498", "unit");
    EXPECT_FAIL(L, aqs_shape_add(L, 0, AQS_SHAPE_BOX, sz, O, qnan, NULL), AQS_EINVAL, "quat[0] = nan", "finite");
    /* hulls */
    memcpy(flat, cube, sizeof flat);
    for (k = 0; k < 8; k++) flat[3 * k + 2] = 0.0;
    memcpy(nanpts, cube, sizeof nanpts);
    nanpts[7] = NAN;
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, cube, 3, O, Q1, NULL), AQS_EINVAL, "npoints = 3", "at least 4");
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, NULL, 8, O, Q1, NULL), AQS_EINVAL, "points", "NULL");
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, flat, 8, O, Q1, NULL), AQS_EINVAL, "the 8 points are coplanar", "aqs_shape_add_hull");
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, nanpts, 8, O, Q1, NULL), AQS_EINVAL, "points[7] (point 2) = nan", "finite");
    /* hulls: the coplanarity test is the same at every scale (a unit cube shrunk by 1e-140 or
     * grown by 1e140 is a hull; unscaled, the squares underflowed or overflowed below 1e-161
     * and above 1e154 and it was called coplanar), and the scale is bounded as for sizes */
    for (k = 0; k < 24; k++) small[k] = 1e-140 * cube[k], big[k] = 1e140 * cube[k], tinypts[k] = 1e-200 * cube[k];
    assert_int_equal(aqs_shape_add_hull(L, 0, small, 8, O, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add_hull(L, 0, big, 8, O, Q1, NULL), AQS_OK);
    big[4] = 2e150;
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, big, 8, O, Q1, NULL), AQS_EINVAL, "points[4] (point 1) = 2e+150", "beyond 1e150");
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 0, tinypts, 8, O, Q1, NULL), AQS_EINVAL, "the 8 points lie within 1e-150", "underflows");
    EXPECT_FAIL(L, aqs_shape_add_hull(L, 9, cube, 8, O, Q1, NULL), AQS_ERANGE, "body = 9", "aqs_shape_add_hull");
    /* filters */
    EXPECT_FAIL(L, aqs_body_set_collision_filter(L, 3, 1, 1), AQS_ERANGE, "aqs_body_set_collision_filter", "body = 3");
    EXPECT_FAIL(L, aqs_collision_exclude_pair(L, 1, 1), AQS_EINVAL, "body_a = body_b = 1", "two bodies");
    EXPECT_FAIL(L, aqs_collision_exclude_pair(L, 0, 4), AQS_ERANGE, "body_b = 4", "aqs_collision_exclude_pair");
    EXPECT_FAIL(L, aqs_linkage_set_collide_joined(L, 2), AQS_EINVAL, "enabled = 2", "0 or 1");
    /* queries before finalize, bad arguments */
    {
        size_t n;
        int32_t hit;
        aqs_contact c[2];
        EXPECT_FAIL(L, aqs_linkage_collide(L, AQS_COLLIDE_LAZY, c, 2, &n), AQS_ESTATE, "aqs_linkage_collide", "not finalized");
        EXPECT_FAIL(L, aqs_linkage_any_contact(L, &hit), AQS_ESTATE, "aqs_linkage_any_contact", "not finalized");
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        EXPECT_FAIL(L, aqs_linkage_collide(L, 3, c, 2, &n), AQS_EINVAL, "mode = 3", "AQS_COLLIDE_");
        EXPECT_FAIL(L, aqs_linkage_collide(L, AQS_COLLIDE_LAZY, c, 2, NULL), AQS_EINVAL, "count", "NULL");
        EXPECT_FAIL(L, aqs_linkage_collide(L, AQS_COLLIDE_LAZY, NULL, 2, &n), AQS_EINVAL, "contacts is NULL", "capacity = 2");
        EXPECT_FAIL(L, aqs_linkage_any_contact(L, NULL), AQS_EINVAL, "hit", "NULL");
    }
    assert_int_equal(aqs_shape_add(NULL, 0, AQS_SHAPE_BOX, sz, O, Q1, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_collide(NULL, 0, NULL, 0, NULL), AQS_EINVAL);
    aqs_linkage_destroy(L);
}

/* Spheres of radius 0.6 on a straight chain 1 m apart overlap their
 * neighbours by 0.2 and nothing else. */
static void test_joined_bodies(void **state)
{
    aqs_linkage *L = chain(4, 0.6, 1);
    aqs_contact c[8];
    size_t n = 0, i;
    assert_int_equal(count_contacts(L), 0); /* joined: excluded by default */
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, c, 8, &n), AQS_OK);
    assert_int_equal(n, 3);
    for (i = 0; i < n; i++) {
        assert_int_equal(c[i].body_b, c[i].body_a + 1);
        assert_int_equal(c[i].shape_a, c[i].body_a);
        assert_true(fabs(c[i].depth - 0.2) < 1e-12);
        assert_true(fabs(c[i].nx - 1.0) < 1e-12); /* from a towards b */
        assert_true(fabs(c[i].px - (c[i].body_a + 0.5)) < 0.1 + 1e-12); /* inside the lens */
    }
    /* exclusions and groups */
    assert_int_equal(aqs_collision_exclude_pair(L, 2, 1), AQS_OK);
    assert_int_equal(aqs_collision_exclude_pair(L, 1, 2), AQS_OK); /* idempotent */
    assert_int_equal(count_contacts(L), 2);
    assert_int_equal(aqs_body_set_collision_filter(L, 0, 2u, 0xFFFFFFFFu), AQS_OK);
    assert_int_equal(count_contacts(L), 2); /* 0's group 2 meets 1's mask all */
    assert_int_equal(aqs_body_set_collision_filter(L, 1, 1u, 1u), AQS_OK);
    assert_int_equal(count_contacts(L), 1); /* 1's mask 1 rejects 0's group 2 */
    assert_int_equal(aqs_linkage_set_collide_joined(L, 0), AQS_OK);
    assert_int_equal(count_contacts(L), 0);
    aqs_linkage_destroy(L);
}

/* Capacity protocol: ESIZE with the total; the first capacity contacts written. */
static void test_capacity(void **state)
{
    aqs_linkage *L = chain(6, 0.6, 1);
    aqs_contact all[8], part[2];
    size_t n = 0, m = 0, i, j;
    int32_t hit = -1;
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_FULL, all, 8, &n), AQS_OK);
    assert_int_equal(n, 5);
    memset(part, 0, sizeof part);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_FULL, part, 2, &m), AQS_ESIZE);
    assert_int_equal(m, 5);
    test_assert_contains(aqs_linkage_last_error(L), "capacity = 2 but 5 contacts");
    for (j = 0; j < 2; j++) {
        int found = 0;
        for (i = 0; i < n; i++) found |= memcmp(&all[i], &part[j], sizeof part[j]) == 0;
        assert_true(found);
    }
    assert_int_equal(aqs_linkage_any_contact(L, &hit), AQS_OK);
    assert_int_equal(hit, 1);
    assert_int_equal(aqs_linkage_set_collide_joined(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_any_contact(L, &hit), AQS_OK);
    assert_int_equal(hit, 0);
    aqs_linkage_destroy(L);
}

/* A pendulum: body 0 revolute about z at the origin, body 1 welded to it
 * at (1, 0, 0) holding a sphere of radius 0.5 at its origin, body 2 welded
 * to 1 with a box; an obstacle sphere of radius 0.5 at (0, -1.8, 0). At
 * q = -pi/2 the welded sphere's centre is at (0, -1, 0): depth 0.2, normal
 * (0, -1, 0) from the body to the obstacle. Welded bodies never collide
 * with each other; the contact names the original body. */
static void test_welded_shapes_follow(void **state)
{
    aqs_linkage *L = test_new_linkage();
    const double one[3] = {1, 0, 0}, r[3] = {0.5, 0, 0}, obst[3] = {0, -1.8, 0}, half[3] = {0.4, 0.4, 0.4};
    aqs_contact c[4];
    size_t n = 0;
    double q = -1.5707963267948966;
    int32_t s;
    test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
    test_add_body(L, 1.0, 0, 0, 0, 0.1);
    test_add_body(L, 1.0, 0, 0, 0, 0.1);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, O, Q1, ZAX, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, one, Q1, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 1, 2, O, Q1, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, 1, AQS_SHAPE_SPHERE, r, O, Q1, &s), AQS_OK);
    assert_int_equal(s, 0);
    assert_int_equal(aqs_shape_add(L, 2, AQS_SHAPE_BOX, half, O, Q1, &s), AQS_OK); /* overlaps shape 0 */
    assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_SPHERE, r, obst, Q1, &s), AQS_OK);
    assert_int_equal(s, 2);
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK); /* welded still never collide */
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(count_contacts(L), 0);
    assert_int_equal(aqs_joint_set_position(L, 0, &q, 1), AQS_OK);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, c, 4, &n), AQS_OK);
    assert_int_equal(n, 2); /* sphere and box against the obstacle */
    if (c[0].shape_a != 0) {
        aqs_contact t = c[0];
        c[0] = c[1];
        c[1] = t;
    }
    assert_int_equal(c[0].body_a, 1);
    assert_int_equal(c[0].shape_a, 0);
    assert_int_equal(c[0].body_b, AQS_WORLD);
    assert_int_equal(c[0].shape_b, 2);
    assert_true(fabs(c[0].depth - 0.2) < 1e-9);
    assert_true(fabs(c[0].nx) < 1e-6 && fabs(c[0].ny + 1.0) < 1e-9 && fabs(c[0].nz) < 1e-6);
    assert_true(fabs(c[0].px) < 1e-6 && c[0].py <= -1.3 + 1e-9 && c[0].py >= -1.5 - 1e-9);
    assert_int_equal(c[1].body_a, 2);
    assert_int_equal(c[1].body_b, AQS_WORLD);
    assert_true(fabs(c[1].depth - 0.1) < 1e-9); /* box face at y = -1.4, obstacle top at -1.3 */
    /* excluding the obstacles for body 2 */
    assert_int_equal(aqs_collision_exclude_pair(L, AQS_WORLD, 2), AQS_OK);
    assert_int_equal(count_contacts(L), 1);
    /* obstacles' own filter */
    assert_int_equal(aqs_body_set_collision_filter(L, AQS_WORLD, 4u, 0xFFFFFFFFu), AQS_OK);
    assert_int_equal(aqs_body_set_collision_filter(L, 1, 1u, 3u), AQS_OK);
    assert_int_equal(count_contacts(L), 0);
    aqs_linkage_destroy(L);
}

/* Shapes added after finalize are picked up; a scene without shapes has no
 * collision state at all. */
static void test_late_shapes_and_no_state(void **state)
{
    aqs_linkage *L = test_new_linkage();
    const double sz[3] = {0.6, 0, 0};
    int32_t i, count = -1;
    for (i = 0; i < 3; i++) {
        double pos[3] = {i ? 1.0 : 0.0, 0, 0};
        test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, Q1, ZAX, NULL), AQS_OK);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(count_contacts(L), 0);
    assert_int_equal(aqs_linkage_step(L, 0.1), AQS_OK);
    assert_null(L->col);
    assert_int_equal(aqs_linkage_get_shape_count(L, &count), AQS_OK);
    assert_int_equal(count, 0);
    assert_int_equal(aqs_shape_add(L, 0, AQS_SHAPE_SPHERE, sz, O, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, 2, AQS_SHAPE_SPHERE, sz, O, Q1, NULL), AQS_OK);
    assert_int_equal(count_contacts(L), 0); /* 2 m apart */
    {
        const double at[3] = {1.9, 0, 0};
        assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_SPHERE, sz, at, Q1, NULL), AQS_OK);
    }
    assert_int_equal(count_contacts(L), 1); /* the obstacle touches body 2's sphere */
    aqs_linkage_destroy(L);
}

/* Penalty contact, closed form: a pendulum (mass 1, centre of mass 0.5 m
 * out, revolute about z) with a sphere of radius 0.1 at its tip (1, 0, 0)
 * falls under gravity onto an obstacle box whose top face is at y = -0.1.
 * Quasi-static steps converge to the rest state where the contact force
 * k depth, applied at the contact point, balances gravity's torque:
 * k depth x_p = m g 0.5 cos q (checked with the reported contact to 1e-9
 * relative once qdd is below 1e-9), so depth = m g 0.5 / k up to the
 * contact point's offset from the tip (|x_p - cos q| <= sqrt(2 r depth):
 * checked to 2%). A user force on the body still acts (it is added to,
 * not replaced by, the contact force). */
static void test_penalty_rest(void **state)
{
    aqs_linkage *L = test_new_linkage();
    const double tip[3] = {1, 0, 0}, r[3] = {0.1, 0, 0}, half[3] = {0.2, 0.5, 0.2}, at[3] = {1.0, -0.6, 0};
    const double g[3] = {0, -9.81, 0}, k = 1e4;
    double q = 0, qdd = 1, pos[3], quat[4];
    aqs_contact c;
    size_t n = 0;
    int step;
    test_add_body(L, 1.0, 0.5, 0, 0, 0.01);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, O, Q1, ZAX, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, 0, AQS_SHAPE_SPHERE, r, tip, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_BOX, half, at, Q1, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, k), AQS_ESTATE);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, -1.0), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "stiffness = -1");
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, NAN), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, k), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    for (step = 0; step < 400; step++) assert_int_equal(aqs_linkage_step(L, sqrt(1e-5)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_joint_get_acceleration(L, 0, &qdd, 1), AQS_OK);
    assert_int_equal(aqs_joint_get_position(L, 0, &q, 1), AQS_OK);
    assert_true(fabs(qdd) < 1e-9);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, &c, 1, &n), AQS_OK);
    assert_int_equal(n, 1);
    assert_true(fabs(c.ny + 1.0) < 1e-6); /* from the sphere down into the box */
    {
        double torque_contact = k * c.depth * (c.px * (-c.ny) - c.py * (-c.nx)); /* (p x F)_z, F = -k d n */
        double torque_gravity = 9.81 * 0.5 * cos(q);
        assert_true(fabs(torque_contact - torque_gravity) <= 1e-9 * torque_gravity + 1e-9 * 0.26);
        assert_true(fabs(c.depth - 9.81 * 0.5 / k) <= 0.02 * 9.81 * 0.5 / k);
    }
    assert_int_equal(aqs_body_get_pose_world(L, 0, pos, quat), AQS_OK);
    /* a user force pressing the tip down by 10 N: the new rest depth adds 10 / k */
    {
        const double f[3] = {0, -10.0, 0}, pt[3] = {1, 0, 0};
        assert_int_equal(aqs_body_set_force(L, 0, f, pt, NULL), AQS_OK);
        for (step = 0; step < 400; step++) assert_int_equal(aqs_linkage_step(L, sqrt(1e-5)), AQS_OK);
        assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, &c, 1, &n), AQS_OK);
        assert_true(fabs(c.depth - (9.81 * 0.5 + 10.0) / k) <= 0.02 * (9.81 * 0.5 + 10.0) / k);
        /* clear_forces removes the user force but keeps the contact
         * stiffness: back to the gravity-only rest depth; then the force again */
        assert_int_equal(aqs_linkage_clear_forces(L), AQS_OK);
        for (step = 0; step < 400; step++) assert_int_equal(aqs_linkage_step(L, sqrt(1e-5)), AQS_OK);
        assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, &c, 1, &n), AQS_OK);
        assert_true(fabs(c.depth - 9.81 * 0.5 / k) <= 0.02 * 9.81 * 0.5 / k);
        assert_int_equal(aqs_body_set_force(L, 0, f, pt, NULL), AQS_OK);
        for (step = 0; step < 400; step++) assert_int_equal(aqs_linkage_step(L, sqrt(1e-5)), AQS_OK);
    }
    /* off again: the pendulum falls through */
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, 0.0), AQS_OK);
    for (step = 0; step < 50; step++) assert_int_equal(aqs_linkage_step(L, sqrt(1e-5)), AQS_OK);
    assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, &c, 1, &n), AQS_OK);
    assert_true(c.depth > 3.0 * (9.81 * 0.5 + 10.0) / k);
    /* with penalty on, a filter change changes the loads: no refine of the last solve */
    assert_int_equal(aqs_linkage_set_contact_stiffness(L, k), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_refine(L, 1e-4), AQS_OK);
    assert_int_equal(aqs_collision_exclude_pair(L, 0, AQS_WORLD), AQS_OK);
    assert_int_equal(aqs_linkage_refine(L, 1e-6), AQS_ESTATE);
    aqs_linkage_destroy(L);
}

/* A chain of 4 links with tip spheres, hinged to the world, falls onto a
 * floor (stiffness 300, dt 0.01: dt^2 k / I well inside the stable range of
 * the quasi-static update) and comes to rest: max |qdd| below 1e-6 with
 * three or more links in contact; adaptive steps reach the same rest state as exact ones (the
 * same positions to 1e-6). */
static void test_penalty_chain_rests(void **state)
{
    double qa[4], qe[4];
    int pass;
    for (pass = 0; pass < 2; pass++) {
        aqs_linkage *L = test_new_linkage();
        const double r[3] = {0.1, 0, 0}, tipp[3] = {1, 0, 0}, floor_half[3] = {10, 0.5, 10};
        const double floor_at[3] = {3, -0.7, 0}, g[3] = {0, -9.81, 0};
        double qdd[4], m = 0;
        size_t n = 0;
        int32_t i;
        for (i = 0; i < 4; i++) {
            double pos[3] = {i ? 1.0 : 0.0, 0, 0};
            test_add_body(L, 1.0, 0.5, 0, 0, 0.01);
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, Q1, ZAX, NULL), AQS_OK);
            assert_int_equal(aqs_shape_add(L, i, AQS_SHAPE_SPHERE, r, tipp, Q1, NULL), AQS_OK);
        }
        assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_BOX, floor_half, floor_at, Q1, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
        assert_int_equal(aqs_linkage_set_contact_stiffness(L, 300.0), AQS_OK);
        if (pass == 1) assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
        for (i = 0; i < 1500; i++) assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(L, qdd, 4), AQS_OK);
        for (i = 0; i < 4; i++) m = fmax(m, fabs(qdd[i]));
        assert_true(m < 1e-6);
        assert_int_equal(aqs_linkage_collide(L, AQS_COLLIDE_LAZY, NULL, 0, &n), AQS_ESIZE);
        assert_true(n >= 3);
        assert_int_equal(aqs_linkage_get_positions(L, pass ? qa : qe, 4), AQS_OK);
        aqs_linkage_destroy(L);
    }
    assert_true(test_max_abs_diff(qa, qe, 4) < 1e-6);
}

/* The error paths of the collision getters and setters not covered above.
 * A NULL linkage is AQS_EINVAL for each of them, writes nothing through
 * the out pointers, and (with no linkage to hold a message) the last error
 * is the fixed NULL-linkage text naming the argument. A NULL count is
 * AQS_EINVAL naming the function and the argument, and changes nothing.
 * aqs_linkage_get_collision_stats takes no struct (so there is no size to
 * get wrong): each out pointer may be NULL, and reading the statistics
 * changes neither them nor the contacts. */
static void test_collision_api_errors(void **state)
{
    static const double cube[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
    aqs_linkage *L = chain(4, 0.6, 0);
    int32_t count = -7, hit = -7, out = -7, st[4] = {-7, -7, -7, -7}, st2[4], k, ns = -1;
    size_t n0, n1;
    (void)state;
    /* NULL linkage */
    assert_int_equal(aqs_linkage_get_shape_count(NULL, &count), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_shape_count(NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_collision_stats(NULL, &st[0], &st[1], &st[2], &st[3]), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_collision_stats(NULL, NULL, NULL, NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_body_set_collision_filter(NULL, 0, 1u, 1u), AQS_EINVAL);
    assert_int_equal(aqs_body_set_collision_filter(NULL, AQS_WORLD, 1u, 1u), AQS_EINVAL);
    assert_int_equal(aqs_collision_exclude_pair(NULL, 0, 1), AQS_EINVAL);
    assert_int_equal(aqs_collision_exclude_pair(NULL, AQS_WORLD, 0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_any_contact(NULL, &hit), AQS_EINVAL);
    assert_int_equal(aqs_linkage_any_contact(NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_collide_joined(NULL, 1), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_collide_joined(NULL, 0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_contact_stiffness(NULL, 100.0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_contact_stiffness(NULL, 0.0), AQS_EINVAL);
    assert_int_equal(aqs_shape_add_hull(NULL, 0, cube, 8, O, Q1, &out), AQS_EINVAL);
    assert_int_equal(aqs_shape_add_hull(NULL, AQS_WORLD, cube, 8, O, Q1, &out), AQS_EINVAL);
    assert_int_equal(count, -7);
    assert_int_equal(hit, -7);
    assert_int_equal(out, -7);
    for (k = 0; k < 4; k++) assert_int_equal(st[k], -7);
    test_assert_contains(aqs_linkage_last_error(NULL), "linkage is NULL");
    assert_string_equal(aqs_linkage_last_error(L), ""); /* L saw none of it */

    /* NULL count: before and after finalize; nothing changes */
    EXPECT_FAIL(L, aqs_linkage_get_shape_count(L, NULL), AQS_EINVAL, "aqs_linkage_get_shape_count", "count is NULL");
    assert_int_equal(aqs_linkage_get_shape_count(L, &ns), AQS_OK);
    assert_int_equal(ns, 4);
    /* statistics before any query: all 0, NULL outputs accepted */
    assert_int_equal(aqs_linkage_get_collision_stats(L, &st[0], &st[1], &st[2], &st[3]), AQS_OK);
    for (k = 0; k < 4; k++) assert_int_equal(st[k], 0);
    assert_int_equal(aqs_linkage_get_collision_stats(L, NULL, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    n0 = count_contacts(L);
    assert_int_equal(n0, 3);
    EXPECT_FAIL(L, aqs_linkage_get_shape_count(L, NULL), AQS_EINVAL, "aqs_linkage_get_shape_count", "count is NULL");
    n1 = count_contacts(L);
    assert_int_equal(n1, n0);
    /* statistics of that query: each output alone gives the same value as
     * all four together, and reading does not reset them */
    assert_int_equal(aqs_linkage_get_collision_stats(L, &st[0], &st[1], &st[2], &st[3]), AQS_OK);
    assert_true(st[2] >= 3); /* at least the three touching pairs reached libccd */
    for (k = 0; k < 4; k++) st2[k] = -7;
    assert_int_equal(aqs_linkage_get_collision_stats(L, &st2[0], NULL, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_get_collision_stats(L, NULL, &st2[1], NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_get_collision_stats(L, NULL, NULL, &st2[2], NULL), AQS_OK);
    assert_int_equal(aqs_linkage_get_collision_stats(L, NULL, NULL, NULL, &st2[3]), AQS_OK);
    for (k = 0; k < 4; k++) assert_int_equal(st2[k], st[k]);
    assert_int_equal(aqs_linkage_get_collision_stats(L, NULL, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_get_collision_stats(L, &st2[0], &st2[1], &st2[2], &st2[3]), AQS_OK);
    for (k = 0; k < 4; k++) assert_int_equal(st2[k], st[k]);
    assert_int_equal(count_contacts(L), n0);
    aqs_linkage_destroy(L);
}

/* A hull's interior points change nothing: its centre (MPR's interior point)
 * comes from the hull's extreme points (src/collide/shape.c, hull_centre).
 * A box given by its 8 corners, and the same box with 30 interior points
 * clustered in one corner (listed first), against a sphere obstacle at 1,000
 * random placements, shallow to deep (the sphere's centre anywhere inside):
 * the same contacts, bit for bit. Until 2026-12-05 the centre was the
 * centroid of all the points, and deep contacts' depths differed by up to
 * 1.07 between the two (MPR's estimate moves with its interior point). */
static void hull_box_scene(aqs_linkage *L, const double *pts, int32_t npts)
{
    const double com[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z3[3] = {0, 0, 0};
    const double q1[4] = {1, 0, 0, 0}, r[3] = {0.1, 0, 0};
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FREE, AQS_WORLD, 0, z3, q1, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add_hull(L, 0, pts, npts, z3, q1, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_SPHERE, r, z3, q1, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
}

static void test_hull_interior_points(void **state)
{
    const double h[3] = {0.3, 0.5, 0.7};
    double corners[24], more[114];
    aqs_linkage *A = test_new_linkage(), *B = test_new_linkage();
    uint64_t rng = 11;
    int32_t i, k, deep = 0;
    (void)state;
    for (i = 0; i < 8; i++)
        for (k = 0; k < 3; k++) corners[3 * i + k] = (i >> k & 1 ? 1.0 : -1.0) * h[k];
    for (i = 0; i < 30; i++)
        for (k = 0; k < 3; k++) more[3 * i + k] = test_uniform(&rng, 0.5, 0.99) * h[k];
    memcpy(more + 90, corners, sizeof corners);
    hull_box_scene(A, corners, 8);
    hull_box_scene(B, more, 38);
    for (i = 0; i < 1000; i++) {
        double q[7] = {0, 0, 0, 1, 0, 0, 0}, w;
        aqs_contact ca[2], cb[2];
        size_t na = 0, nb = 0;
        for (k = 0; k < 3; k++) q[k] = test_uniform(&rng, -1.05, 1.05) * h[k]; /* the hull at -p: p in the box mostly */
        for (k = 0; k < 4; k++) q[3 + k] = test_uniform(&rng, -1, 1);
        w = sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]);
        for (k = 0; k < 4; k++) q[3 + k] /= w;
        assert_int_equal(aqs_linkage_set_positions(A, q, 7), AQS_OK);
        assert_int_equal(aqs_linkage_set_positions(B, q, 7), AQS_OK);
        memset(ca, 0, sizeof ca);
        memset(cb, 0, sizeof cb);
        assert_int_equal(aqs_linkage_collide(A, AQS_COLLIDE_LAZY, ca, 2, &na), AQS_OK);
        assert_int_equal(aqs_linkage_collide(B, AQS_COLLIDE_LAZY, cb, 2, &nb), AQS_OK);
        assert_true(na == nb && na <= 1);
        assert_memory_equal(ca, cb, sizeof ca);
        if (na == 1 && ca[0].depth > 0.1) deep++;
    }
    assert_true(deep > 300); /* most placements are deep: where the centre mattered */
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
}

/* aqs_linkage_get_query_stats: the size-versioned statistics agree with the
 * four-pointer getter and with the collision state's own counters (read
 * through src/collide/collide.h), size covers what is written, and bad arguments
 * are AQS_EINVAL naming them. */
static void test_query_stats(void **state)
{
    aqs_linkage *L = chain(6, 0.6, 1);
    aqs_collision_stats cs, small;
    int32_t st[4];
    int k;
    (void)state;
    memset(&cs, 0x5a, sizeof cs);
    cs.size = sizeof cs;
    assert_int_equal(aqs_linkage_get_query_stats(NULL, &cs), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_query_stats(L, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "stats is NULL");
    cs.size = 7;
    assert_int_equal(aqs_linkage_get_query_stats(L, &cs), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "stats->size = 7");
    cs.size = sizeof cs; /* before any query: zeros */
    assert_int_equal(aqs_linkage_get_query_stats(L, &cs), AQS_OK);
    assert_int_equal(cs.size, sizeof cs);
    assert_true(cs.nodes_refit == 0 && cs.volume_tests == 0 && cs.near_tests == 0);
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    for (k = 0; k < 3; k++) {
        double q = 0.05 * (k + 1);
        assert_true(count_contacts(L) > 0);
        cs.size = sizeof cs;
        assert_int_equal(aqs_linkage_get_query_stats(L, &cs), AQS_OK);
        assert_int_equal(aqs_linkage_get_collision_stats(L, &st[0], &st[1], &st[2], &st[3]), AQS_OK);
        assert_int_equal(cs.nodes_refit, st[0]);
        assert_int_equal(cs.volume_tests, st[1]);
        assert_int_equal(cs.narrow_tests, st[2]);
        assert_int_equal(cs.nodes_skipped, st[3]);
        assert_int_equal(cs.certs_reused, L->col->certs_reused);
        assert_int_equal(cs.certs_made, L->col->certs_made);
        assert_int_equal(cs.near_tests, L->col->near_tests);
        assert_true(cs.narrow_tests >= 5); /* the touching neighbours reached libccd */
        assert_int_equal(aqs_joint_set_position(L, 2, &q, 1), AQS_OK);
    }
    /* an older caller's smaller struct: only what its size covers */
    memset(&small, 0x5a, sizeof small);
    small.size = 12;
    assert_int_equal(aqs_linkage_get_query_stats(L, &small), AQS_OK);
    assert_int_equal(small.size, 12);
    assert_int_equal(small.nodes_refit, cs.nodes_refit);
    assert_int_equal(small.volume_tests, cs.volume_tests);
    memset(&cs, 0x5a, sizeof cs);
    assert_memory_equal(&small.narrow_tests, &cs.narrow_tests, sizeof cs - offsetof(aqs_collision_stats, narrow_tests));
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_shapes),
        cmocka_unit_test(test_joined_bodies),
        cmocka_unit_test(test_capacity),
        cmocka_unit_test(test_welded_shapes_follow),
        cmocka_unit_test(test_late_shapes_and_no_state),
        cmocka_unit_test(test_penalty_rest),
        cmocka_unit_test(test_penalty_chain_rests),
        cmocka_unit_test(test_collision_api_errors),
        cmocka_unit_test(test_hull_interior_points),
        cmocka_unit_test(test_query_stats),
    };
    return cmocka_run_group_tests_name("collide", tests, NULL, NULL);
}
