/* dense.c -- small dense kernels. */
#include "dense.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "avx.h"

/* AVX for the long reflections of dense_qr_append (dense_qr_append_simd):
 * compiled for AVX by a function attribute whatever the build's flags, run
 * only when the caller says the processor has it (the tree's flag, set by
 * dca_enable). "avx", not "fma": every lane rounds as the scalar code. */
#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define DENSE_AVX 1
#define DENSE_TARGET_AVX __attribute__((target("avx")))
#endif

void dense_mul(const double *A, const double *B, double *C, int m, int k, int n)
{
    int i, j, l;
    for (i = 0; i < m; i++) {
        double *c = C + (long)i * n;
        for (j = 0; j < n; j++) c[j] = 0.0;
        for (l = 0; l < k; l++) {
            double a = A[(long)i * k + l];
            const double *b = B + (long)l * n;
            for (j = 0; j < n; j++) c[j] += a * b[j];
        }
    }
}

void dense_mul_tn(const double *A, const double *B, double *C, int m, int k, int n)
{
    int i, j, l;
    for (i = 0; i < m * n; i++) C[i] = 0.0;
    for (l = 0; l < k; l++) {
        const double *b = B + (long)l * n;
        for (i = 0; i < m; i++) {
            double a = A[(long)l * m + i];
            double *c = C + (long)i * n;
            for (j = 0; j < n; j++) c[j] += a * b[j];
        }
    }
}

void dense_mul_nt(const double *A, const double *B, double *C, int m, int k, int n)
{
    int i, j, l;
    for (i = 0; i < m; i++) {
        const double *a = A + (long)i * k;
        for (j = 0; j < n; j++) {
            const double *b = B + (long)j * k;
            double s = 0.0;
            for (l = 0; l < k; l++) s += a[l] * b[l];
            C[(long)i * n + j] = s;
        }
    }
}

void dense_matvec(const double *A, const double *x, double *y, int m, int n)
{
    int i, j;
    for (i = 0; i < m; i++) {
        double s = 0.0;
        for (j = 0; j < n; j++) s += A[(long)i * n + j] * x[j];
        y[i] = s;
    }
}

void dense_tmatvec(const double *A, const double *x, double *y, int m, int n)
{
    int i, j;
    for (j = 0; j < n; j++) y[j] = 0.0;
    for (i = 0; i < m; i++)
        for (j = 0; j < n; j++) y[j] += A[(long)i * n + j] * x[i];
}

void dense_symmetrize(double *A, int n)
{
    int i, j;
    for (i = 0; i < n; i++)
        for (j = i + 1; j < n; j++) {
            double s = 0.5 * (A[i * n + j] + A[j * n + i]);
            A[i * n + j] = s;
            A[j * n + i] = s;
        }
}

/* In-place lower Cholesky factor; 0 on success, -1 at a non-positive pivot. */
static int cholesky(double *L, int n)
{
    int i, j, k;
    for (j = 0; j < n; j++) {
        double d = L[j * n + j];
        for (k = 0; k < j; k++) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 0.0)) return -1;
        d = sqrt(d);
        L[j * n + j] = d;
        for (i = j + 1; i < n; i++) {
            double s = L[i * n + j];
            for (k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = s / d;
        }
    }
    return 0;
}

static int inverse_cholesky(const double *A, double *out, int n)
{
    double L[36], Linv[36];
    int i, j, k;
    memcpy(L, A, sizeof(double) * n * n);
    if (cholesky(L, n) != 0) return -1;
    /* Linv = L^{-1} (lower), then out = Linv^T Linv. */
    for (i = 0; i < n * n; i++) Linv[i] = 0.0;
    for (j = 0; j < n; j++) {
        Linv[j * n + j] = 1.0 / L[j * n + j];
        for (i = j + 1; i < n; i++) {
            double s = 0.0;
            for (k = j; k < i; k++) s -= L[i * n + k] * Linv[k * n + j];
            Linv[i * n + j] = s / L[i * n + i];
        }
    }
    for (i = 0; i < n; i++)
        for (j = 0; j <= i; j++) {
            double s = 0.0;
            for (k = i; k < n; k++) s += Linv[k * n + i] * Linv[k * n + j];
            out[i * n + j] = s;
            out[j * n + i] = s;
        }
    return 0;
}

static int inverse_lu(const double *A, double *out, int n)
{
    double M[36], I[36];
    int i, j, k;
    memcpy(M, A, sizeof(double) * n * n);
    for (i = 0; i < n * n; i++) I[i] = 0.0;
    for (i = 0; i < n; i++) I[i * n + i] = 1.0;
    for (k = 0; k < n; k++) {
        int piv = k;
        double best = fabs(M[k * n + k]);
        for (i = k + 1; i < n; i++)
            if (fabs(M[i * n + k]) > best) {
                best = fabs(M[i * n + k]);
                piv = i;
            }
        if (!(best > 0.0)) return -1;
        if (piv != k)
            for (j = 0; j < n; j++) {
                double t = M[k * n + j];
                M[k * n + j] = M[piv * n + j];
                M[piv * n + j] = t;
                t = I[k * n + j];
                I[k * n + j] = I[piv * n + j];
                I[piv * n + j] = t;
            }
        for (i = 0; i < n; i++) {
            double f;
            if (i == k) continue;
            f = M[i * n + k] / M[k * n + k];
            if (f == 0.0) continue;
            for (j = k; j < n; j++) M[i * n + j] -= f * M[k * n + j];
            for (j = 0; j < n; j++) I[i * n + j] -= f * I[k * n + j];
        }
    }
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) out[i * n + j] = I[i * n + j] / M[i * n + i];
    dense_symmetrize(out, n);
    return 0;
}

int dense_cholesky6(const double *A, double *C)
{
    int i, j, k;
    for (i = 0; i < 36; i++) C[i] = 0.0;
    for (j = 0; j < 6; j++) {
        double d = A[7 * j], inv;
        for (k = 0; k < j; k++) d -= C[6 * j + k] * C[6 * j + k];
        if (!(d > 0.0) || !isfinite(d)) return -1;
        d = sqrt(d);
        C[7 * j] = d;
        inv = 1.0 / d;
        for (i = j + 1; i < 6; i++) {
            double s = A[6 * i + j];
            for (k = 0; k < j; k++) s -= C[6 * i + k] * C[6 * j + k];
            C[6 * i + j] = s * inv;
        }
    }
    return 0;
}

/* V = A^{-1} = C^{-T} C^{-1} from the Cholesky factor C (6x6): Ci = C^{-1}
 * column by column (Ci_jj = 1 / C_jj; Ci_ij = (0 - sum_{k=j}^{i-1} C_ik Ci_kj)
 * / C_ii, the terms subtracted in k's order), then V_ij = 0 + sum_{k=i}^{5}
 * Ci_ki Ci_kj (j <= i, added in k's order) and V_ji = V_ij. Written out,
 * one named value per entry of Ci: the same operations in the same order as
 * those loops (a third of their instructions; the inverse-inertia node
 * update calls it once a node). */
void dense_cholesky6_inverse(const double *C, double *V)
{
    double c00, c10, c20, c30, c40, c50, c11, c21, c31, c41, c51,
        c22, c32, c42, c52, c33, c43, c53, c44, c54, c55;
    c00 = 1.0 / C[0];
    c10 = (0.0 - C[6] * c00) / C[7];
    c20 = (0.0 - C[12] * c00 - C[13] * c10) / C[14];
    c30 = (0.0 - C[18] * c00 - C[19] * c10 - C[20] * c20) / C[21];
    c40 = (0.0 - C[24] * c00 - C[25] * c10 - C[26] * c20 - C[27] * c30) / C[28];
    c50 = (0.0 - C[30] * c00 - C[31] * c10 - C[32] * c20 - C[33] * c30 - C[34] * c40) / C[35];
    c11 = 1.0 / C[7];
    c21 = (0.0 - C[13] * c11) / C[14];
    c31 = (0.0 - C[19] * c11 - C[20] * c21) / C[21];
    c41 = (0.0 - C[25] * c11 - C[26] * c21 - C[27] * c31) / C[28];
    c51 = (0.0 - C[31] * c11 - C[32] * c21 - C[33] * c31 - C[34] * c41) / C[35];
    c22 = 1.0 / C[14];
    c32 = (0.0 - C[20] * c22) / C[21];
    c42 = (0.0 - C[26] * c22 - C[27] * c32) / C[28];
    c52 = (0.0 - C[32] * c22 - C[33] * c32 - C[34] * c42) / C[35];
    c33 = 1.0 / C[21];
    c43 = (0.0 - C[27] * c33) / C[28];
    c53 = (0.0 - C[33] * c33 - C[34] * c43) / C[35];
    c44 = 1.0 / C[28];
    c54 = (0.0 - C[34] * c44) / C[35];
    c55 = 1.0 / C[35];
    V[0] = 0.0 + c00 * c00 + c10 * c10 + c20 * c20 + c30 * c30 + c40 * c40 + c50 * c50;
    V[6] = 0.0 + c11 * c10 + c21 * c20 + c31 * c30 + c41 * c40 + c51 * c50;
    V[1] = V[6];
    V[7] = 0.0 + c11 * c11 + c21 * c21 + c31 * c31 + c41 * c41 + c51 * c51;
    V[12] = 0.0 + c22 * c20 + c32 * c30 + c42 * c40 + c52 * c50;
    V[2] = V[12];
    V[13] = 0.0 + c22 * c21 + c32 * c31 + c42 * c41 + c52 * c51;
    V[8] = V[13];
    V[14] = 0.0 + c22 * c22 + c32 * c32 + c42 * c42 + c52 * c52;
    V[18] = 0.0 + c33 * c30 + c43 * c40 + c53 * c50;
    V[3] = V[18];
    V[19] = 0.0 + c33 * c31 + c43 * c41 + c53 * c51;
    V[9] = V[19];
    V[20] = 0.0 + c33 * c32 + c43 * c42 + c53 * c52;
    V[15] = V[20];
    V[21] = 0.0 + c33 * c33 + c43 * c43 + c53 * c53;
    V[24] = 0.0 + c44 * c40 + c54 * c50;
    V[4] = V[24];
    V[25] = 0.0 + c44 * c41 + c54 * c51;
    V[10] = V[25];
    V[26] = 0.0 + c44 * c42 + c54 * c52;
    V[16] = V[26];
    V[27] = 0.0 + c44 * c43 + c54 * c53;
    V[22] = V[27];
    V[28] = 0.0 + c44 * c44 + c54 * c54;
    V[30] = 0.0 + c55 * c50;
    V[5] = V[30];
    V[31] = 0.0 + c55 * c51;
    V[11] = V[31];
    V[32] = 0.0 + c55 * c52;
    V[17] = V[32];
    V[33] = 0.0 + c55 * c53;
    V[23] = V[33];
    V[34] = 0.0 + c55 * c54;
    V[29] = V[34];
    V[35] = 0.0 + c55 * c55;
}

void dense_cholesky6_lower_solve(const double *C, const double *b, double *w, int n)
{
    int i, k, c;
    for (c = 0; c < n; c++)
        for (i = 0; i < 6; i++) {
            double s = b[n * i + c];
            for (k = 0; k < i; k++) s -= C[6 * i + k] * w[n * k + c];
            w[n * i + c] = s / C[7 * i];
        }
}

void dense_cholesky6_upper_solve(const double *C, const double *w, double *v, int n)
{
    int i, k, c;
    for (c = 0; c < n; c++)
        for (i = 5; i >= 0; i--) {
            double s = w[n * i + c];
            for (k = i + 1; k < 6; k++) s -= C[6 * k + i] * v[n * k + c];
            v[n * i + c] = s / C[7 * i];
        }
}

/* The 6x6 case through the factor above. */
static int inverse_cholesky6(const double *A, double *out)
{
    double C[36];
    if (dense_cholesky6(A, C) != 0) return -1;
    dense_cholesky6_inverse(C, out);
    return 0;
}

int dense_spd_inverse(const double *A, double *out, int n)
{
    int i, st = n == 6 ? inverse_cholesky6(A, out) : inverse_cholesky(A, out, n);
    if (st != 0 && inverse_lu(A, out, n) != 0) return -1;
    for (i = 0; i < n * n; i++)
        if (!isfinite(out[i])) return -1;
    return 0;
}

/* Apply H = I - tau v v^T, v = [1; a] (a: m entries), to ncols columns:
 * column c's pivot entry is t[c ts], its other entries x[c xs .. c xs + m).
 * The usual lengths (m <= 6) have their own fully unrolled loops, with v
 * in registers. */
#define REFLECT_FIXED(M)                                                            \
    static void reflect_##M(const double *a, double tau, double *t, long ts,        \
                            double *x, long xs, int ncols)                          \
    {                                                                               \
        double v[M];                                                                \
        int c, i;                                                                   \
        for (i = 0; i < M; i++) v[i] = a[i];                                        \
        for (c = 0; c < ncols; c++, t += ts, x += xs) {                             \
            double sum = *t, f;                                                     \
            for (i = 0; i < M; i++) sum += v[i] * x[i];                             \
            f = tau * sum;                                                          \
            *t -= f;                                                                \
            for (i = 0; i < M; i++) x[i] -= f * v[i];                               \
        }                                                                           \
    }
REFLECT_FIXED(1)
REFLECT_FIXED(2)
REFLECT_FIXED(3)
REFLECT_FIXED(4)
REFLECT_FIXED(5)
REFLECT_FIXED(6)
#undef REFLECT_FIXED

static void reflect_columns(const double *a, int m, double tau, double *t, long ts, double *x,
                            long xs, int ncols)
{
    int c, i;
    switch (m) {
    case 0: /* v = [1]: H scales the pivot by 1 - tau */
        for (c = 0; c < ncols; c++) t[c * ts] *= 1.0 - tau;
        return;
    case 1: reflect_1(a, tau, t, ts, x, xs, ncols); return;
    case 2: reflect_2(a, tau, t, ts, x, xs, ncols); return;
    case 3: reflect_3(a, tau, t, ts, x, xs, ncols); return;
    case 4: reflect_4(a, tau, t, ts, x, xs, ncols); return;
    case 5: reflect_5(a, tau, t, ts, x, xs, ncols); return;
    case 6: reflect_6(a, tau, t, ts, x, xs, ncols); return;
    default: break;
    }
    /* longer: two columns per pass over a */
    for (c = 0; c + 1 < ncols; c += 2, t += 2 * ts, x += 2 * xs) {
        double *x2 = x + xs, s1 = t[0], s2 = t[ts], f1, f2;
        for (i = 0; i < m; i++) {
            s1 += a[i] * x[i];
            s2 += a[i] * x2[i];
        }
        f1 = tau * s1;
        f2 = tau * s2;
        t[0] -= f1;
        t[ts] -= f2;
        for (i = 0; i < m; i++) {
            x[i] -= f1 * a[i];
            x2[i] -= f2 * a[i];
        }
    }
    if (c < ncols) {
        double sum = *t, f;
        for (i = 0; i < m; i++) sum += a[i] * x[i];
        f = tau * sum;
        *t -= f;
        for (i = 0; i < m; i++) x[i] -= f * a[i];
    }
}

#ifdef DENSE_AVX
/* reflect_columns' loop for m > 6 with four columns a pass: their sums in the
 * four lanes of one register, each from its pivot entry and then in the
 * order of i (a 4 x 4 block of the columns transposed so that lane k meets
 * column k's entries one i at a time), then f = tau sum; each column's
 * x[i] - f a[i] four entries at a time; then two columns in two lanes, and
 * one. Each column's arithmetic is that of the scalar loop. Returns ncols. */
DENSE_TARGET_AVX static int reflect_long_avx(const double *a, int m, double tau, double *t, long ts, double *x,
                                             long xs, int ncols)
{
    const __m256d tt = _mm256_set1_pd(tau);
    int c, i;
    for (c = 0; c + 3 < ncols; c += 4, t += 4 * ts, x += 4 * xs) {
        double *x0 = x, *x1 = x + xs, *x2 = x1 + xs, *x3 = x2 + xs, f[4];
        __m256d acc = _mm256_set_pd(t[3 * ts], t[2 * ts], t[ts], t[0]);
        for (i = 0; i + 3 < m; i += 4) {
            const __m256d ra = _mm256_loadu_pd(x0 + i), rb = _mm256_loadu_pd(x1 + i), rg = _mm256_loadu_pd(x2 + i),
                          rh = _mm256_loadu_pd(x3 + i);
            const __m256d t0 = _mm256_unpacklo_pd(ra, rb), t1 = _mm256_unpackhi_pd(ra, rb); /* (a0 b0 a2 b2), (a1 b1 a3 b3) */
            const __m256d t2 = _mm256_unpacklo_pd(rg, rh), t3 = _mm256_unpackhi_pd(rg, rh);
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_broadcast_sd(a + i), _mm256_permute2f128_pd(t0, t2, 0x20)));
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_broadcast_sd(a + i + 1), _mm256_permute2f128_pd(t1, t3, 0x20)));
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_broadcast_sd(a + i + 2), _mm256_permute2f128_pd(t0, t2, 0x31)));
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_broadcast_sd(a + i + 3), _mm256_permute2f128_pd(t1, t3, 0x31)));
        }
        for (; i < m; i++) {
            const __m128d lo = _mm_loadh_pd(_mm_load_sd(x0 + i), x1 + i), hi = _mm_loadh_pd(_mm_load_sd(x2 + i), x3 + i);
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_broadcast_sd(a + i),
                                                   _mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1)));
        }
        _mm256_storeu_pd(f, _mm256_mul_pd(tt, acc));
        t[0] -= f[0];
        t[ts] -= f[1];
        t[2 * ts] -= f[2];
        t[3 * ts] -= f[3];
        avx_axpy4(x0, x1, x2, x3, f, a, m);
    }
    if (c + 1 < ncols) { /* two columns: their sums in two lanes */
        double *x0 = x, *x1 = x + xs, f[2];
        __m128d acc = _mm_set_pd(t[ts], t[0]);
        for (i = 0; i < m; i++)
            acc = _mm_add_pd(acc, _mm_mul_pd(_mm_set1_pd(a[i]), _mm_loadh_pd(_mm_load_sd(x0 + i), x1 + i)));
        _mm_storeu_pd(f, _mm_mul_pd(_mm256_castpd256_pd128(tt), acc));
        t[0] -= f[0];
        t[ts] -= f[1];
        avx_axpy1(x0, f[0], a, m);
        avx_axpy1(x1, f[1], a, m);
        c += 2;
        t += 2 * ts;
        x += 2 * xs;
    }
    if (c < ncols) {
        double sum = *t, f;
        for (i = 0; i < m; i++) sum += a[i] * x[i];
        f = tau * sum;
        *t -= f;
        avx_axpy1(x, f, a, m);
        c++;
    }
    return c;
}
#endif

/* reflect_columns, with the AVX loop for m > 6 where avx says. */
static inline void reflect_columns_simd(const double *a, int m, double tau, double *t, long ts, double *x, long xs,
                                 int ncols, int avx)
{
#ifdef DENSE_AVX
    if (avx && m > 6 && ncols >= 4) {
        (void)reflect_long_avx(a, m, tau, t, ts, x, xs, ncols);
        return;
    }
#endif
    (void)avx;
    reflect_columns(a, m, tau, t, ts, x, xs, ncols);
}

int dense_qr_append(double *R, int n, int *present, double *D, int p)
{
    return dense_qr_append_simd(R, n, present, D, p, 0);
}

int dense_qr_append_simd(double *R, int n, int *present, double *D, int p, int avx)
{
    int j, i, c, s = 0, rows = 0;
    for (j = 0; j < n; j++) {
        double *a, *rj = R + (long)j * n, norm = 0.0, alpha, v0, tau, scale = 0.0, top;
        int q = p - s, pr = present[j], i0;
        if (q == 0) {
            for (; j < n; j++) rows += present[j] != 0;
            return rows;
        }
        a = D + (long)j * p + s;
        for (i = 0; i < q; i++)
            if (fabs(a[i]) > scale) scale = fabs(a[i]);
        if (scale < DBL_MIN) {
            /* nothing below the pivot, or only subnormal residue of exact zeros
             * (a nearly straight chain leaves some): such entries carry too few
             * bits for a reflection to stay orthogonal (its alpha would round to
             * the subnormal grid), and their squares are below DBL_MIN^2: they
             * are dropped */
            for (i = 0; i < q; i++) a[i] = 0.0;
            rows += pr != 0;
            continue;
        }
        if (!pr && q == 1) {
            /* the last live row, alone in column j: it becomes R's row j as is
             * (dlarfg's tau = 0 when nothing is below the pivot) */
            for (c = j + 1; c < n; c++) rj[c] = D[(long)c * p + s];
            rj[j] = a[0];
            present[j] = 1;
            s++;
            rows++;
            continue;
        }
        top = pr ? rj[j] : a[0];
        if (fabs(top) > scale) scale = fabs(top);
        i0 = pr ? 0 : 1;
        {
            const double inv = 1.0 / scale; /* finite: scale >= DBL_MIN */
            for (i = i0; i < q; i++) norm += (a[i] * inv) * (a[i] * inv);
            norm += (top * inv) * (top * inv);
        }
        norm = scale * sqrt(norm);
        alpha = top > 0 ? -norm : norm;
        v0 = top - alpha;
        /* H = I - tau v v^T with v = [1; a / v0] (|a_i / v0| <= 1: LAPACK's
         * dlarfg scaling) and tau = -v0 / alpha in [1, 2] */
        tau = -v0 / alpha;
        {
            const double iv = 1.0 / v0; /* |v0| >= scale >= DBL_MIN */
            for (i = i0; i < q; i++) a[i] *= iv;
        }
        if (pr) reflect_columns_simd(a + i0, q - i0, tau, rj + j + 1, 1, D + (long)(j + 1) * p + s + i0, p, n - j - 1, avx);
        else reflect_columns_simd(a + 1, q - 1, tau, D + (long)(j + 1) * p + s, p, D + (long)(j + 1) * p + s + 1, p, n - j - 1,
                                  avx);
        if (!pr) {
            /* D's first live row becomes R's row j (zero left of j already) */
            for (c = j + 1; c < n; c++) rj[c] = D[(long)c * p + s];
            present[j] = 1;
            s++;
        }
        rj[j] = alpha;
        rows++;
    }
    return rows;
}

int dense_joint_space_inverse(const double *S, const double *U, int d, double *Dinv)
{
    double D[36];
    int i, j, r;
    for (i = 0; i < d; i++)
        for (j = 0; j < d; j++) {
            double v = 0.0;
            for (r = 0; r < 6; r++) v += S[r * d + i] * U[6 * j + r];
            D[d * i + j] = v;
        }
    dense_symmetrize(D, d);
    return dense_spd_inverse(D, Dinv, d);
}

void dense_free_accel(const double *Dinv, const double *u, double *ac, double *qdd)
{
    double w[6];
    int j;
    dense_matvec6(Dinv, u, w);
    for (j = 0; j < 6; j++) {
        qdd[j] = w[j] - ac[j];
        ac[j] = w[j];
    }
}

void dense_joint_accel(const double *S, const double *U, const double *Dinv, int d, const double *u, double *ac,
                       double *qdd)
{
    double rhs[6];
    int i, j;
    for (j = 0; j < d; j++) {
        double v = u[j];
        for (i = 0; i < 6; i++) v -= U[6 * j + i] * ac[i];
        rhs[j] = v;
    }
    for (j = 0; j < d; j++) {
        double v = 0.0;
        for (i = 0; i < d; i++) v += Dinv[d * j + i] * rhs[i];
        qdd[j] = v;
    }
    for (i = 0; i < 6; i++) {
        double v = 0.0;
        for (j = 0; j < d; j++) v += S[i * d + j] * qdd[j];
        ac[i] += v;
    }
}
