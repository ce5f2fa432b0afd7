/* test_model.c -- src/model/model.c through the public API: every validation rule
 * of aqs_body_add, aqs_joint_add and aqs_linkage_finalize with its status
 * code and a message naming the offending index or value; massless bodies
 * (accepted only when welded to mass or to the world); and a failed
 * finalize leaves the linkage editable, fixable and finalizable. */
#include "testutil.h"

#include <math.h>
#include <string.h>

#define G 9.81

static const double zero3[3] = {0, 0, 0}, ident_quat[4] = {1, 0, 0, 0}, zaxis[3] = {0, 0, 1};

static int32_t body_count(const aqs_linkage *L)
{
    int32_t n = -1;
    assert_int_equal(aqs_linkage_get_sizes(L, &n, NULL, NULL, NULL), AQS_OK);
    return n;
}

static int32_t joint_count(const aqs_linkage *L)
{
    int32_t n = -1;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, &n, NULL, NULL), AQS_OK);
    return n;
}

/* Add a body with a diagonal inertia. */
static aqs_status add_body_diag(aqs_linkage *L, double m, double cx, double ixx, double iyy,
                                double izz, int32_t *out)
{
    double com[3] = {cx, 0, 0}, I[9] = {ixx, 0, 0, 0, iyy, 0, 0, 0, izz};
    return aqs_body_add(L, m, com, I, out);
}

/* The pendulum of test_dca: com at distance len on x, about z, gravity -y:
 * qdd = -m g len cos(q) / (Izz + m len^2). Rounding is a few ulps of O(1)
 * values, so the solved value must agree to 1e-12 relative. */
static void assert_pendulum(aqs_linkage *L, double q, double m, double len, double izz)
{
    double g[3] = {0, -G, 0}, qdd, expect = -m * G * len * cos(q) / (izz + m * len * len);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_joint_set_position(L, 0, &q, 1), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_joint_get_acceleration(L, 0, &qdd, 1), AQS_OK);
    assert_true(fabs(qdd - expect) <= 1e-12 * fabs(expect));
}

/* ------------------------------------------------------------- bodies */

static void test_mass(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double com[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    (void)state;
    assert_int_equal(aqs_body_add(L, -1.5, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_body_add");
    test_assert_contains(aqs_linkage_last_error(L), "mass = -1.5");
    assert_int_equal(aqs_body_add(L, NAN, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "mass = nan");
    assert_int_equal(aqs_body_add(L, INFINITY, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "mass = inf");
    assert_int_equal(aqs_body_add(L, -0.0 - 1e-300, com, I, NULL), AQS_EINVAL);
    com[2] = NAN;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "com[2] = nan");
    com[2] = 0;
    I[4] = -INFINITY;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "inertia[4] = -inf");
    assert_int_equal(body_count(L), 0); /* nothing was added */
    I[4] = 1;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_OK); /* control */
    assert_int_equal(body_count(L), 1);
    aqs_linkage_destroy(L);
}

static void test_inertia_symmetric(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double com[3] = {0, 0, 0}, I[9] = {1, 0.1, 0, 0.2, 1, 0, 0, 0, 1};
    (void)state;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "not symmetric");
    test_assert_contains(aqs_linkage_last_error(L), "inertia[0][1] = 0.1");
    test_assert_contains(aqs_linkage_last_error(L), "inertia[1][0] = 0.2");
    /* (1, 2) against (2, 1) */
    I[3] = 0.1;
    I[5] = 0.05;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "inertia[1][2] = 0.05");
    /* within the relative 1e-9 of the header: accepted */
    I[7] = 0.05 * (1 + 1e-12);
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_OK);
    /* just outside: 2e-9 of the largest entry (1) */
    I[7] = 0.05 + 2e-9;
    assert_int_equal(aqs_body_add(L, 1.0, com, I, NULL), AQS_EINVAL);
    assert_int_equal(body_count(L), 1);
    aqs_linkage_destroy(L);
}

/* One rule at aqs_body_add for every mass (positive semi-definite), and
 * positive definiteness required of each moving rigid group at finalize. */
static void test_inertia_definite(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double com[3] = {0, 0, 0}, off[3] = {0.1, -0.2, 0.05};
    double notpd[9] = {1, 2, 0, 2, 1, 0, 0, 0, 1}; /* eigenvalues -1, 1, 3 */
    double psd[9] = {1, 0, 0, 0, 1, 0, 0, 0, 0};   /* eigenvalues 0, 1, 1 */
    double zero[9] = {0}, unit[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double pos[3] = {0.3, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    (void)state;
    assert_int_equal(aqs_body_add(L, 1.0, com, notpd, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "not positive semi-definite");
    test_assert_contains(aqs_linkage_last_error(L), "-1");
    assert_int_equal(aqs_body_add(L, 0.0, com, notpd, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "semi-definite");
    /* (0.01, zeros) is accepted exactly as (0, zeros) is */
    assert_int_equal(aqs_body_add(L, 1.0, com, unit, NULL), AQS_OK);  /* 0 */
    assert_int_equal(aqs_body_add(L, 0.01, off, zero, NULL), AQS_OK); /* 1 point mass */
    assert_int_equal(aqs_body_add(L, 0.0, com, zero, NULL), AQS_OK);  /* 2 massless */
    assert_int_equal(aqs_body_add(L, 1.0, com, psd, NULL), AQS_OK);   /* 3 a rod */
    assert_int_equal(body_count(L), 4);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, pos, quat, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 1, 2, pos, quat, NULL, NULL), AQS_OK);
    /* the rod moves alone: its group (itself) has a singular inertia */
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 2, 3, pos, quat, axis, NULL), AQS_OK);
    assert_int_equal(aqs_body_set_name(L, 3, "rod"), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
    test_assert_contains(aqs_linkage_last_error(L), "body 3 'rod' (welded to no other body) has a singular inertia");
    aqs_linkage_destroy(L);

    /* A point mass moving alone: singular; welded to the rod, whose axis it
     * is off: the group is definite and finalize accepts it. */
    L = test_new_linkage();
    assert_int_equal(aqs_body_add(L, 0.01, off, zero, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
    test_assert_contains(aqs_linkage_last_error(L), "body 0 (welded to no other body) has a singular inertia (total mass 0.01)");
    aqs_linkage_destroy(L);
    L = test_new_linkage();
    assert_int_equal(aqs_body_add(L, 1.0, com, psd, NULL), AQS_OK);
    assert_int_equal(aqs_body_add(L, 0.01, com, zero, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, 0, 1, off, quat, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    aqs_linkage_destroy(L);

    /* The lax check accepts an indefinite body; its group is still checked. */
    L = test_new_linkage();
    assert_int_equal(aqs_linkage_set_inertia_check(L, 0), AQS_OK);
    assert_int_equal(aqs_body_add(L, 1.0, com, notpd, NULL), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
    test_assert_contains(aqs_linkage_last_error(L), "singular inertia");
    aqs_linkage_destroy(L);

    /* A definite inertia whose centre of mass lies 1e10 m from its frame: the
     * 6 x 6 spatial inertia there does not factor. The message says why (it
     * said "a singular inertia" until 2026-12-05); 1e8 m is accepted. */
    {
        const double I3[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, far[3] = {1e10, 0, 0}, near[3] = {1e8, 0, 0};
        L = test_new_linkage();
        assert_int_equal(aqs_body_add(L, 2.0, far, I3, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "inertia about its centre of mass is definite");
        test_assert_contains(aqs_linkage_last_error(L), "the centre of mass lies 1e+10 from the frame's origin");
        aqs_linkage_destroy(L);
        L = test_new_linkage();
        assert_int_equal(aqs_body_add(L, 2.0, near, I3, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, quat, axis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        aqs_linkage_destroy(L);
    }
}

static void test_inertia_triangle(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double com[3] = {0, 0, 0};
    double bad[9] = {1, 0, 0, 0, 1, 0, 0, 0, 3};     /* 1 + 1 < 3 */
    double lamina[9] = {1, 0, 0, 0, 1, 0, 0, 0, 2};  /* 1 + 1 = 2: a flat plate */
    /* bad rotated by 45 degrees about x: same principal moments, no zeros */
    double rot[9] = {1, 0, 0, 0, 2, -1, 0, -1, 2};
    (void)state;
    assert_int_equal(aqs_body_add(L, 1.0, com, bad, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "triangle inequality");
    test_assert_contains(aqs_linkage_last_error(L), "1, 1, 3");
    assert_int_equal(aqs_body_add(L, 1.0, com, rot, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "triangle inequality");
    assert_int_equal(aqs_body_add(L, 1.0, com, lamina, NULL), AQS_OK);
    /* the check can be switched off for synthetic models, and on again */
    assert_int_equal(aqs_linkage_set_inertia_check(L, 0), AQS_OK);
    assert_int_equal(aqs_body_add(L, 1.0, com, bad, NULL), AQS_OK);
    assert_int_equal(aqs_body_add(L, 1.0, com, rot, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_inertia_check(L, 1), AQS_OK);
    assert_int_equal(aqs_body_add(L, 1.0, com, bad, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_inertia_check(L, 2), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "physical = 2");
    assert_int_equal(body_count(L), 3);
    /* a lax model finalizes and solves: three bodies on one axis */
    {
        int32_t b;
        assert_int_equal(aqs_linkage_set_inertia_check(L, 0), AQS_OK);
        for (b = 0; b < 3; b++)
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, b == 0 ? AQS_WORLD : b - 1, b, zero3,
                                           ident_quat, zaxis, NULL),
                             AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_set_inertia_check(L, 1), AQS_ESTATE);
        test_assert_contains(aqs_linkage_last_error(L), "finalized");
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    }
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------- massless bodies */

static void test_massless(void **state)
{
    const double m = 2.0, len = 0.6, izz = 0.25, q = 0.4;
    (void)state;
    /* welded to the world, a pendulum hanging from it */
    {
        aqs_linkage *L = test_new_linkage();
        double p[3] = {0.3, 0.2, 0};
        int32_t b0, b1;
        assert_int_equal(add_body_diag(L, 0.0, 0, 0, 0, 0, &b0), AQS_OK);
        assert_int_equal(add_body_diag(L, m, len, 0.2, 0.2, izz, &b1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, b0, b1, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, AQS_WORLD, b0, p, ident_quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_pendulum(L, q, m, len, izz);
        aqs_linkage_destroy(L);
    }
    /* welded as the child of a massive body: adds nothing */
    {
        aqs_linkage *L = test_new_linkage();
        double p[3] = {0.5, 0, 0};
        int32_t b0, b1;
        assert_int_equal(add_body_diag(L, m, len, 0.2, 0.2, izz, &b0), AQS_OK);
        assert_int_equal(add_body_diag(L, 0.0, 0.1, 0, 0, 0, &b1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, b0, b1, p, ident_quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_pendulum(L, q, m, len, izz);
        aqs_linkage_destroy(L);
    }
    /* a massless body on the joint carrying a massive body welded to it at
     * distance d: a pendulum of length d + len */
    {
        aqs_linkage *L = test_new_linkage();
        double d = 0.7, p[3] = {0.7, 0, 0};
        int32_t b0, b1;
        assert_int_equal(add_body_diag(L, 0.0, 0, 0, 0, 0, &b0), AQS_OK);
        assert_int_equal(add_body_diag(L, m, len, 0.2, 0.2, izz, &b1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, b0, b1, p, ident_quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_pendulum(L, q, m, d + len, izz);
        aqs_linkage_destroy(L);
    }
    /* a massless body on a moving joint with nothing welded: rejected,
     * naming the body; two massless bodies welded together: rejected too */
    {
        aqs_linkage *L = test_new_linkage();
        int32_t b0, b1, b2;
        assert_int_equal(add_body_diag(L, m, len, 0.2, 0.2, izz, &b0), AQS_OK);
        assert_int_equal(add_body_diag(L, 0.0, 0, 0, 0, 0, &b1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, b0, b1, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_finalize");
        test_assert_contains(aqs_linkage_last_error(L), "body 1 ");
        test_assert_contains(aqs_linkage_last_error(L), "mass 0");
        /* weld another massless body to it: still no mass */
        assert_int_equal(add_body_diag(L, 0.0, 0, 0, 0, 0, &b2), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, b1, b2, zaxis, ident_quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 1 ");
        aqs_linkage_destroy(L);
    }
}

/* -------------------------------------------------------------- topology */

static aqs_linkage *bodies(int n)
{
    aqs_linkage *L = test_new_linkage();
    int i;
    for (i = 0; i < n; i++) test_add_body(L, 1.0, 0.1, 0, 0, 0.1);
    return L;
}

static void test_topology(void **state)
{
    (void)state;
    /* empty */
    {
        aqs_linkage *L = test_new_linkage();
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "no body");
        aqs_linkage_destroy(L);
    }
    /* a body with no parent joint */
    {
        aqs_linkage *L = bodies(3);
        test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 0, 2, 0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 1 has no parent joint");
        aqs_linkage_destroy(L);
    }
    /* a body with two parent joints */
    {
        aqs_linkage *L = bodies(2);
        test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 0, 1, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_PRISMATIC, AQS_WORLD, 1, 0, 0, 0, 1, 0, 0);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 1 is the child of two joints (1 and 2)");
        aqs_linkage_destroy(L);
    }
    /* a cycle: bodies 1 and 2 each the child of the other, so each has one
     * parent joint but neither reaches the world */
    {
        aqs_linkage *L = bodies(3);
        test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 1, 2, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 2, 1, 0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 1 is not connected to the world");
        aqs_linkage_destroy(L);
    }
    /* a longer cycle hanging off nothing: 0 -> 1 -> 2 -> 0, all from bodies */
    {
        aqs_linkage *L = bodies(4);
        test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 3, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 2, 0, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 0, 1, 0, 0, 0, 0, 0, 1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, 1, 2, 0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 0 is not connected to the world");
        aqs_linkage_destroy(L);
    }
    /* a body as its own parent */
    {
        aqs_linkage *L = bodies(1);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, 0, 0, zero3, ident_quat, zaxis, NULL), AQS_EINVAL);
        test_assert_contains(aqs_linkage_last_error(L), "parent = child = 0");
        assert_int_equal(joint_count(L), 0);
        aqs_linkage_destroy(L);
    }
    /* a free joint from a body: rejected when added (aqs_joint_add checks
     * it already; aqs.h lists it among the finalize checks) */
    {
        aqs_linkage *L = bodies(2);
        test_add_joint(L, AQS_JOINT_FREE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FREE, 0, 1, zero3, ident_quat, NULL, NULL), AQS_EINVAL);
        test_assert_contains(aqs_linkage_last_error(L), "free joint");
        test_assert_contains(aqs_linkage_last_error(L), "parent = 0");
        assert_int_equal(joint_count(L), 1);
        test_add_joint(L, AQS_JOINT_SPHERICAL, 0, 1, 0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK); /* a floating base with a ball joint */
        aqs_linkage_destroy(L);
    }
}

/* ------------------------------------------------------ joint arguments */

static void test_joint_arguments(void **state)
{
    aqs_linkage *L = bodies(2);
    double axis[3] = {0, 0, 0}, quat[4] = {1.01, 0, 0, 0}, pos[3] = {0, 0, NAN};
    (void)state;
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, zero3, ident_quat, axis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "axis = (0, 0, 0) is zero");
    axis[1] = 1e-13; /* below the 1e-12 floor: zero */
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_CYLINDRICAL, AQS_WORLD, 0, zero3, ident_quat, axis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "is zero");
    axis[1] = NAN;
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_PLANAR, AQS_WORLD, 0, zero3, ident_quat, axis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "axis[1] = nan");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_UNIVERSAL, AQS_WORLD, 0, zero3, ident_quat, NULL, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "axis is NULL");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_PRISMATIC, AQS_WORLD, 0, zero3, quat, zaxis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "quat has norm 1.01");
    quat[0] = 0;
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, AQS_WORLD, 0, zero3, quat, NULL, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "quat has norm 0");
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, pos, ident_quat, zaxis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "pos[2] = nan");
    assert_int_equal(aqs_joint_add(L, 8, AQS_WORLD, 0, zero3, ident_quat, zaxis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "type = 8");
    assert_int_equal(aqs_joint_add(L, -1, AQS_WORLD, 0, zero3, ident_quat, zaxis, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "type = -1");
    assert_int_equal(joint_count(L), 0);

    /* Accepted: a quaternion within 1e-6 of unit (normalized), an axis of
     * any length (normalized), a NULL axis where it is ignored. */
    {
        double s = sqrt(0.5) * (1 + 8e-7), q45[4] = {s, 0, 0, s}, ax2[3] = {0, 0, 2};
        double p[3], qw[4], d = 1.5, n;
        int32_t j0, j1;
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_PRISMATIC, AQS_WORLD, 0, zero3, q45, ax2, &j0), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_SPHERICAL, 0, 1, zero3, ident_quat, NULL, &j1), AQS_OK);
        assert_int_equal(j0, 0);
        assert_int_equal(j1, 1);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_joint_set_position(L, 0, &d, 1), AQS_OK);
        assert_int_equal(aqs_body_get_pose_world(L, 0, p, qw), AQS_OK);
        /* the joint frame is turned 90 degrees about z; its z axis is the
         * world z: the body moved by d (not 2 d) along z, and its
         * orientation is the normalized quaternion */
        assert_true(fabs(p[0]) < 1e-15 && fabs(p[1]) < 1e-15 && fabs(p[2] - d) < 1e-15);
        n = sqrt(qw[0] * qw[0] + qw[1] * qw[1] + qw[2] * qw[2] + qw[3] * qw[3]);
        assert_true(fabs(n - 1) < 1e-15);
        assert_true(fabs(qw[0] - sqrt(0.5)) < 1e-15 && fabs(qw[3] - sqrt(0.5)) < 1e-15);
    }
    aqs_linkage_destroy(L);
}

/* ------------------------------------------ fixing after a failed finalize */

static void test_fix_after_failure(void **state)
{
    const double m = 1.5, len = 0.8, izz = 0.2, q = -0.3;
    (void)state;
    /* a missing parent joint, then added */
    {
        aqs_linkage *L = test_new_linkage();
        int32_t b0;
        assert_int_equal(add_body_diag(L, m, len, 0.1, 0.1, izz, &b0), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 0 has no parent joint");
        /* still in the building phase: not finalized, editable */
        assert_int_equal(aqs_linkage_get_tree_stats(L, NULL, NULL, NULL, NULL), AQS_ESTATE);
        assert_int_equal(aqs_linkage_solve(L), AQS_ESTATE);
        assert_int_equal(aqs_linkage_set_inertia_check(L, 1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_pendulum(L, q, m, len, izz);
        aqs_linkage_destroy(L);
    }
    /* a massless body, then a massive body welded to it */
    {
        aqs_linkage *L = test_new_linkage();
        double p[3] = {0.4, 0, 0};
        int32_t b0, b1, nodes;
        assert_int_equal(add_body_diag(L, 0.0, 0, 0, 0, 0, &b0), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        test_assert_contains(aqs_linkage_last_error(L), "body 0 ");
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL); /* repeatable */
        assert_int_equal(add_body_diag(L, m, len, 0.1, 0.1, izz, &b1), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, b0, b1, p, ident_quat, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_tree_stats(L, &nodes, NULL, NULL, NULL), AQS_OK);
        assert_int_equal(nodes, 3); /* world leaf, one composite, one joint */
        assert_pendulum(L, q, m, 0.4 + len, izz);
        /* finalized now: a second finalize is a phase error */
        assert_int_equal(aqs_linkage_finalize(L), AQS_ESTATE);
        aqs_linkage_destroy(L);
    }
    /* an empty linkage, then filled */
    {
        aqs_linkage *L = test_new_linkage();
        int32_t b0;
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL);
        assert_int_equal(aqs_linkage_finalize(L), AQS_EMODEL); /* repeatable */
        assert_int_equal(add_body_diag(L, m, len, 0.1, 0.1, izz, &b0), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b0, zero3, ident_quat, zaxis, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_pendulum(L, q, m, len, izz);
        aqs_linkage_destroy(L);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mass),
        cmocka_unit_test(test_inertia_symmetric),
        cmocka_unit_test(test_inertia_definite),
        cmocka_unit_test(test_inertia_triangle),
        cmocka_unit_test(test_massless),
        cmocka_unit_test(test_topology),
        cmocka_unit_test(test_joint_arguments),
        cmocka_unit_test(test_fix_after_failure),
    };
    return cmocka_run_group_tests_name("model", tests, NULL, NULL);
}
