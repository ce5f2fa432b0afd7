/* test_spatial.c -- src/base/spatial.c: quaternions, rotations, poses, 6-D motion
 * and force transforms, spatial inertias (MATH.md §1).
 *
 * Reference values come from formulas written independently in the test
 * (tests/support: Rodrigues, the quaternion matrix in its (w^2 - v.v) form)
 * or from identities (inverse, associativity, power invariance, momentum).
 *
 * Tolerance: every quantity here is O(1) (unit rotations, offsets and
 * masses of a few units) and each result is at most a few tens of floating
 * point operations, so rounding is a few tens of ulps (< 1e-14) relative to
 * the largest entry. TOL = 1e-13 (relative to max(1, largest entry)) keeps a
 * margin of ten while any formula error (a wrong sign, a transposed block)
 * shows up at O(1e-2) or more. */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "spatial.h"

#define TOL 1e-13
#define PI 3.14159265358979323846

/* max |a - b| <= TOL * max(1, max |b|) */
static void assert_close(const double *a, const double *b, size_t n)
{
    double scale = 1.0, d;
    size_t i;
    for (i = 0; i < n; i++)
        if (fabs(b[i]) > scale) scale = fabs(b[i]);
    d = test_max_abs_diff(a, b, n);
    if (!(d <= TOL * scale)) {
        print_error("max difference %.3g > %.3g\n", d, TOL * scale);
        for (i = 0; i < n; i++) print_error("  [%zu] %.17g vs %.17g\n", i, a[i], b[i]);
        fail();
    }
}

static void random_vec3(uint64_t *s, double lo, double hi, double v[3])
{
    int i;
    for (i = 0; i < 3; i++) v[i] = test_uniform(s, lo, hi);
}

static void random_pose(uint64_t *s, pose *P)
{
    double q[4];
    test_random_quat(s, q);
    test_quat_matrix(q, P->R);
    random_vec3(s, -2, 2, P->p);
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static void matvec3(const double R[9], const double v[3], double out[3])
{
    int i;
    for (i = 0; i < 3; i++) out[i] = R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2];
}

static void transpose3(const double A[9], double T[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) T[3 * j + i] = A[3 * i + j];
}

static double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
           A[2] * (A[3] * A[7] - A[4] * A[6]);
}

static void mul6(const double *A, const double *B, double *C)
{
    int i, j, k;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) {
            double s = 0;
            for (k = 0; k < 6; k++) s += A[6 * i + k] * B[6 * k + j];
            C[6 * i + j] = s;
        }
}

static void matvec6(const double *A, const double *x, double *y)
{
    int i, k;
    for (i = 0; i < 6; i++) {
        double s = 0;
        for (k = 0; k < 6; k++) s += A[6 * i + k] * x[k];
        y[i] = s;
    }
}

static void tmatvec6(const double *A, const double *x, double *y)
{
    int i, k;
    for (i = 0; i < 6; i++) {
        double s = 0;
        for (k = 0; k < 6; k++) s += A[6 * k + i] * x[k];
        y[i] = s;
    }
}

static void transpose6(const double *A, double *T)
{
    int i, j;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) T[6 * j + i] = A[6 * i + j];
}

static double dot(const double *a, const double *b, int n)
{
    double s = 0;
    int i;
    for (i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

static void assert_rotation(const double R[9])
{
    double RT[9], P[9];
    static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    transpose3(R, RT);
    test_mat3_mul(RT, R, P);
    assert_close(P, I3, 9);
    assert_true(fabs(det3(R) - 1.0) < TOL);
}

/* Quaternion -> matrix against the independent formula, and back. */
static void test_quat_rotation_round_trip(void **state)
{
    uint64_t s = 1;
    int k;
    (void)state;
    for (k = 0; k < 1000; k++) {
        double q[4], R[9], Rref[9], q2[4];
        test_random_quat(&s, q);
        quat_to_rot(q, R);
        test_quat_matrix(q, Rref);
        assert_close(R, Rref, 9);
        assert_rotation(R);
        rot_to_quat(R, q2); /* w >= 0 like q, so the sign is fixed */
        assert_close(q2, q, 4);
        assert_true(fabs(quat_norm(q2) - 1.0) < TOL);
    }
    /* Matrix -> quaternion -> matrix, with rotations chosen to reach every
     * branch of the largest-component selection: small angles (trace
     * largest) and angles near pi about x, y, z (one diagonal entry largest). */
    {
        const double axes[6][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}, {-1, 2, 0.5}, {0.2, -0.1, -3}};
        const double angles[6] = {0.0, 0.3, -1.7, 2.9, PI - 1e-3, 3.1415};
        int a, b;
        for (a = 0; a < 6; a++)
            for (b = 0; b < 6; b++) {
                double R[9], q[4], R2[9], qref[4], n = sqrt(dot(axes[a], axes[a], 3));
                int i;
                test_rodrigues(axes[a], angles[b], R);
                rot_to_quat(R, q);
                quat_to_rot(q, R2);
                assert_close(R2, R, 9);
                /* the quaternion itself: (cos t/2, sin t/2 n) up to the sign w >= 0 */
                qref[0] = cos(0.5 * angles[b]);
                for (i = 0; i < 3; i++) qref[1 + i] = sin(0.5 * angles[b]) * axes[a][i] / n;
                if (qref[0] < 0)
                    for (i = 0; i < 4; i++) qref[i] = -qref[i];
                assert_close(q, qref, 4);
            }
    }
    /* A half turn (w = 0): the sign is arbitrary, the rotation is not. */
    {
        double qh[4] = {0, 0, 0.6, 0.8}, R[9], q[4];
        test_quat_matrix(qh, R);
        rot_to_quat(R, q);
        assert_true(fabs(fabs(dot(q, qh, 4)) - 1.0) < TOL);
    }
}

/* R(a b) = R(a) R(b); a a* = 1. */
static void test_quat_mul(void **state)
{
    uint64_t s = 2;
    int k;
    (void)state;
    for (k = 0; k < 500; k++) {
        double a[4], b[4], ab[4], Ra[9], Rb[9], Rab[9], RaRb[9], ac[4], aac[4];
        static const double one[4] = {1, 0, 0, 0};
        test_random_quat(&s, a);
        test_random_quat(&s, b);
        quat_mul(a, b, ab);
        test_quat_matrix(a, Ra);
        test_quat_matrix(b, Rb);
        test_mat3_mul(Ra, Rb, RaRb);
        test_quat_matrix(ab, Rab);
        assert_close(Rab, RaRb, 9);
        assert_true(fabs(quat_norm(ab) - 1.0) < TOL);
        ac[0] = a[0];
        ac[1] = -a[1];
        ac[2] = -a[2];
        ac[3] = -a[3];
        quat_mul(a, ac, aac);
        assert_close(aac, one, 4);
    }
    /* i j = k and j i = -k fix the handedness of the product. */
    {
        double i_[4] = {0, 1, 0, 0}, j_[4] = {0, 0, 1, 0}, out[4];
        double k_[4] = {0, 0, 0, 1}, mk[4] = {0, 0, 0, -1};
        quat_mul(i_, j_, out);
        assert_close(out, k_, 4);
        quat_mul(j_, i_, out);
        assert_close(out, mk, 4);
    }
}

/* quat_from_rotvec and rot_axis_angle agree with Rodrigues, for angles
 * beyond pi and across the small-angle series threshold. */
static void test_rotvec_axis_angle(void **state)
{
    uint64_t s = 3;
    int k;
    (void)state;
    for (k = 0; k < 500; k++) {
        double n[3], w[3], q[4], Rq[9], Ra[9], Rref[9], len, angle = test_uniform(&s, -3 * PI, 3 * PI);
        int i;
        random_vec3(&s, -1, 1, n);
        len = sqrt(dot(n, n, 3));
        for (i = 0; i < 3; i++) n[i] /= len;
        for (i = 0; i < 3; i++) w[i] = angle * n[i];
        quat_from_rotvec(w, q);
        assert_true(fabs(quat_norm(q) - 1.0) < TOL);
        test_quat_matrix(q, Rq);
        test_rodrigues(n, angle, Rref);
        assert_close(Rq, Rref, 9);
        rot_axis_angle(n, angle, Ra);
        assert_close(Ra, Rref, 9);
        /* the axis is fixed, a perpendicular vector turns by angle */
        {
            double an[3], u[3] = {n[1], -n[0], 0}, Ru[3], expect[3], nu[3];
            double lu = sqrt(dot(u, u, 3));
            if (lu < 0.1) {
                u[0] = 0;
                u[1] = n[2];
                u[2] = -n[1];
                lu = sqrt(dot(u, u, 3));
            }
            for (i = 0; i < 3; i++) u[i] /= lu;
            matvec3(Ra, n, an);
            assert_close(an, n, 3);
            matvec3(Ra, u, Ru);
            cross(n, u, nu);
            for (i = 0; i < 3; i++) expect[i] = cos(angle) * u[i] + sin(angle) * nu[i];
            assert_close(Ru, expect, 3);
        }
    }
    /* Small angles, on both sides of the series threshold: relative accuracy
     * of the vector part ~ 1 ulp (compared at 1e-14 relative). */
    {
        const double angles[] = {1e-15, 1e-12, 1e-9, 9.99e-9, 1.001e-8, 1e-6, 1e-3};
        const double n[3] = {0.48, -0.6, 0.64}; /* unit: 0.2304 + 0.36 + 0.4096 = 1 */
        size_t a;
        for (a = 0; a < sizeof angles / sizeof angles[0]; a++) {
            double w[3], q[4], sh = sin(0.5 * angles[a]);
            int i;
            for (i = 0; i < 3; i++) w[i] = angles[a] * n[i];
            quat_from_rotvec(w, q);
            assert_true(fabs(q[0] - cos(0.5 * angles[a])) <= 1e-16);
            for (i = 0; i < 3; i++) assert_true(fabs(q[1 + i] - sh * n[i]) <= 1e-14 * sh);
        }
    }
    /* The zero vector is exactly the identity. */
    {
        double w[3] = {0, 0, 0}, q[4];
        quat_from_rotvec(w, q);
        assert_true(q[0] == 1.0 && q[1] == 0.0 && q[2] == 0.0 && q[3] == 0.0);
    }
}

static void apply(const pose *P, const double x[3], double out[3])
{
    int i;
    matvec3(P->R, x, out);
    for (i = 0; i < 3; i++) out[i] += P->p[i];
}

static void assert_pose_close(const pose *a, const pose *b)
{
    assert_close(a->R, b->R, 9);
    assert_close(a->p, b->p, 3);
}

/* pose_compose is the composition of the point maps x -> R x + p;
 * pose_inverse inverts it; associativity; (ab)^-1 = b^-1 a^-1. */
static void test_pose_compose_inverse(void **state)
{
    uint64_t s = 4;
    int k;
    pose I;
    (void)state;
    pose_identity(&I);
    {
        static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, z[3] = {0, 0, 0};
        assert_true(memcmp(I.R, I3, sizeof I3) == 0 && memcmp(I.p, z, sizeof z) == 0);
    }
    for (k = 0; k < 300; k++) {
        pose a, b, c, ab, bc, ab_c, a_bc, ai, bi, t, abi, biai;
        double x[3], y1[3], y2[3], tmp[3];
        random_pose(&s, &a);
        random_pose(&s, &b);
        random_pose(&s, &c);
        random_vec3(&s, -3, 3, x);
        pose_compose(&a, &b, &ab);
        apply(&b, x, tmp);
        apply(&a, tmp, y1);
        apply(&ab, x, y2);
        assert_close(y2, y1, 3);
        pose_inverse(&a, &ai);
        pose_compose(&a, &ai, &t);
        assert_pose_close(&t, &I);
        pose_compose(&ai, &a, &t);
        assert_pose_close(&t, &I);
        pose_inverse(&ai, &t);
        assert_pose_close(&t, &a);
        pose_compose(&ab, &c, &ab_c);
        pose_compose(&b, &c, &bc);
        pose_compose(&a, &bc, &a_bc);
        assert_pose_close(&ab_c, &a_bc);
        pose_inverse(&b, &bi);
        pose_inverse(&ab, &abi);
        pose_compose(&bi, &ai, &biai);
        assert_pose_close(&abi, &biai);
        pose_compose(&I, &a, &t);
        assert_pose_close(&t, &a);
        pose_compose(&a, &I, &t);
        assert_pose_close(&t, &a);
    }
    /* pose_from_quat */
    {
        double q[4], pos[3] = {1.5, -2, 0.25}, R[9];
        pose P;
        test_random_quat(&s, q);
        pose_from_quat(pos, q, &P);
        test_quat_matrix(q, R);
        assert_close(P.R, R, 9);
        assert_close(P.p, pos, 3);
    }
}

/* 3-vector and 3x3 helpers against the definitions. */
static void test_vec3_mat3(void **state)
{
    uint64_t s = 5;
    int k;
    (void)state;
    for (k = 0; k < 200; k++) {
        double a[3], b[3], c[3], A[9], B[9], AB[9], ref[9], v[3], AT[9];
        int i;
        random_vec3(&s, -2, 2, a);
        random_vec3(&s, -2, 2, b);
        for (i = 0; i < 9; i++) {
            A[i] = test_uniform(&s, -2, 2);
            B[i] = test_uniform(&s, -2, 2);
        }
        vec3_cross(a, b, c);
        cross(a, b, ref);
        assert_close(c, ref, 3);
        assert_true(fabs(vec3_dot(a, b) - (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])) < TOL * 12);
        mat3_mul(A, B, AB);
        test_mat3_mul(A, B, ref);
        assert_close(AB, ref, 9);
        mat3_vec(A, a, v);
        matvec3(A, a, ref);
        assert_close(v, ref, 3);
        mat3_tvec(A, a, v);
        transpose3(A, AT);
        matvec3(AT, a, ref);
        assert_close(v, ref, 3);
        /* a x a is exactly zero (each term cancels with its own mirror) */
        vec3_cross(a, a, c);
        assert_true(c[0] == 0.0 && c[1] == 0.0 && c[2] == 0.0);
    }
}

/* Motion transform X = to_parent(P) against its definition: a motion
 * [w; v_O] of F, written in G, is [R w; R v_O + p x (R w)]. from_parent is
 * its inverse; forces go by X^{-T} = from_parent^T, which keeps the power
 * f . v; transforms compose like poses. */
static void test_spatial_transforms(void **state)
{
    uint64_t s = 6;
    int k;
    (void)state;
    for (k = 0; k < 300; k++) {
        pose P, P2, P12;
        double X[36], Xi[36], prod[36], I6[36] = {0}, v[6], f[6], Xv[6], ref[6], fG[6];
        double Rw[3], Rv[3], pRw[3], Rn[3], Rf[3], pRf[3], X2[36], X12[36], XX2[36];
        int i;
        for (i = 0; i < 6; i++) I6[7 * i] = 1.0;
        random_pose(&s, &P);
        random_pose(&s, &P2);
        for (i = 0; i < 6; i++) {
            v[i] = test_uniform(&s, -1, 1);
            f[i] = test_uniform(&s, -1, 1);
        }
        spatial_to_parent(&P, X);
        spatial_from_parent(&P, Xi);
        mul6(X, Xi, prod);
        assert_close(prod, I6, 36);
        mul6(Xi, X, prod);
        assert_close(prod, I6, 36);
        /* definition of the motion transform */
        matvec6(X, v, Xv);
        matvec3(P.R, v, Rw);
        matvec3(P.R, v + 3, Rv);
        cross(P.p, Rw, pRw);
        for (i = 0; i < 3; i++) {
            ref[i] = Rw[i];
            ref[3 + i] = Rv[i] + pRw[i];
        }
        assert_close(Xv, ref, 6);
        /* force transform F -> G: [n_O; f] -> [R n + p x R f; R f] = Xi^T f */
        tmatvec6(Xi, f, fG);
        matvec3(P.R, f, Rn);
        matvec3(P.R, f + 3, Rf);
        cross(P.p, Rf, pRf);
        for (i = 0; i < 3; i++) {
            ref[i] = Rn[i] + pRf[i];
            ref[3 + i] = Rf[i];
        }
        assert_close(fG, ref, 6);
        /* power is frame independent */
        assert_true(fabs(dot(fG, Xv, 6) - dot(f, v, 6)) < TOL * 10);
        /* X(P P2) = X(P) X(P2) */
        pose_compose(&P, &P2, &P12);
        spatial_to_parent(&P2, X2);
        spatial_to_parent(&P12, X12);
        mul6(X, X2, XX2);
        assert_close(X12, XX2, 36);
        /* The structured forms of from_parent equal the 6x6 products. */
        {
            double out[6], B[36], S[36], BXt[36], XiT[36], T1[36], T2[36], outB[36];
            int j;
            spatial_xform_motion(&P, v, out);
            matvec6(Xi, v, ref);
            assert_close(out, ref, 6);
            spatial_xform_force_back(&P, f, out);
            tmatvec6(Xi, f, ref);
            assert_close(out, ref, 6);
            for (i = 0; i < 36; i++) B[i] = test_uniform(&s, -1, 1);
            for (i = 0; i < 6; i++)
                for (j = 0; j <= i; j++) S[6 * i + j] = S[6 * j + i] = test_uniform(&s, -1, 1);
            spatial_xform_rows(&P, B, outB);
            transpose6(Xi, XiT);
            mul6(B, XiT, BXt);
            assert_close(outB, BXt, 36);
            spatial_xform_congruence(&P, S, outB);
            mul6(Xi, S, T1);
            mul6(T1, XiT, T2);
            assert_close(outB, T2, 36);
            /* a pure rotation takes the blockwise path: X = diag(R^T, R^T) */
            {
                pose Pr = P;
                double Xr[36] = {0}, XrT[36];
                int a, b;
                Pr.p[0] = Pr.p[1] = Pr.p[2] = 0.0;
                for (a = 0; a < 3; a++)
                    for (b = 0; b < 3; b++) Xr[6 * a + b] = Xr[6 * (a + 3) + b + 3] = P.R[3 * b + a];
                spatial_xform_congruence(&Pr, S, outB);
                transpose6(Xr, XrT);
                mul6(Xr, S, T1);
                mul6(T1, XrT, T2);
                assert_close(outB, T2, 36);
                for (a = 0; a < 6; a++) /* exactly symmetric */
                    for (b = 0; b < 6; b++) assert_true(outB[6 * a + b] == outB[6 * b + a]);
            }
        }
    }
}

/* A random rigid body: mass, com, and a rotational inertia R diag(d) R^T
 * with principal moments obeying the triangle inequality. */
static void random_body(uint64_t *s, double *m, double c[3], double Ic[9])
{
    double q[4], R[9], D[9] = {0}, RD[9], RT[9];
    double d1 = test_uniform(s, 0.1, 1), d2 = test_uniform(s, 0.1, 1);
    *m = test_uniform(s, 0.5, 3);
    random_vec3(s, -1, 1, c);
    D[0] = d1;
    D[4] = d2;
    D[8] = test_uniform(s, fabs(d1 - d2) + 0.01, d1 + d2);
    test_random_quat(s, q);
    test_quat_matrix(q, R);
    test_mat3_mul(R, D, RD);
    transpose3(R, RT);
    test_mat3_mul(RD, RT, Ic);
    /* exactly symmetric, as the library stores inertias */
    Ic[1] = Ic[3] = 0.5 * (Ic[1] + Ic[3]);
    Ic[2] = Ic[6] = 0.5 * (Ic[2] + Ic[6]);
    Ic[5] = Ic[7] = 0.5 * (Ic[5] + Ic[7]);
}

/* I [w; v_O] is the momentum about O: [Ic w + c x h; h] with the linear
 * momentum h = m (v_O + w x c); v^T I v is twice the kinetic energy. */
static void test_spatial_inertia_definition(void **state)
{
    uint64_t s = 7;
    int k;
    (void)state;
    for (k = 0; k < 300; k++) {
        double m, c[3], Ic[9], I[36], v[6], Iv[6], ref[6], vc[3], wc[3], h[3], Icw[3], ch[3];
        double ke2;
        int i, j;
        random_body(&s, &m, c, Ic);
        for (i = 0; i < 6; i++) v[i] = test_uniform(&s, -1, 1);
        spatial_inertia(m, c, Ic, I);
        /* exactly symmetric: the blocks are built from symmetric parts */
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) assert_true(I[6 * i + j] == I[6 * j + i]);
        matvec6(I, v, Iv);
        cross(v, c, wc);
        for (i = 0; i < 3; i++) {
            vc[i] = v[3 + i] + wc[i];
            h[i] = m * vc[i];
        }
        matvec3(Ic, v, Icw);
        cross(c, h, ch);
        for (i = 0; i < 3; i++) {
            ref[i] = Icw[i] + ch[i];
            ref[3 + i] = h[i];
        }
        assert_close(Iv, ref, 6);
        ke2 = m * dot(vc, vc, 3) + dot(v, Icw, 3);
        assert_true(ke2 > 0);
        assert_true(fabs(dot(v, Iv, 6) - ke2) < TOL * 10 * (1 + ke2));
    }
}

/* The inertia moved to the parent frame equals the inertia built directly
 * there from (m, R c + p, R Ic R^T), and v^T I v is frame independent. */
static void test_inertia_transform(void **state)
{
    uint64_t s = 8;
    int k;
    (void)state;
    for (k = 0; k < 300; k++) {
        double m, c[3], Ic[9], IF[36], IG[36], cG[3], IcG[9], RIc[9], RT[9], ref[36];
        double X[36], vF[6], vG[6], IFv[6], IGv[6];
        pose P;
        int i;
        random_body(&s, &m, c, Ic);
        random_pose(&s, &P);
        spatial_inertia(m, c, Ic, IF);
        spatial_inertia_to_parent(&P, IF, IG);
        apply(&P, c, cG);
        test_mat3_mul(P.R, Ic, RIc);
        transpose3(P.R, RT);
        test_mat3_mul(RIc, RT, IcG);
        spatial_inertia(m, cG, IcG, ref);
        assert_close(IG, ref, 36);
        for (i = 0; i < 6; i++) vF[i] = test_uniform(&s, -1, 1);
        spatial_to_parent(&P, X);
        matvec6(X, vF, vG);
        matvec6(IF, vF, IFv);
        matvec6(IG, vG, IGv);
        {
            double e = dot(vF, IFv, 6);
            assert_true(fabs(dot(vG, IGv, 6) - e) < TOL * 10 * (1 + e));
        }
    }
    /* Any symmetric 6x6 (an articulated inertia is not a rigid body's):
     * X^T IF X with X = spatial_from_parent(P), by plain 6x6 products. */
    for (k = 0; k < 300; k++) {
        double IF[36], IG[36], X[36], T[36], ref[36];
        pose P;
        int i, j, r;
        for (i = 0; i < 6; i++)
            for (j = i; j < 6; j++) IF[6 * i + j] = IF[6 * j + i] = test_uniform(&s, -2, 2);
        random_pose(&s, &P);
        spatial_inertia_to_parent(&P, IF, IG);
        spatial_from_parent(&P, X);
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) {
                T[6 * i + j] = 0;
                for (r = 0; r < 6; r++) T[6 * i + j] += IF[6 * i + r] * X[6 * r + j]; /* IF X */
            }
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) {
                ref[6 * i + j] = 0;
                for (r = 0; r < 6; r++) ref[6 * i + j] += X[6 * r + i] * T[6 * r + j]; /* X^T (IF X) */
            }
        assert_close(IG, ref, 36);
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) assert_true(IG[6 * i + j] == IG[6 * j + i]);
    }
}

/* sphere_merge: the result holds both spheres (every point of each, up to
 * the relative 1e-12 it rounds up by) and is the smallest such sphere when
 * neither holds the other (radius (d + r1 + r2) / 2); an empty side gives
 * the other; a sphere inside the other gives the larger. */
static void test_sphere_merge(void **state)
{
    uint64_t s = 77;
    int k, i;
    (void)state;
    for (k = 0; k < 2000; k++) {
        double a[4], b[4], m[4], d;
        for (i = 0; i < 3; i++) a[i] = test_uniform(&s, -5, 5), b[i] = test_uniform(&s, -5, 5);
        a[3] = test_uniform(&s, 0, 3);
        b[3] = test_uniform(&s, 0, 3);
        sphere_merge(a, b, m);
        d = vec3_dist(a, b);
        assert_true(vec3_dist(m, a) + a[3] <= m[3] * (1 + 1e-13) + 1e-13);
        assert_true(vec3_dist(m, b) + b[3] <= m[3] * (1 + 1e-13) + 1e-13);
        if (d + b[3] <= a[3]) assert_true(memcmp(m, a, sizeof m) == 0);
        else if (d + a[3] <= b[3]) assert_true(memcmp(m, b, sizeof m) == 0);
        else assert_true(fabs(m[3] - 0.5 * (d + a[3] + b[3])) <= 1e-11 * m[3]);
    }
    {
        double e[4] = {1, 2, 3, -1}, b[4] = {4, 5, 6, 0.5}, m[4];
        sphere_merge(e, b, m);
        assert_true(memcmp(m, b, sizeof m) == 0);
        sphere_merge(b, e, m);
        assert_true(memcmp(m, b, sizeof m) == 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quat_rotation_round_trip),
        cmocka_unit_test(test_quat_mul),
        cmocka_unit_test(test_rotvec_axis_angle),
        cmocka_unit_test(test_pose_compose_inverse),
        cmocka_unit_test(test_sphere_merge),
        cmocka_unit_test(test_vec3_mat3),
        cmocka_unit_test(test_spatial_transforms),
        cmocka_unit_test(test_spatial_inertia_definition),
        cmocka_unit_test(test_inertia_transform),
    };
    return cmocka_run_group_tests_name("spatial", tests, NULL, NULL);
}
