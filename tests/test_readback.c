/* test_readback.c -- src/api/readback.c: aqs_body_get_inertial and
 * aqs_joint_get_definition return what was added (after the documented
 * normalization: quaternion and axis divided by their norms, the quaternion
 * negated when its w is negative, inertia symmetrized), in every phase, for every joint type; NULL out pointers are
 * accepted; bad indices and a NULL linkage fail without writing anything. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NB 8

static const int32_t types[NB] = {AQS_JOINT_FREE,     AQS_JOINT_REVOLUTE,  AQS_JOINT_SPHERICAL,
                                  AQS_JOINT_FIXED,    AQS_JOINT_PLANAR,    AQS_JOINT_UNIVERSAL,
                                  AQS_JOINT_PRISMATIC, AQS_JOINT_CYLINDRICAL};
static const int32_t parents[NB] = {AQS_WORLD, 0, 1, 0, 3, 4, 2, 6};

/* Inputs of body / joint i, deliberately not normalized. */
static void body_input(int i, double *mass, double com[3], double I[9])
{
    *mass = 1.0 + 0.25 * i;
    com[0] = 0.1 * i;
    com[1] = -0.2;
    com[2] = 0.3 + i;
    I[0] = 0.3; I[1] = 0.01; I[2] = -0.02;
    I[3] = 0.01 + 1e-12 * i; I[4] = 0.25; I[5] = 0.0;       /* asymmetric within 1e-9 */
    I[6] = -0.02; I[7] = 0.0; I[8] = 0.2 + 0.01 * i;
}

static void joint_input(int i, double pos[3], double quat[4], double axis[3])
{
    const double s = 1.0 + 4e-7; /* norm within the 1e-6 tolerance, not 1 */
    pos[0] = 0.5; pos[1] = -0.1 * i; pos[2] = 0.25;
    quat[0] = 0.5 * s; quat[1] = 0.5 * s; quat[2] = -0.5 * s; quat[3] = 0.5 * s;
    if (i % 2) {
        quat[0] = 0.8 * s; quat[1] = 0.0; quat[2] = 0.6 * s; quat[3] = 0.0;
    }
    if (i == 2 || i == 6) quat[0] = -0.5 * s; /* w < 0: read back as -q (w >= 0), the same rotation */
    axis[0] = 0.0; axis[1] = 3.0 + i; axis[2] = 4.0;
}

static aqs_linkage *build(void)
{
    aqs_linkage *L = test_new_linkage();
    int i;
    for (i = 0; i < NB; i++) {
        double m, c[3], I[9];
        body_input(i, &m, c, I);
        assert_int_equal(aqs_body_add(L, m, c, I, NULL), AQS_OK);
    }
    for (i = 0; i < NB; i++) {
        double p[3], q[4], a[3];
        joint_input(i, p, q, a);
        assert_int_equal(aqs_joint_add(L, types[i], parents[i], i, p, q, a, NULL), AQS_OK);
    }
    return L;
}

/* Every read-back value against the inputs normalized here, independently. */
static void check_model(const aqs_linkage *L)
{
    int i, k;
    for (i = 0; i < NB; i++) {
        double m, c[3], I[9], gm = -1, gc[3], gI[9];
        body_input(i, &m, c, I);
        assert_int_equal(aqs_body_get_inertial(L, i, &gm, gc, gI), AQS_OK);
        assert_true(gm == m);
        for (k = 0; k < 3; k++) assert_true(gc[k] == c[k]);
        for (k = 0; k < 9; k++) {
            const double sym = 0.5 * (I[k] + I[3 * (k % 3) + k / 3]);
            assert_true(fabs(gI[k] - sym) <= 1e-17);
            assert_true(gI[k] == gI[3 * (k % 3) + k / 3]); /* exactly symmetric */
        }
    }
    for (i = 0; i < NB; i++) {
        double p[3], q[4], a[3], gp[3], gq[4], ga[3], qn, an;
        int32_t t = -9, par = -9, ch = -9;
        joint_input(i, p, q, a);
        assert_int_equal(aqs_joint_get_definition(L, i, &t, &par, &ch, gp, gq, ga), AQS_OK);
        assert_int_equal(t, types[i]);
        assert_int_equal(par, parents[i]);
        assert_int_equal(ch, i);
        for (k = 0; k < 3; k++) assert_true(gp[k] == p[k]);
        qn = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (q[0] < 0.0) qn = -qn; /* outputs have w >= 0 (docs/api.md, Conventions) */
        assert_true(gq[0] >= 0.0);
        for (k = 0; k < 4; k++) assert_true(fabs(gq[k] - q[k] / qn) <= 2.3e-16);
        an = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (types[i] == AQS_JOINT_FREE || types[i] == AQS_JOINT_SPHERICAL ||
            types[i] == AQS_JOINT_FIXED) {
            assert_true(ga[0] == 0.0 && ga[1] == 0.0 && ga[2] == 1.0);
        } else {
            for (k = 0; k < 3; k++) assert_true(fabs(ga[k] - a[k] / an) <= 2.3e-16);
        }
    }
}

static void test_values_in_every_phase(void **state)
{
    aqs_linkage *L = build();
    const double g[3] = {0.1, -9.81, 0.3};
    (void)state;
    check_model(L);                                   /* building */
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    check_model(L);                                   /* finalized */
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    check_model(L);                                   /* solved and moved */
    aqs_linkage_destroy(L);
}

static void test_null_outputs(void **state)
{
    aqs_linkage *L = build();
    double m = 0, c[3] = {0}, q[4] = {0};
    int32_t ch = -5;
    (void)state;
    assert_int_equal(aqs_body_get_inertial(L, 2, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_joint_get_definition(L, 2, NULL, NULL, NULL, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_body_get_inertial(L, 2, &m, NULL, NULL), AQS_OK);
    assert_true(m == 1.5);
    assert_int_equal(aqs_body_get_inertial(L, 2, NULL, c, NULL), AQS_OK);
    assert_true(c[0] == 0.1 * 2 && c[2] == 0.3 + 2);
    assert_int_equal(aqs_joint_get_definition(L, 3, NULL, NULL, &ch, NULL, q, NULL), AQS_OK);
    assert_int_equal(ch, 3);
    assert_true(fabs(q[0] - 0.8) < 1e-15 && fabs(q[2] - 0.6) < 1e-15);
    aqs_linkage_destroy(L);
}

static void test_errors(void **state)
{
    aqs_linkage *L = build();
    const int32_t bad[4] = {-1, NB, INT32_MIN, INT32_MAX};
    double m = 7, c[3] = {7, 7, 7}, I[9], p[3] = {7, 7, 7}, q[4] = {7, 7, 7, 7}, a[3] = {7, 7, 7};
    int32_t t = 7, par = 7, ch = 7, k, i;
    char text[64];
    (void)state;
    for (k = 0; k < 9; k++) I[k] = 7;
    assert_int_equal(aqs_body_get_inertial(NULL, 0, &m, c, I), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_definition(NULL, 0, &t, &par, &ch, p, q, a), AQS_EINVAL);
    for (i = 0; i < 4; i++) {
        assert_int_equal(aqs_body_get_inertial(L, bad[i], &m, c, I), AQS_ERANGE);
        test_assert_contains(aqs_linkage_last_error(L), "aqs_body_get_inertial");
        snprintf(text, sizeof text, "body = %d", (int)bad[i]);
        test_assert_contains(aqs_linkage_last_error(L), text);
        assert_int_equal(aqs_joint_get_definition(L, bad[i], &t, &par, &ch, p, q, a), AQS_ERANGE);
        test_assert_contains(aqs_linkage_last_error(L), "aqs_joint_get_definition");
        snprintf(text, sizeof text, "joint = %d", (int)bad[i]);
        test_assert_contains(aqs_linkage_last_error(L), text);
    }
    /* nothing was written */
    assert_true(m == 7 && t == 7 && par == 7 && ch == 7);
    for (k = 0; k < 3; k++) assert_true(c[k] == 7 && p[k] == 7 && a[k] == 7);
    for (k = 0; k < 4; k++) assert_true(q[k] == 7);
    for (k = 0; k < 9; k++) assert_true(I[k] == 7);
    /* the model is intact and still finalizes */
    check_model(L);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    aqs_linkage_destroy(L);
}

static void test_empty_linkage(void **state)
{
    aqs_linkage *L = test_new_linkage();
    (void)state;
    assert_int_equal(aqs_body_get_inertial(L, 0, NULL, NULL, NULL), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "[0, 0)");
    assert_int_equal(aqs_joint_get_definition(L, 0, NULL, NULL, NULL, NULL, NULL, NULL), AQS_ERANGE);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_values_in_every_phase),
        cmocka_unit_test(test_null_outputs),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_empty_linkage),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
