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

#endif
