/* spatial.c -- rigid poses, quaternions, 6-D transforms and inertias. */
#include "spatial.h"

#include <math.h>
#include <string.h>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include "dense.h"

void pose_identity(pose *P)
{
    static const double I3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    memcpy(P->R, I3, sizeof I3);
    P->p[0] = P->p[1] = P->p[2] = 0.0;
}

void pose_compose(const pose *a, const pose *b, pose *out)
{
    double t[3];
    mat3_mul(a->R, b->R, out->R);
    mat3_vec(a->R, b->p, t);
    out->p[0] = a->p[0] + t[0];
    out->p[1] = a->p[1] + t[1];
    out->p[2] = a->p[2] + t[2];
}

void pose_inverse(const pose *a, pose *out)
{
    int i, j;
    double t[3];
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) out->R[3 * i + j] = a->R[3 * j + i];
    mat3_tvec(a->R, a->p, t);
    out->p[0] = -t[0];
    out->p[1] = -t[1];
    out->p[2] = -t[2];
}

void pose_from_quat(const double pos[3], const double quat[4], pose *P)
{
    quat_to_rot(quat, P->R);
    P->p[0] = pos[0];
    P->p[1] = pos[1];
    P->p[2] = pos[2];
}

void quat_to_rot(const double q[4], double R[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    R[0] = 1 - 2 * (y * y + z * z);
    R[1] = 2 * (x * y - w * z);
    R[2] = 2 * (x * z + w * y);
    R[3] = 2 * (x * y + w * z);
    R[4] = 1 - 2 * (x * x + z * z);
    R[5] = 2 * (y * z - w * x);
    R[6] = 2 * (x * z - w * y);
    R[7] = 2 * (y * z + w * x);
    R[8] = 1 - 2 * (x * x + y * y);
}

void rot_to_quat(const double R[9], double q[4])
{
    /* Shepperd's method: pick the largest of w, x, y, z to divide by. */
    double tr = R[0] + R[4] + R[8], s;
    if (tr >= R[0] && tr >= R[4] && tr >= R[8]) {
        s = 2.0 * sqrt(1.0 + tr);
        q[0] = 0.25 * s;
        q[1] = (R[7] - R[5]) / s;
        q[2] = (R[2] - R[6]) / s;
        q[3] = (R[3] - R[1]) / s;
    } else if (R[0] >= R[4] && R[0] >= R[8]) {
        s = 2.0 * sqrt(1.0 + R[0] - R[4] - R[8]);
        q[0] = (R[7] - R[5]) / s;
        q[1] = 0.25 * s;
        q[2] = (R[1] + R[3]) / s;
        q[3] = (R[2] + R[6]) / s;
    } else if (R[4] >= R[8]) {
        s = 2.0 * sqrt(1.0 + R[4] - R[0] - R[8]);
        q[0] = (R[2] - R[6]) / s;
        q[1] = (R[1] + R[3]) / s;
        q[2] = 0.25 * s;
        q[3] = (R[5] + R[7]) / s;
    } else {
        s = 2.0 * sqrt(1.0 + R[8] - R[0] - R[4]);
        q[0] = (R[3] - R[1]) / s;
        q[1] = (R[2] + R[6]) / s;
        q[2] = (R[5] + R[7]) / s;
        q[3] = 0.25 * s;
    }
    if (q[0] < 0) {
        q[0] = -q[0];
        q[1] = -q[1];
        q[2] = -q[2];
        q[3] = -q[3];
    }
    s = quat_norm(q);
    q[0] /= s;
    q[1] /= s;
    q[2] /= s;
    q[3] /= s;
}

void quat_mul(const double a[4], const double b[4], double out[4])
{
    double w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    double x = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    double y = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    double z = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    out[0] = w;
    out[1] = x;
    out[2] = y;
    out[3] = z;
}

void quat_from_rotvec(const double w[3], double q[4])
{
    double angle = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    double half = 0.5 * angle;
    /* sin(half)/angle, with its Taylor series near zero. */
    double k = angle < 1e-8 ? 0.5 - angle * angle / 48.0 : sin(half) / angle;
    q[0] = cos(half);
    q[1] = k * w[0];
    q[2] = k * w[1];
    q[3] = k * w[2];
}

double quat_norm(const double q[4])
{
    return sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
}

void rot_axis_angle(const double a[3], double angle, double R[9])
{
    double c = cos(angle), s = sin(angle), t = 1.0 - c;
    double x = a[0], y = a[1], z = a[2];
    R[0] = t * x * x + c;
    R[1] = t * x * y - s * z;
    R[2] = t * x * z + s * y;
    R[3] = t * x * y + s * z;
    R[4] = t * y * y + c;
    R[5] = t * y * z - s * x;
    R[6] = t * x * z - s * y;
    R[7] = t * y * z + s * x;
    R[8] = t * z * z + c;
}

void vec3_cross(const double a[3], const double b[3], double out[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

double vec3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

void mat3_mul(const double A[9], const double B[9], double out[9])
{
    int i;
#ifdef __SSE2__
    /* columns 0 and 1 of a row in the two lanes, each entry's expression as below */
    const __m128d b0 = _mm_loadu_pd(B), b1 = _mm_loadu_pd(B + 3), b2 = _mm_loadu_pd(B + 6);
    for (i = 0; i < 3; i++) {
        const double a0 = A[3 * i], a1 = A[3 * i + 1], a2 = A[3 * i + 2];
        const double x2 = a0 * B[2] + a1 * B[5] + a2 * B[8];
        const __m128d s01 = _mm_add_pd(_mm_mul_pd(_mm_set1_pd(a0), b0), _mm_mul_pd(_mm_set1_pd(a1), b1));
        _mm_storeu_pd(out + 3 * i, _mm_add_pd(s01, _mm_mul_pd(_mm_set1_pd(a2), b2)));
        out[3 * i + 2] = x2;
    }
#else
    int j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            out[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
#endif
}

void mat3_vec(const double A[9], const double v[3], double out[3])
{
    double x = A[0] * v[0] + A[1] * v[1] + A[2] * v[2];
    double y = A[3] * v[0] + A[4] * v[1] + A[5] * v[2];
    double z = A[6] * v[0] + A[7] * v[1] + A[8] * v[2];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

void mat3_tvec(const double A[9], const double v[3], double out[3])
{
    double x = A[0] * v[0] + A[3] * v[1] + A[6] * v[2];
    double y = A[1] * v[0] + A[4] * v[1] + A[7] * v[2];
    double z = A[2] * v[0] + A[5] * v[1] + A[8] * v[2];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

static void skew(const double p[3], double S[9])
{
    S[0] = 0;
    S[1] = -p[2];
    S[2] = p[1];
    S[3] = p[2];
    S[4] = 0;
    S[5] = -p[0];
    S[6] = -p[1];
    S[7] = p[0];
    S[8] = 0;
}

static void put_block(double X[36], int bi, int bj, const double B[9])
{
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) X[6 * (3 * bi + i) + 3 * bj + j] = B[3 * i + j];
}

void spatial_to_parent(const pose *P, double X[36])
{
    double S[9], SR[9];
    static const double Z[9] = {0};
    skew(P->p, S);
    mat3_mul(S, P->R, SR);
    put_block(X, 0, 0, P->R);
    put_block(X, 0, 1, Z);
    put_block(X, 1, 0, SR);
    put_block(X, 1, 1, P->R);
}

void spatial_from_parent(const pose *P, double X[36])
{
    pose inv;
    pose_inverse(P, &inv);
    spatial_to_parent(&inv, X);
}

void spatial_inertia(double m, const double c[3], const double Ic[9], double I[36])
{
    double S[9], SST[9], mS[9], mST[9], top[9], mI[9] = {0};
    int i, j;
    skew(c, S);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double s = 0;
            int k;
            for (k = 0; k < 3; k++) s += S[3 * i + k] * S[3 * j + k];
            SST[3 * i + j] = s;
        }
    for (i = 0; i < 9; i++) {
        top[i] = Ic[i] + m * SST[i];
        mS[i] = m * S[i];
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) mST[3 * i + j] = mS[3 * j + i];
    mI[0] = mI[4] = mI[8] = m;
    put_block(I, 0, 0, top);
    put_block(I, 0, 1, mS);
    put_block(I, 1, 0, mST);
    put_block(I, 1, 1, mI);
}

/* out (3x3, stride 3) = R S R^T for a 3x3 block S stored with row stride 6;
 * a symmetric block (sym) is formed from its upper triangle and mirrored. */
static void rot_block_to_parent(const double *R, const double *S, double *out, int sym)
{
    double T[9];
    int i, j;
    for (i = 0; i < 3; i++) /* T = S R^T */
        for (j = 0; j < 3; j++) T[3 * i + j] = S[6 * i] * R[3 * j] + S[6 * i + 1] * R[3 * j + 1] + S[6 * i + 2] * R[3 * j + 2];
    for (i = 0; i < 3; i++) /* out = R T, fixed bounds so that it unrolls */
        for (j = 0; j < 3; j++) out[3 * i + j] = R[3 * i] * T[j] + R[3 * i + 1] * T[3 + j] + R[3 * i + 2] * T[6 + j];
    if (sym) {
        out[3] = out[1];
        out[6] = out[2];
        out[7] = out[5];
    }
}

void spatial_inertia_to_parent(const pose *P, const double IF[36], double IG[36])
{
    /* X* IF X*^T = X^T IF X with X = spatial_from_parent(P) = diag(R^T, R^T)
     * [1 0; -p~ 1]. With IF = [A B; B^T C], rotate the blocks (A' = R A R^T,
     * B' = R B R^T, C' = R C R^T), then shift the reference point:
     * IG = [A' + K + K^T - p~ C' p~,  B' + p~ C';  (B' + p~ C')^T,  C'],
     * K = p~ B'^T. Any symmetric IF (articulated inertias too); the result is
     * exactly symmetric. */
    const double *p = P->p;
    double A[9], B[9], C[9], E[9], K[9], px[9];
    int i, j, k;
    rot_block_to_parent(P->R, IF, A, 1);
    rot_block_to_parent(P->R, IF + 3, B, 0);
    rot_block_to_parent(P->R, IF + 21, C, 1);
    skew(p, px);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            double e = B[3 * i + j], kk = 0.0;
            for (k = 0; k < 3; k++) {
                e += px[3 * i + k] * C[3 * k + j];  /* B' + p~ C' */
                kk += px[3 * i + k] * B[3 * j + k]; /* p~ B'^T */
            }
            E[3 * i + j] = e;
            K[3 * i + j] = kk;
        }
    for (i = 0; i < 3; i++)
        for (j = i; j < 3; j++) {
            /* (p~ C' p~)_ij = sum_k (p~ C')_ik p~_kj, with p~ C' = E - B' */
            double v = A[3 * i + j] + K[3 * i + j] + K[3 * j + i];
            for (k = 0; k < 3; k++) v -= (E[3 * i + k] - B[3 * i + k]) * px[3 * k + j];
            IG[6 * i + j] = IG[6 * j + i] = v;
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            IG[6 * i + 3 + j] = IG[6 * (3 + j) + i] = E[3 * i + j];
            IG[6 * (3 + i) + 3 + j] = C[3 * i + j];
        }
}

void spatial_xform_motion(const pose *P, const double v[6], double out[6])
{
    /* [R^T w; R^T (v - p x w)], written out: this runs ~20 times per node. */
    const double *R = P->R, *p = P->p;
    double t0 = v[3], t1 = v[4], t2 = v[5];
    if (p[0] != 0.0 || p[1] != 0.0 || p[2] != 0.0) { /* rotations (revolute) skip this */
        t0 -= p[1] * v[2] - p[2] * v[1];
        t1 -= p[2] * v[0] - p[0] * v[2];
        t2 -= p[0] * v[1] - p[1] * v[0];
    }
    out[0] = R[0] * v[0] + R[3] * v[1] + R[6] * v[2];
    out[1] = R[1] * v[0] + R[4] * v[1] + R[7] * v[2];
    out[2] = R[2] * v[0] + R[5] * v[1] + R[8] * v[2];
    out[3] = R[0] * t0 + R[3] * t1 + R[6] * t2;
    out[4] = R[1] * t0 + R[4] * t1 + R[7] * t2;
    out[5] = R[2] * t0 + R[5] * t1 + R[8] * t2;
}

void spatial_xform_force_back(const pose *P, const double f[6], double out[6])
{
    double c[3];
    mat3_vec(P->R, f + 3, out + 3);
    mat3_vec(P->R, f, out);
    vec3_cross(P->p, out + 3, c);
    out[0] += c[0];
    out[1] += c[1];
    out[2] += c[2];
}

void spatial_xform_rows(const pose *P, const double *B, double *out)
{
    int i;
    for (i = 0; i < 6; i++) spatial_xform_motion(P, B + 6 * i, out + 6 * i);
}

/* out = R^T S R for 3x3 blocks stored with row stride 6 (S and out point
 * at the block's first entry); a symmetric block (sym) is formed from its
 * upper triangle and mirrored, so it comes out exactly symmetric. */
static void rot_congruence_block(const double *R, const double *S, double *out, int sym)
{
    double T[9];
    int i, j, k;
    for (i = 0; i < 3; i++) /* T = S R */
        for (j = 0; j < 3; j++) T[3 * i + j] = S[6 * i] * R[j] + S[6 * i + 1] * R[3 + j] + S[6 * i + 2] * R[6 + j];
    for (i = 0; i < 3; i++)
        for (j = sym ? i : 0; j < 3; j++) {
            double v = 0.0;
            for (k = 0; k < 3; k++) v += R[3 * k + i] * T[3 * k + j];
            out[6 * i + j] = v;
            if (sym) out[6 * j + i] = v;
        }
}

void spatial_xform_congruence(const pose *P, const double *S, double *out)
{
    double Y[36], YT[36];
    int i, j;
    if (P->p[0] == 0.0 && P->p[1] == 0.0 && P->p[2] == 0.0) {
        /* A pure rotation (every revolute J(q)): X = diag(R^T, R^T), so
         * X S X^T is R^T S_ab R blockwise; the lower-left block is the
         * transpose of the upper-right one. */
        rot_congruence_block(P->R, S, out, 1);
        rot_congruence_block(P->R, S + 3, out + 3, 0);
        rot_congruence_block(P->R, S + 21, out + 21, 1);
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) out[6 * (3 + j) + i] = out[6 * i + 3 + j];
        return;
    }
    spatial_xform_rows(P, S, Y); /* Y = S X^T */
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) YT[6 * j + i] = Y[6 * i + j];
    spatial_xform_rows(P, YT, Y); /* (X S X^T)^T = X S X^T */
    for (i = 0; i < 6; i++) {
        out[7 * i] = Y[7 * i];
        for (j = i + 1; j < 6; j++) out[6 * i + j] = out[6 * j + i] = 0.5 * (Y[6 * i + j] + Y[6 * j + i]);
    }
}

void spatial_force_from_parent(const pose *P, const double f[6], double out[6])
{
    /* The same arithmetic as a motion vector with the two halves swapped. */
    double sw[6] = {f[3], f[4], f[5], f[0], f[1], f[2]}, o[6];
    spatial_xform_motion(P, sw, o);
    out[0] = o[3];
    out[1] = o[4];
    out[2] = o[5];
    out[3] = o[0];
    out[4] = o[1];
    out[5] = o[2];
}

double vec3_dist(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(vec3_dot(d, d));
}

void sphere_merge(const double *s1, const double *s2, double *out)
{
    double d, R;
    int i;
    if (s1[3] < 0.0) { memcpy(out, s2, 4 * sizeof(double)); return; }
    if (s2[3] < 0.0) { memcpy(out, s1, 4 * sizeof(double)); return; }
    d = vec3_dist(s1, s2);
    if (d + s2[3] <= s1[3]) { memcpy(out, s1, 4 * sizeof(double)); return; }
    if (d + s1[3] <= s2[3]) { memcpy(out, s2, 4 * sizeof(double)); return; }
    R = 0.5 * (d + s1[3] + s2[3]);
    for (i = 0; i < 3; i++) out[i] = s1[i] + (R - s1[3]) / d * (s2[i] - s1[i]);
    out[3] = R * (1.0 + 1e-12);
}
