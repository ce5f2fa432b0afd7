/* test_joint.c -- src/model/joint.c: sizes per type, the completing directions,
 * the child pose as a function of q (against the header's definitions),
 * the motion subspace (against numerical differentiation of the pose),
 * integration on the manifold and the validation of positions. */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "joint.h"

/* The pose definitions are a few trigonometric evaluations and 3x3
 * products of O(1) values: rounding < 1e-15; 1e-13 leaves a wide margin
 * while any wrong sign, axis or order of rotations is O(0.1). */
#define TOL 1e-13

static const int all_types[JOINT_TYPE_COUNT] = {
    AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,   AQS_JOINT_FREE,
    AQS_JOINT_FIXED,    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL, AQS_JOINT_PLANAR};

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void random_unit(uint64_t *s, double a[3])
{
    double n;
    int i;
    do {
        for (i = 0; i < 3; i++) a[i] = test_uniform(s, -1, 1);
        n = sqrt(dot3(a, a));
    } while (n < 0.1);
    for (i = 0; i < 3; i++) a[i] /= n;
}

/* The header's rule, written out: e = the first coordinate axis along which
 * |a| is smallest, u = normalize(e - (e.a) a), v = a x u. */
static void reference_directions(const double a[3], double u[3], double v[3])
{
    int e = 0, i;
    double n;
    if (fabs(a[1]) < fabs(a[e])) e = 1;
    if (fabs(a[2]) < fabs(a[e])) e = 2;
    for (i = 0; i < 3; i++) u[i] = (i == e) - a[e] * a[i];
    n = sqrt(dot3(u, u));
    for (i = 0; i < 3; i++) u[i] /= n;
    cross3(a, u, v);
}

static joint_def make_joint(int32_t type, const double axis[3])
{
    joint_def j;
    memset(&j, 0, sizeof j);
    j.type = type;
    j.parent = AQS_WORLD;
    j.quat[0] = 1.0;
    memcpy(j.axis, axis, sizeof j.axis);
    joint_directions(j.axis, j.u, j.v);
    return j;
}

/* A random valid position of the type: angles in (-2.5, 2.5), lengths in
 * (-2, 2), unit quaternions. */
static void random_position(uint64_t *s, int32_t type, double *q)
{
    int i, nq = joint_nq(type);
    for (i = 0; i < nq; i++) q[i] = test_uniform(s, -2.5, 2.5);
    if (type == AQS_JOINT_SPHERICAL) test_random_quat(s, q);
    if (type == AQS_JOINT_FREE) test_random_quat(s, q + 3);
}

static void assert_close(const double *a, const double *b, size_t n, double tol)
{
    double d = test_max_abs_diff(a, b, n);
    if (!(d <= tol)) {
        size_t i;
        print_error("max difference %.3g > %.3g\n", d, tol);
        for (i = 0; i < n; i++) print_error("  [%zu] %.17g vs %.17g\n", i, a[i], b[i]);
        fail();
    }
}

static void test_sizes(void **state)
{
    /* The header's table: (nq, nv) per type, and which types use the axis. */
    static const int expect[JOINT_TYPE_COUNT][3] = {
        {1, 1, 1}, {1, 1, 1}, {4, 3, 0}, {7, 6, 0}, {0, 0, 0}, {2, 2, 1}, {2, 2, 1}, {3, 3, 1}};
    int t, u;
    (void)state;
    for (t = 0; t < JOINT_TYPE_COUNT; t++) {
        assert_int_equal(all_types[t], t); /* the AQS_JOINT_* values are 0..7 */
        assert_int_equal(joint_nq(t), expect[t][0]);
        assert_int_equal(joint_nv(t), expect[t][1]);
        assert_int_equal(joint_uses_axis(t) != 0, expect[t][2]);
        assert_non_null(joint_type_name(t));
        assert_true(strlen(joint_type_name(t)) > 0);
        for (u = 0; u < t; u++) assert_string_not_equal(joint_type_name(t), joint_type_name(u));
    }
}

static void test_directions(void **state)
{
    uint64_t s = 21;
    int k;
    (void)state;
    {
        /* a = z gives exactly (x, y, z); a = x gives (y, z, x); a = y, (x, -z, y) */
        static const double a[3][3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
        static const double eu[3][3] = {{1, 0, 0}, {0, 1, 0}, {1, 0, 0}};
        static const double ev[3][3] = {{0, 1, 0}, {0, 0, 1}, {0, 0, -1}};
        int i;
        for (i = 0; i < 3; i++) {
            double u[3], v[3];
            joint_directions(a[i], u, v);
            assert_true(test_max_abs_diff(u, eu[i], 3) == 0.0);
            assert_true(test_max_abs_diff(v, ev[i], 3) == 0.0);
        }
    }
    for (k = 0; k < 1000; k++) {
        double a[3], u[3], v[3], ru[3], rv[3], uxv[3];
        random_unit(&s, a);
        if (k % 4 == 0) a[k % 3] = 0.0; /* ties and zeros in |a| */
        if (k % 4 == 0) {
            double n = sqrt(dot3(a, a));
            int i;
            for (i = 0; i < 3; i++) a[i] /= n;
        }
        joint_directions(a, u, v);
        reference_directions(a, ru, rv);
        assert_close(u, ru, 3, TOL);
        assert_close(v, rv, 3, TOL);
        /* orthonormal and right-handed: u x v = a */
        assert_true(fabs(dot3(u, u) - 1) < TOL && fabs(dot3(v, v) - 1) < TOL);
        assert_true(fabs(dot3(u, v)) < TOL && fabs(dot3(u, a)) < TOL && fabs(dot3(v, a)) < TOL);
        cross3(u, v, uxv);
        assert_close(uxv, a, 3, TOL);
    }
}

/* The child pose of each type against its definition in aqs.h. */
static void reference_pose(const joint_def *j, const double *q, double R[9], double p[3])
{
    static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    int i;
    memcpy(R, I3, sizeof I3);
    p[0] = p[1] = p[2] = 0.0;
    switch (j->type) {
    case AQS_JOINT_REVOLUTE: test_rodrigues(j->axis, q[0], R); break;
    case AQS_JOINT_PRISMATIC:
        for (i = 0; i < 3; i++) p[i] = q[0] * j->axis[i];
        break;
    case AQS_JOINT_SPHERICAL: test_quat_matrix(q, R); break;
    case AQS_JOINT_FREE:
        test_quat_matrix(q + 3, R);
        for (i = 0; i < 3; i++) p[i] = q[i];
        break;
    case AQS_JOINT_FIXED: break;
    case AQS_JOINT_UNIVERSAL: {
        /* q1 about a, then q2 about the moved u: R = Rot(a, q1) Rot(u, q2) */
        double Ra[9], Ru[9];
        test_rodrigues(j->axis, q[0], Ra);
        test_rodrigues(j->u, q[1], Ru);
        test_mat3_mul(Ra, Ru, R);
        break;
    }
    case AQS_JOINT_CYLINDRICAL:
        test_rodrigues(j->axis, q[0], R);
        for (i = 0; i < 3; i++) p[i] = q[1] * j->axis[i];
        break;
    case AQS_JOINT_PLANAR:
        /* translation q1 u + q2 v, then rotation q3 about a */
        test_rodrigues(j->axis, q[2], R);
        for (i = 0; i < 3; i++) p[i] = q[0] * j->u[i] + q[1] * j->v[i];
        break;
    default: fail();
    }
}

static void test_child_pose(void **state)
{
    uint64_t s = 22;
    int t, k;
    (void)state;
    for (t = 0; t < JOINT_TYPE_COUNT; t++)
        for (k = 0; k < 200; k++) {
            double a[3], q[7], R[9], p[3];
            joint_def j;
            pose P;
            random_unit(&s, a);
            j = make_joint(t, a);
            random_position(&s, t, q);
            joint_child_pose(&j, q, &P);
            reference_pose(&j, q, R, p);
            assert_close(P.R, R, 9, TOL);
            assert_close(P.p, p, 3, TOL);
            if (k == 0) {
                /* the zero position is the identity pose for every type */
                static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z[3] = {0, 0, 0};
                double q0[7];
                joint_zero_position(t, q0);
                joint_child_pose(&j, q0, &P);
                assert_close(P.R, I3, 9, 0.0);
                assert_close(P.p, z, 3, 0.0);
            }
        }
    /* A concrete case: revolute about z by 90 degrees maps x to y. */
    {
        double a[3] = {0, 0, 1}, q = 1.5707963267948966, x[3], ex[3] = {0, 1, 0};
        joint_def j = make_joint(AQS_JOINT_REVOLUTE, a);
        pose P;
        joint_child_pose(&j, &q, &P);
        x[0] = P.R[0];
        x[1] = P.R[3];
        x[2] = P.R[6];
        assert_close(x, ex, 3, TOL);
    }
}

/* q moved by h along velocity coordinate i: additive for scalar coordinates;
 * for spherical and free joints the velocity coordinates are the child's
 * body-frame angular (and linear) velocity, and the move is the one of
 * joint_integrate (checked on its own in test_integrate). */
static void move(const joint_def *j, const double *q, int i, double h, double *out)
{
    double e[6] = {0, 0, 0, 0, 0, 0};
    memcpy(out, q, sizeof(double) * (size_t)joint_nq(j->type));
    e[i] = 1.0;
    joint_integrate(j, out, e, h);
}

/* S (6 x nv, child frame) column i is the body-frame twist of the child
 * per unit velocity i: with P(t) the child pose moved by t along i,
 * omega = vee(skew part of R0^T R(t)) / t and v = R0^T (p(t) - p0) / t, by
 * central differences. h = 1e-5: truncation O(h^2) ~ 1e-10 and rounding
 * O(u / h) ~ 1e-11 for O(1) poses, so 1e-8 separates them from any wrong
 * column (O(0.1) and more at these non-zero positions). */
static void test_subspace_numerical(void **state)
{
    uint64_t s = 23;
    const double h = 1e-5;
    int t, k;
    (void)state;
    for (t = 0; t < JOINT_TYPE_COUNT; t++)
        for (k = 0; k < 50; k++) {
            double a[3], q[7], qp[7], qm[7], S[36], R0T[9];
            int nv = joint_nv(t), i, r, c;
            joint_def j;
            pose P0, Pp, Pm;
            random_unit(&s, a);
            j = make_joint(t, a);
            random_position(&s, t, q);
            joint_child_pose(&j, q, &P0);
            for (r = 0; r < 3; r++)
                for (c = 0; c < 3; c++) R0T[3 * r + c] = P0.R[3 * c + r];
            for (i = 0; i < 6 * nv; i++) S[i] = NAN;
            joint_subspace(&j, q, S);
            for (i = 0; i < nv; i++) {
                double Mp[9], Mm[9], w[3], v[3], dp[3], col[6], num[6];
                move(&j, q, i, h, qp);
                move(&j, q, i, -h, qm);
                joint_child_pose(&j, qp, &Pp);
                joint_child_pose(&j, qm, &Pm);
                test_mat3_mul(R0T, Pp.R, Mp);
                test_mat3_mul(R0T, Pm.R, Mm);
                /* vee of the skew part: (M[2][1] - M[1][2]) / 2, ... */
                w[0] = ((Mp[7] - Mp[5]) - (Mm[7] - Mm[5])) / (4 * h);
                w[1] = ((Mp[2] - Mp[6]) - (Mm[2] - Mm[6])) / (4 * h);
                w[2] = ((Mp[3] - Mp[1]) - (Mm[3] - Mm[1])) / (4 * h);
                for (r = 0; r < 3; r++) dp[r] = (Pp.p[r] - Pm.p[r]) / (2 * h);
                for (r = 0; r < 3; r++) v[r] = R0T[3 * r] * dp[0] + R0T[3 * r + 1] * dp[1] + R0T[3 * r + 2] * dp[2];
                for (r = 0; r < 3; r++) {
                    num[r] = w[r];
                    num[3 + r] = v[r];
                }
                for (r = 0; r < 6; r++) col[r] = S[r * nv + i];
                assert_close(col, num, 6, 1e-8);
            }
        }
}

/* q <- q (+) h qdd against closed forms. */
static void test_integrate(void **state)
{
    uint64_t s = 24;
    int t, k;
    (void)state;
    /* Scalar coordinates: additive, q + h qdd (one rounding each). */
    for (t = 0; t < JOINT_TYPE_COUNT; t++) {
        double a[3] = {0, 0, 1}, q[7], q0[7], qdd[6], h = 0.37;
        joint_def j = make_joint(t, a);
        int i;
        if (t == AQS_JOINT_SPHERICAL || t == AQS_JOINT_FREE) continue;
        random_position(&s, t, q);
        memcpy(q0, q, sizeof q);
        for (i = 0; i < 6; i++) qdd[i] = test_uniform(&s, -3, 3);
        joint_integrate(&j, q, qdd, h);
        for (i = 0; i < joint_nq(t); i++) assert_true(fabs(q[i] - (q0[i] + h * qdd[i])) <= 1e-15 * 4);
    }
    /* Spherical and free: a body-frame rotation vector w = h qdd[0..2]:
     * R_new = R_old Rot(w / |w|, |w|), quaternion unit; free: the origin
     * moves by R_old h qdd[3..5]. Angles up to ~5 rad (beyond pi) and tiny. */
    for (k = 0; k < 400; k++) {
        int free_joint = k % 2, qi = free_joint ? 3 : 0, i;
        double a[3] = {0, 0, 1}, q[7], q0[7], qdd[6], R0[9], Rw[9], Rexp[9], R[9], w[3];
        double scale = k % 5 == 0 ? 1e-12 : 1.0, h = 0.5, wn;
        joint_def j = make_joint(free_joint ? AQS_JOINT_FREE : AQS_JOINT_SPHERICAL, a);
        random_position(&s, j.type, q);
        memcpy(q0, q, sizeof q);
        for (i = 0; i < 6; i++) qdd[i] = scale * test_uniform(&s, -5, 5);
        joint_integrate(&j, q, qdd, h);
        assert_true(fabs(sqrt(q[qi] * q[qi] + q[qi + 1] * q[qi + 1] + q[qi + 2] * q[qi + 2] +
                              q[qi + 3] * q[qi + 3]) - 1.0) < 1e-15 * 4);
        for (i = 0; i < 3; i++) w[i] = h * qdd[i];
        wn = sqrt(dot3(w, w));
        test_quat_matrix(q0 + qi, R0);
        test_rodrigues(w, wn, Rw);
        test_mat3_mul(R0, Rw, Rexp);
        test_quat_matrix(q + qi, R);
        assert_close(R, Rexp, 9, TOL);
        if (free_joint) {
            double dp[3], moved[3];
            for (i = 0; i < 3; i++) dp[i] = h * qdd[3 + i];
            for (i = 0; i < 3; i++) moved[i] = q0[i] + R0[3 * i] * dp[0] + R0[3 * i + 1] * dp[1] + R0[3 * i + 2] * dp[2];
            assert_close(q, moved, 3, TOL);
        }
    }
    /* Many steps: the quaternion stays unit (renormalized every step) and
     * the rotations compose: n steps of w about a fixed axis = angle n |w|. */
    {
        double a[3] = {0, 0, 1}, q[4] = {1, 0, 0, 0}, qdd[3] = {0.3, -0.2, 0.6}, R[9], Rexp[9];
        double w[3], n = 10000, h = 1e-3;
        joint_def j = make_joint(AQS_JOINT_SPHERICAL, a);
        int step, i;
        for (step = 0; step < (int)n; step++) {
            joint_integrate(&j, q, qdd, h);
            assert_true(fabs(sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]) - 1.0) < 1e-15 * 4);
        }
        for (i = 0; i < 3; i++) w[i] = n * h * qdd[i];
        test_rodrigues(w, sqrt(dot3(w, w)), Rexp);
        test_quat_matrix(q, R);
        /* 1e4 compositions, each with a few ulps of error: ~1e-12 */
        assert_close(R, Rexp, 9, 1e-11);
    }
}

static void test_check_position(void **state)
{
    double out[7];
    (void)state;
    /* Non-finite values: the one-based index of the first one. */
    {
        double q[3] = {0.1, NAN, INFINITY};
        assert_int_equal(joint_check_position(AQS_JOINT_PLANAR, q, out), 2);
        q[1] = 0.2;
        assert_int_equal(joint_check_position(AQS_JOINT_PLANAR, q, out), 3);
        q[2] = -INFINITY;
        assert_int_equal(joint_check_position(AQS_JOINT_PLANAR, q, out), 3);
        q[2] = 0.3;
        assert_int_equal(joint_check_position(AQS_JOINT_PLANAR, q, out), 0);
        assert_true(out[0] == 0.1 && out[1] == 0.2 && out[2] == 0.3); /* copied as is */
    }
    {
        double q[7] = {1, 2, 3, 1, 0, NAN, 0};
        assert_int_equal(joint_check_position(AQS_JOINT_FREE, q, out), 6);
        q[5] = 0;
        q[0] = NAN;
        assert_int_equal(joint_check_position(AQS_JOINT_FREE, q, out), 1);
    }
    {
        double q = NAN;
        assert_int_equal(joint_check_position(AQS_JOINT_REVOLUTE, &q, out), 1);
    }
    /* Quaternions: unit within 1e-6, then normalized; outside, -1. */
    {
        double q[4] = {0.5, 0.5, 0.5, 0.5}, n;
        int i;
        for (i = 0; i < 4; i++) q[i] *= 1.0 + 9e-7; /* norm 1 + 9e-7: accepted */
        assert_int_equal(joint_check_position(AQS_JOINT_SPHERICAL, q, out), 0);
        n = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
        assert_true(fabs(n - 1.0) < 4e-16);
        for (i = 0; i < 4; i++) assert_true(fabs(out[i] - 0.5) < 4e-16);
        for (i = 0; i < 4; i++) q[i] = 0.5 * (1.0 + 1.1e-6); /* norm 1 + 1.1e-6 */
        assert_int_equal(joint_check_position(AQS_JOINT_SPHERICAL, q, out), -1);
        for (i = 0; i < 4; i++) q[i] = 0.5 * (1.0 - 1.1e-6);
        assert_int_equal(joint_check_position(AQS_JOINT_SPHERICAL, q, out), -1);
        for (i = 0; i < 4; i++) q[i] = 0.0;
        assert_int_equal(joint_check_position(AQS_JOINT_SPHERICAL, q, out), -1);
    }
    {
        /* free: the translation is copied exactly, the quaternion normalized */
        double q[7] = {1e3, -2.5, 7, 0, 0.6 * (1 + 5e-7), 0, 0.8 * (1 + 5e-7)};
        assert_int_equal(joint_check_position(AQS_JOINT_FREE, q, out), 0);
        assert_true(out[0] == 1e3 && out[1] == -2.5 && out[2] == 7);
        assert_true(fabs(out[4] - 0.6) < 4e-16 && fabs(out[6] - 0.8) < 4e-16 && out[3] == 0 && out[5] == 0);
        q[4] = 0.6 * 1.01;
        assert_int_equal(joint_check_position(AQS_JOINT_FREE, q, out), -1);
    }
    /* A fixed joint has no position: nothing to reject. */
    {
        double dummy = NAN;
        assert_int_equal(joint_check_position(AQS_JOINT_FIXED, &dummy, out), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sizes),
        cmocka_unit_test(test_directions),
        cmocka_unit_test(test_child_pose),
        cmocka_unit_test(test_subspace_numerical),
        cmocka_unit_test(test_integrate),
        cmocka_unit_test(test_check_position),
    };
    return cmocka_run_group_tests_name("joint", tests, NULL, NULL);
}
