/* test_dense.c -- src/base/dense.c: the small dense kernels against naive loops,
 * and dense_spd_inverse on well-conditioned SPD matrices, on badly scaled
 * ones (mass ratios), on a numerically singular SPD matrix that defeats
 * Cholesky (the LU fallback), and its failures (-1). */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "dense.h"

static void fill(uint64_t *s, double *a, int n)
{
    int i;
    for (i = 0; i < n; i++) a[i] = test_uniform(s, -1, 1);
}

/* Poison an output so that an entry the kernel forgets to write shows. */
static void poison(double *a, int n)
{
    int i;
    for (i = 0; i < n; i++) a[i] = NAN;
}

/* Naive references, summing in the textbook order. */
static void naive_mul(const double *A, const double *B, double *C, int m, int k, int n, int ta, int tb)
{
    int i, j, l;
    for (i = 0; i < m; i++)
        for (j = 0; j < n; j++) {
            double s = 0;
            for (l = 0; l < k; l++) {
                double a = ta ? A[l * m + i] : A[i * k + l];
                double b = tb ? B[j * k + l] : B[l * n + j];
                s += a * b;
            }
            C[i * n + j] = s;
        }
}

/* Products of k terms of size <= 1: rounding <= k u in each entry (k <= 13
 * here); 1e-14 absolute is a factor of ten above that and far below the
 * O(0.1) error of any indexing mistake. */
#define PROD_TOL 1e-14

static void test_products(void **state)
{
    static const int shapes[][3] = {{1, 1, 1}, {1, 6, 1}, {6, 1, 6}, {2, 3, 4}, {6, 6, 6},
                                    {5, 7, 3}, {12, 6, 6}, {6, 13, 2}, {3, 2, 12}};
    uint64_t s = 11;
    size_t t;
    (void)state;
    for (t = 0; t < sizeof shapes / sizeof shapes[0]; t++) {
        int m = shapes[t][0], k = shapes[t][1], n = shapes[t][2];
        double A[200], B[200], C[200], R[200], x[20], y[20], yr[20];
        int i;
        fill(&s, A, m * k);
        fill(&s, B, k * n);
        poison(C, m * n);
        dense_mul(A, B, C, m, k, n);
        naive_mul(A, B, R, m, k, n, 0, 0);
        assert_true(test_max_abs_diff(C, R, (size_t)(m * n)) <= PROD_TOL);
        /* A^T B with A (k x m) */
        poison(C, m * n);
        dense_mul_tn(A, B, C, m, k, n);
        naive_mul(A, B, R, m, k, n, 1, 0);
        assert_true(test_max_abs_diff(C, R, (size_t)(m * n)) <= PROD_TOL);
        /* A B^T with B (n x k) */
        poison(C, m * n);
        dense_mul_nt(A, B, C, m, k, n);
        naive_mul(A, B, R, m, k, n, 0, 1);
        assert_true(test_max_abs_diff(C, R, (size_t)(m * n)) <= PROD_TOL);
        /* y = A x, A (m x k) */
        fill(&s, x, k);
        poison(y, m);
        dense_matvec(A, x, y, m, k);
        naive_mul(A, x, yr, m, k, 1, 0, 0);
        assert_true(test_max_abs_diff(y, yr, (size_t)m) <= PROD_TOL);
        /* y = A^T x, A (m x k) */
        fill(&s, x, m);
        poison(y, k);
        dense_tmatvec(A, x, y, m, k);
        naive_mul(A, x, yr, k, m, 1, 1, 0);
        assert_true(test_max_abs_diff(y, yr, (size_t)k) <= PROD_TOL);
        for (i = 0; i < m * n; i++) assert_true(isfinite(C[i]));
    }
    /* The fixed-size 6x6 kernels of the hot path. */
    {
        double A[36], B[36], C[36], R[36], x[6], y[6], yr[6];
        int rep;
        for (rep = 0; rep < 20; rep++) {
            fill(&s, A, 36);
            fill(&s, B, 36);
            fill(&s, x, 6);
            poison(C, 36);
            dense_mul66(A, B, C);
            naive_mul(A, B, R, 6, 6, 6, 0, 0);
            assert_true(test_max_abs_diff(C, R, 36) <= PROD_TOL);
            poison(C, 36);
            dense_mul66_nt(A, B, C);
            naive_mul(A, B, R, 6, 6, 6, 0, 1);
            assert_true(test_max_abs_diff(C, R, 36) <= PROD_TOL);
            poison(y, 6);
            dense_matvec6(A, x, y);
            naive_mul(A, x, yr, 6, 6, 1, 0, 0);
            assert_true(test_max_abs_diff(y, yr, 6) <= PROD_TOL);
            poison(y, 6);
            dense_tmatvec6(A, x, y);
            naive_mul(A, x, yr, 6, 6, 1, 1, 0);
            assert_true(test_max_abs_diff(y, yr, 6) <= PROD_TOL);
        }
    }
}

static void test_symmetrize(void **state)
{
    uint64_t s = 12;
    int n;
    (void)state;
    for (n = 1; n <= 7; n++) {
        double A[49], S[49];
        int i, j;
        fill(&s, A, n * n);
        memcpy(S, A, sizeof(double) * (size_t)(n * n));
        dense_symmetrize(S, n);
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) {
                /* (a + b) / 2 is exact up to one rounding, and symmetric exactly */
                assert_true(S[i * n + j] == S[j * n + i]);
                assert_true(fabs(S[i * n + j] - 0.5 * (A[i * n + j] + A[j * n + i])) <= 1e-16);
            }
    }
}

/* A = B B^T + shift I, n x n. */
static void random_spd(uint64_t *s, double *A, int n, double shift)
{
    double B[36];
    int i;
    fill(s, B, n * n);
    naive_mul(B, B, A, n, n, n, 0, 1);
    for (i = 0; i < n; i++) A[i * n + i] += shift;
    dense_symmetrize(A, n);
}

/* max |A X - I| */
static double inverse_residual(const double *A, const double *X, int n)
{
    double P[36], I[36] = {0};
    int i;
    naive_mul(A, X, P, n, n, n, 0, 0);
    for (i = 0; i < n; i++) I[i * n + i] = 1.0;
    return test_max_abs_diff(P, I, (size_t)(n * n));
}

/* Well-conditioned SPD, every size 1..6 (6 has its own unrolled path):
 * cond(A) <= (n + shift) / shift ~ 15 with shift 0.5, so the residual is a
 * few ulps times 15 n; 1e-13 is ten times that. The output may alias A. */
static void test_spd_inverse_random(void **state)
{
    uint64_t s = 13;
    int n, rep;
    (void)state;
    for (n = 1; n <= 6; n++)
        for (rep = 0; rep < 50; rep++) {
            double A[36], X[36], Y[36];
            int i, j;
            random_spd(&s, A, n, 0.5);
            poison(X, n * n);
            assert_int_equal(dense_spd_inverse(A, X, n), 0);
            assert_true(inverse_residual(A, X, n) < 1e-13);
            for (i = 0; i < n; i++)
                for (j = 0; j < n; j++) assert_true(X[i * n + j] == X[j * n + i]);
            memcpy(Y, A, sizeof Y);
            assert_int_equal(dense_spd_inverse(Y, Y, n), 0);
            assert_true(test_max_abs_diff(Y, X, (size_t)(n * n)) < 1e-13);
        }
}

/* Mass ratios: A = D C D with D = diag(1e-6 .. 1e6) and C well conditioned.
 * cond(A) ~ 1e24, but Cholesky is invariant under this scaling, so the
 * scaled residual (D X D) C - I stays at cond(C) u ~ 1e-14 (tolerance 1e-12
 * for the 6x6 products of entries up to ~10). */
static void test_spd_inverse_scaled(void **state)
{
    uint64_t s = 14;
    int rep;
    (void)state;
    for (rep = 0; rep < 50; rep++) {
        double C[36], A[36], X[36], DXD[36], d[6];
        int i, j;
        random_spd(&s, C, 6, 0.5);
        for (i = 0; i < 6; i++) d[i] = pow(10.0, test_uniform(&s, -6, 6));
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) A[6 * i + j] = d[i] * C[6 * i + j] * d[j];
        assert_int_equal(dense_spd_inverse(A, X, 6), 0);
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) DXD[6 * i + j] = d[i] * X[6 * i + j] * d[j];
        assert_true(inverse_residual(DXD, C, 6) < 1e-12);
    }
}

/* Textbook Cholesky (the algorithm the library tries first), dividing by
 * the pivot or multiplying by its reciprocal: 1 if both meet a non-positive
 * pivot. Used to prove that a matrix reaches the fallback. */
static int cholesky_variant_fails(const double *A, int n, int reciprocal)
{
    double L[36];
    int i, j, k;
    memcpy(L, A, sizeof(double) * (size_t)(n * n));
    for (j = 0; j < n; j++) {
        double d = L[j * n + j];
        for (k = 0; k < j; k++) d -= L[j * n + k] * L[j * n + k];
        if (!(d > 0.0)) return 1;
        d = sqrt(d);
        L[j * n + j] = d;
        for (i = j + 1; i < n; i++) {
            double t = L[i * n + j];
            for (k = 0; k < j; k++) t -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = reciprocal ? t * (1.0 / d) : t / d;
        }
    }
    return 0;
}

static int cholesky_fails(const double *A, int n)
{
    return cholesky_variant_fails(A, n, 0) && cholesky_variant_fails(A, n, 1);
}

/* A symmetric indefinite, well-conditioned matrix: Cholesky stops at the
 * first pivot, so the result is entirely the LU fallback's, and it must be
 * the exact inverse (residual tolerance as for the random SPD case). */
static void test_spd_inverse_fallback_accuracy(void **state)
{
    uint64_t s = 15;
    int n, rep;
    (void)state;
    for (n = 2; n <= 6; n++)
        for (rep = 0; rep < 20; rep++) {
            double A[36], X[36];
            random_spd(&s, A, n, 0.5);
            A[0] = -A[0] - 1.0; /* a negative first pivot */
            assert_true(cholesky_fails(A, n));
            assert_int_equal(dense_spd_inverse(A, X, n), 0);
            assert_true(inverse_residual(A, X, n) < 1e-12);
        }
}

/* An SPD matrix that Cholesky cannot factor: A = B B^T with the integer
 * B = [9224 3193; 4599 1592] of determinant 1, so A is exactly SPD with
 * exactly representable entries, det A = 1 and the exact inverse is the
 * integer adjugate. cond(A) ~ 1.4e16 > 1/u, so the second pivot is lost to
 * rounding: the textbook Cholesky fails (asserted) and the fallback runs.
 * No method can get the scale of the inverse right here (cond(A) u ~ 1.6),
 * but its near-null direction is determined to ~u: the result must be
 * finite, symmetric, a positive multiple of the exact inverse along that
 * direction (positive definite, as V must be in the DCA), to 1e-12.
 * The matrix is embedded, permuted, in a 6x6 with a well-conditioned rest
 * that must come out exact (1e-14 relative). */
static void test_spd_inverse_fallback_ill_conditioned(void **state)
{
    const double a11 = 95277425.0, a12 = 47504432.0, a22 = 23685265.0;
    const double inv[3] = {a22, -a12, a11}; /* adjugate / det, det = 1 */
    const int bad[2] = {1, 4}, good[4] = {0, 2, 3, 5};
    const double rest[4] = {1.0, 2.0, 3.0, 4.0};
    double A[36] = {0}, X[36], x[3], alpha, nx, ni;
    int i, j, r;
    (void)state;
    /* exactness of the construction: a11 a22 - a12^2 = 1 in integers */
    assert_true(9224.0 * 9224 + 3193.0 * 3193 == a11 && 4599.0 * 4599 + 1592.0 * 1592 == a22);
    assert_true(9224.0 * 4599 + 3193.0 * 1592 == a12);
    A[6 * bad[0] + bad[0]] = a11;
    A[6 * bad[0] + bad[1]] = A[6 * bad[1] + bad[0]] = a12;
    A[6 * bad[1] + bad[1]] = a22;
    for (i = 0; i < 4; i++) A[7 * good[i]] = rest[i];
    for (r = 2; r <= 6; r += 4) {
        double A2[4] = {a11, a12, a12, a22}, *M = r == 2 ? A2 : A;
        int n = r, b0 = r == 2 ? 0 : bad[0], b1 = r == 2 ? 1 : bad[1];
        assert_true(cholesky_fails(M, n));
        poison(X, n * n);
        assert_int_equal(dense_spd_inverse(M, X, n), 0);
        for (i = 0; i < n * n; i++) assert_true(isfinite(X[i]));
        for (i = 0; i < n; i++)
            for (j = 0; j < n; j++) assert_true(X[i * n + j] == X[j * n + i]);
        x[0] = X[n * b0 + b0];
        x[1] = X[n * b0 + b1];
        x[2] = X[n * b1 + b1];
        /* x = alpha inv + e: alpha > 0 and e tiny */
        nx = sqrt(x[0] * x[0] + 2 * x[1] * x[1] + x[2] * x[2]);
        ni = sqrt(inv[0] * inv[0] + 2 * inv[1] * inv[1] + inv[2] * inv[2]);
        alpha = (x[0] * inv[0] + 2 * x[1] * inv[1] + x[2] * inv[2]) / (ni * ni);
        assert_true(alpha > 0.0);
        for (i = 0; i < 3; i++) assert_true(fabs(x[i] / nx - inv[i] / ni) < 1e-12);
        if (n == 6) {
            for (i = 0; i < 4; i++) {
                assert_true(fabs(X[7 * good[i]] - 1.0 / rest[i]) <= 1e-14 / rest[i]);
                for (j = 0; j < 6; j++)
                    if (j != good[i]) assert_true(fabs(X[6 * good[i] + j]) <= 1e-14 * nx);
            }
        }
    }
}

/* Failures: exactly singular matrices (rank-deficient with exact pivots of
 * 0), NaN entries, and a result that overflows. (Infinite entries are not
 * tested: the inverse's limit can be finite, e.g. diag(1, Inf) -> diag(1, 0),
 * and the header promises -1 only for singular input or non-finite output.) */
static void test_spd_inverse_failures(void **state)
{
    double X[36];
    (void)state;
    {
        double A[4] = {1, 1, 1, 1}; /* rank 1 */
        assert_int_equal(dense_spd_inverse(A, X, 2), -1);
    }
    {
        double A[9] = {2, 0, 1, 0, 0, 0, 1, 0, 2}; /* zero row and column */
        assert_int_equal(dense_spd_inverse(A, X, 3), -1);
    }
    {
        double A[36] = {0}; /* zero 6x6 (its own unrolled path first) */
        assert_int_equal(dense_spd_inverse(A, X, 6), -1);
    }
    {
        double A[36] = {0};
        int i;
        for (i = 0; i < 6; i++) A[7 * i] = 1.0;
        A[6 * 2 + 3] = A[6 * 3 + 2] = NAN;
        assert_int_equal(dense_spd_inverse(A, X, 6), -1);
        A[6 * 2 + 3] = A[6 * 3 + 2] = 0.0;
        A[35] = NAN;
        assert_int_equal(dense_spd_inverse(A, X, 6), -1);
        A[35] = 1.0;
        assert_int_equal(dense_spd_inverse(A, X, 6), 0); /* the control: now fine */
    }
    {
        double A[4] = {NAN, 0, 0, 1};
        assert_int_equal(dense_spd_inverse(A, X, 2), -1);
    }
    {
        /* SPD and factorable, but 1 / 1e-310 overflows to Inf */
        double A[4] = {1e-310, 0, 0, 1};
        assert_int_equal(dense_spd_inverse(A, X, 2), -1);
    }
}

/* Gram matrix G = sum over the present rows of R (n x n row-major) of r r^T,
 * plus D^T D for the p x n column-major D. */
static void gram(const double *R, const int *present, int n, const double *D, int p, double *G)
{
    int i, j, r;
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) {
            double s = 0;
            for (r = 0; r < n; r++)
                if (!present || present[r]) s += R[r * n + i] * R[r * n + j];
            for (r = 0; r < p; r++) s += D[i * p + r] * D[j * p + r];
            G[i * n + j] = s;
        }
}

/* dense_qr_append: the Gram matrix (what
 * ||T z||^2 evaluates) is kept to rounding (1e-13 of its largest entry:
 * n <= 20 reflections of unit-size entries), R stays upper triangular with
 * its rows where present says, and the row counts are right: on random
 * sizes, random present patterns (none in a third of the trials), D of full
 * and deficient rank, and entries scaled by 1e150 and 1e-160. */
static void test_qr_append(void **state)
{
    uint64_t s = 77;
    int trial;
    (void)state;
    for (trial = 0; trial < 400; trial++) {
        int n = 1 + (int)test_uniform(&s, 0, 19.99), p = (int)test_uniform(&s, 0, 9.99), i, j, rows, np = 0;
        int present[20], copy[20];
        double R[400], R0[400], D[200], D0[200], G0[400], G1[400], scale = 0, sc;
        for (j = 0; j < n; j++) present[j] = trial % 3 != 0 && test_uniform(&s, 0, 1) < 0.6;
        fill(&s, R, n * n);
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++)
                if (!present[j] || i < j) R[j * n + i] = 0.0;
        fill(&s, D, p * n);
        if (trial % 4 == 3 && p > 1) /* rank deficient: the last row of D copies the first */
            for (j = 0; j < n; j++) D[j * p + p - 1] = D[j * p];
        memcpy(R0, R, sizeof R);
        memcpy(D0, D, sizeof D);
        memcpy(copy, present, sizeof present);
        for (j = 0; j < n; j++) np += present[j];
        gram(R0, present, n, D0, p, G0);
        /* far from 1: the reflections are scaled (no overflow, no underflow) */
        sc = trial % 5 == 1 ? 1e150 : trial % 5 == 2 ? 1e-160 : 1.0;
        for (i = 0; i < n * n; i++) R[i] *= sc;
        for (i = 0; i < p * n; i++) D[i] *= sc;
        rows = dense_qr_append(R, n, present, D, p);
        for (i = 0; i < n * n; i++) R[i] /= sc;
        gram(R, present, n, NULL, 0, G1);
        for (i = 0; i < n * n; i++) scale = fmax(scale, fabs(G0[i]));
        for (i = 0; i < n * n; i++) assert_true(fabs(G1[i] - G0[i]) <= 1e-13 * (scale + 1));
        for (j = 0, i = 0; j < n; j++) i += present[j];
        assert_int_equal(rows, i);
        assert_true(rows >= np && rows <= np + p && rows <= n);
        for (j = 0; j < n; j++) {
            int c;
            if (copy[j]) assert_true(present[j]); /* rows never disappear */
            if (present[j])
                for (c = 0; c < j; c++) assert_true(R[j * n + c] == 0.0);
        }
    }
}

/* Subnormal entries (the rounding residue of exact zeros, as a nearly straight
 * chain leaves them) must not turn into NaN (1 / a subnormal overflows, and
 * inf * 0 is NaN) nor into a reflection that is not orthogonal (its alpha
 * would round to the subnormal grid: the Gram matrix's 1.49 came back as
 * 1.4899999981 before they were dropped). Every entry stays finite and the
 * Gram matrix D^T D + R^T R is kept to 1e-13 of its largest entry. */
static void test_qr_append_subnormal(void **state)
{
    const int n = 4, p = 3;
    int present[4] = {1, 0, 0, 1}, i, j, copy[4];
    double R[16] = {0}, D[12], G0[16], G1[16], scale = 0.0;
    (void)state;
    R[0] = 2.0, R[1] = 0.5, R[15] = 1.0;
    for (j = 0; j < n; j++)
        for (i = 0; i < p; i++) D[j * p + i] = (i + j) % 2 ? 3e-316 * (i + 1) : (j == 3 ? 0.7 : 0.0);
    memcpy(copy, present, sizeof copy);
    gram(R, present, n, D, p, G0);
    dense_qr_append(R, n, present, D, p);
    gram(R, present, n, NULL, 0, G1);
    for (i = 0; i < n * n; i++) {
        assert_true(isfinite(R[i]));
        scale = fmax(scale, fabs(G0[i]));
    }
    for (i = 0; i < n * n; i++) assert_true(fabs(G1[i] - G0[i]) <= 1e-13 * scale);
    (void)copy;
}

/* dense_qr_append_simd with avx = 1 (the AVX reflections over more than 6
 * rows, four columns a pass) against avx = 0 (dense_qr_append's scalar
 * loops): the same R, D, present and row count, bit for bit (memcmp), on
 * random sizes up to the node update's (n <= 37 columns, p <= 18 rows), so
 * that every column count modulo 4 and every reflection length 1 .. 17
 * occur. Skipped (nothing asserted) on a processor without AVX or a build
 * without the kernels' compiler support; reported. */
static void test_qr_append_avx(void **state)
{
    uint64_t s = 1234;
    int trial, ran = 0;
    (void)state;
#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    if (!__builtin_cpu_supports("avx")) {
        print_message("qr_append_avx: SKIPPED: no AVX on this processor\n");
        return;
    }
#else
    print_message("qr_append_avx: SKIPPED: no AVX kernels in this build\n");
    return;
#endif
    for (trial = 0; trial < 600; trial++) {
        int n = 1 + (int)test_uniform(&s, 0, 36.99), p = 1 + (int)test_uniform(&s, 0, 17.99), i, j, r0, r1;
        int pr0[37], pr1[37];
        double R0[37 * 37], R1[37 * 37], D0[18 * 37], D1[18 * 37];
        for (j = 0; j < n; j++) pr0[j] = trial % 3 != 0 && test_uniform(&s, 0, 1) < 0.5;
        fill(&s, R0, n * n);
        for (j = 0; j < n; j++)
            for (i = 0; i < n; i++)
                if (!pr0[j] || i < j) R0[j * n + i] = 0.0;
        fill(&s, D0, p * n);
        memcpy(R1, R0, sizeof(double) * (size_t)(n * n));
        memcpy(D1, D0, sizeof(double) * (size_t)(p * n));
        memcpy(pr1, pr0, sizeof(int) * (size_t)n);
        r0 = dense_qr_append_simd(R0, n, pr0, D0, p, 0);
        r1 = dense_qr_append_simd(R1, n, pr1, D1, p, 1);
        assert_int_equal(r0, r1);
        assert_memory_equal(pr0, pr1, sizeof(int) * (size_t)n);
        assert_memory_equal(R0, R1, sizeof(double) * (size_t)(n * n));
        assert_memory_equal(D0, D1, sizeof(double) * (size_t)(p * n));
        ran++;
    }
    assert_int_equal(ran, 600);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_products),
        cmocka_unit_test(test_symmetrize),
        cmocka_unit_test(test_spd_inverse_random),
        cmocka_unit_test(test_spd_inverse_scaled),
        cmocka_unit_test(test_spd_inverse_fallback_accuracy),
        cmocka_unit_test(test_spd_inverse_fallback_ill_conditioned),
        cmocka_unit_test(test_spd_inverse_failures),
        cmocka_unit_test(test_qr_append),
        cmocka_unit_test(test_qr_append_subnormal),
        cmocka_unit_test(test_qr_append_avx),
    };
    return cmocka_run_group_tests_name("dense", tests, NULL, NULL);
}
