/* dense.h -- small dense kernels (row-major): products, Cholesky with an LU
 * fallback, inverses of small SPD matrices. */
#ifndef AQS_DENSE_H
#define AQS_DENSE_H

/* C (m x n) = A (m x k) * B (k x n). C must not alias A or B. */
void dense_mul(const double *A, const double *B, double *C, int m, int k, int n);
/* C (m x n) = A^T * B with A (k x m), B (k x n). */
void dense_mul_tn(const double *A, const double *B, double *C, int m, int k, int n);
/* C (m x n) = A * B^T with A (m x k), B (n x k). */
void dense_mul_nt(const double *A, const double *B, double *C, int m, int k, int n);
/* y (m) = A (m x n) x. */
void dense_matvec(const double *A, const double *x, double *y, int m, int n);
/* y (n) = A^T x with A (m x n). */
void dense_tmatvec(const double *A, const double *x, double *y, int m, int n);
/* A <- (A + A^T) / 2, n x n. */
void dense_symmetrize(double *A, int n);

/* Inverse of a symmetric positive definite n x n matrix (n <= 6): Cholesky,
 * falling back to LU with partial pivoting when Cholesky meets a
 * non-positive pivot (MATH.md §3.8). Returns 0, or -1 if A is singular or
 * the result is not finite. out may alias A. */
int dense_spd_inverse(const double *A, double *out, int n);
/* A joint's D = S^T U (d x d; S 6 x d row-major, U d rows of 6: U_k = I S_k),
 * symmetrized, inverted into Dinv (d x d) by dense_spd_inverse: 0, or -1
 * when D is not numerically positive definite. */
int dense_joint_space_inverse(const double *S, const double *U, int d, double *Dinv);
/* A joint's accelerations from its articulated factors (S, U as above, Dinv
 * d x d): qdd = Dinv (u - U ac), then ac += S qdd. qdd may alias u. */
/* The same for a free joint (S = 1, d = 6): D^-1 U^T = 1, so qdd = Dinv u - ac
 * and then ac = Dinv u, without the product D^-1 (U^T ac), which loses
 * cond(D) u of ac (a free near point mass whose centre of mass is off its
 * frame's origin, in free fall: 4 rad/s^2 for 0). qdd may alias u. */
void dense_free_accel(const double *Dinv, const double *u, double *ac, double *qdd);
void dense_joint_accel(const double *S, const double *U, const double *Dinv, int d, const double *u, double *ac,
                       double *qdd);


/* Fixed-size 6x6 kernels (the hot path): the compiler unrolls them. */
static inline void dense_mul66(const double *A, const double *B, double *C)
{
    int i, j, l;
    for (i = 0; i < 6; i++) {
        double c[6] = {0, 0, 0, 0, 0, 0};
        for (l = 0; l < 6; l++) {
            double a = A[6 * i + l];
            for (j = 0; j < 6; j++) c[j] += a * B[6 * l + j];
        }
        for (j = 0; j < 6; j++) C[6 * i + j] = c[j];
    }
}

/* C = A B^T (through B^T, so that the inner loop runs over contiguous
 * entries and vectorizes) */
static inline void dense_mul66_nt(const double *A, const double *B, double *C)
{
    double Bt[36];
    int i, j;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) Bt[6 * j + i] = B[6 * i + j];
    dense_mul66(A, Bt, C);
}

/* y = A x */
static inline void dense_matvec6(const double *A, const double *x, double *y)
{
    int i, l;
    for (i = 0; i < 6; i++) {
        double s = 0.0;
        for (l = 0; l < 6; l++) s += A[6 * i + l] * x[l];
        y[i] = s;
    }
}

/* y = A^T x */
static inline void dense_tmatvec6(const double *A, const double *x, double *y)
{
    int i, l;
    double s[6] = {0, 0, 0, 0, 0, 0};
    for (l = 0; l < 6; l++)
        for (i = 0; i < 6; i++) s[i] += A[6 * l + i] * x[l];
    for (i = 0; i < 6; i++) y[i] = s[i];
}

/* Cholesky factor of a 6x6 SPD matrix: A = C C^T, C lower (row-major, the
 * upper part zeroed). Returns 0, or -1 at a non-positive or non-finite pivot. */
int dense_cholesky6(const double *A, double *C);
/* V = A^{-1} = C^{-T} C^{-1} from the Cholesky factor C (6x6); used by the
 * inverse-inertia DCA form (src/solve/dca_phi.c). */
void dense_cholesky6_inverse(const double *C, double *V);
/* Solve C w = b (forward) for n right-hand sides stored as the columns of the
 * 6 x n row-major b; w has the same layout. */
void dense_cholesky6_lower_solve(const double *C, const double *b, double *w, int n);
/* Solve C^T v = w (backward), same layout. */
void dense_cholesky6_upper_solve(const double *C, const double *w, double *v, int n);

/* QR update by rows. R (n x n, row-major) holds rows at the positions j
 * with present[j] != 0, each zero left of column j (an upper-triangular
 * matrix with rows missing; the missing rows are zero); D is p x n column-major (column j at D + j p).
 * On return R holds the R factor of [R; D] in the same form, so that the sum
 * of r_j r_j^T over the present rows grows by D^T D: a reflection over R's
 * row j (if present) and D's live rows zeroes D's column j; where row j is
 * missing and D's column is not zero, D's first live row becomes R's row j
 * (present[j] set) and leaves D. D is destroyed. Returns the present rows.
 * About 2 p n^2 flops, against 2 (n + p) n^2 for the stacked matrix. */
int dense_qr_append(double *R, int n, int *present, double *D, int p);
/* The same with avx != 0 where the processor has AVX (the tree's flag,
 * src/solve/dca.c): the reflections over more than 6 rows four columns at a
 * time with AVX, the same results bit for bit. avx = 0 is dense_qr_append. */
int dense_qr_append_simd(double *R, int n, int *present, double *D, int p, int avx);

#endif
