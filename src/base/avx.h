/* avx.h -- the AVX row kernels shared by the Householder reflections of
 * src/solve/dca.c (reflect_row) and src/base/dense.c (dense_qr_append_simd).
 * Internal, header only (static inline: inlined at each caller's fixed sizes).
 * Compiled for AVX by a function attribute whatever the build's flags, and
 * run only where the caller has checked the processor (the tree's flag, set
 * by dca_enable). "avx", not "fma": nothing is fused, so every lane rounds as
 * the scalar expression x[i] - f * a[i] does, and the results are bit for
 * bit the scalar loops' (make check-scalar). AQS_AVX is defined where they
 * exist. */
#ifndef AQS_AVX_H
#define AQS_AVX_H

#if defined(__SSE2__) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define AQS_AVX 1
#define AQS_TARGET_AVX __attribute__((target("avx")))
#define AQS_AVX_INLINE __attribute__((always_inline))

/* x[i] -= f a[i], i < m: four entries a register, then two, then one */
AQS_TARGET_AVX static inline AQS_AVX_INLINE void avx_axpy1(double *x, double f, const double *a, int m)
{
    const __m256d ff = _mm256_set1_pd(f);
    int i = 0;
    for (; i + 3 < m; i += 4)
        _mm256_storeu_pd(x + i, _mm256_sub_pd(_mm256_loadu_pd(x + i), _mm256_mul_pd(ff, _mm256_loadu_pd(a + i))));
    if (i + 1 < m) {
        _mm_storeu_pd(x + i, _mm_sub_pd(_mm_loadu_pd(x + i), _mm_mul_pd(_mm256_castpd256_pd128(ff), _mm_loadu_pd(a + i))));
        i += 2;
    }
    if (i < m) x[i] -= f * a[i];
}

/* x_k[i] -= f[k] a[i] for the four rows x_k, i < m: the four rows a register
 * column at a time, then two entries, then one */
AQS_TARGET_AVX static inline AQS_AVX_INLINE void avx_axpy4(double *x0, double *x1, double *x2, double *x3,
                                                           const double f[4], const double *a, int m)
{
    const __m256d f0 = _mm256_broadcast_sd(f), f1 = _mm256_broadcast_sd(f + 1), f2 = _mm256_broadcast_sd(f + 2),
                  f3 = _mm256_broadcast_sd(f + 3);
    int i = 0;
    for (; i + 3 < m; i += 4) {
        const __m256d va = _mm256_loadu_pd(a + i);
        _mm256_storeu_pd(x0 + i, _mm256_sub_pd(_mm256_loadu_pd(x0 + i), _mm256_mul_pd(f0, va)));
        _mm256_storeu_pd(x1 + i, _mm256_sub_pd(_mm256_loadu_pd(x1 + i), _mm256_mul_pd(f1, va)));
        _mm256_storeu_pd(x2 + i, _mm256_sub_pd(_mm256_loadu_pd(x2 + i), _mm256_mul_pd(f2, va)));
        _mm256_storeu_pd(x3 + i, _mm256_sub_pd(_mm256_loadu_pd(x3 + i), _mm256_mul_pd(f3, va)));
    }
    if (i + 1 < m) {
        const __m128d va = _mm_loadu_pd(a + i);
        _mm_storeu_pd(x0 + i, _mm_sub_pd(_mm_loadu_pd(x0 + i), _mm_mul_pd(_mm256_castpd256_pd128(f0), va)));
        _mm_storeu_pd(x1 + i, _mm_sub_pd(_mm_loadu_pd(x1 + i), _mm_mul_pd(_mm256_castpd256_pd128(f1), va)));
        _mm_storeu_pd(x2 + i, _mm_sub_pd(_mm_loadu_pd(x2 + i), _mm_mul_pd(_mm256_castpd256_pd128(f2), va)));
        _mm_storeu_pd(x3 + i, _mm_sub_pd(_mm_loadu_pd(x3 + i), _mm_mul_pd(_mm256_castpd256_pd128(f3), va)));
        i += 2;
    }
    if (i < m) {
        x0[i] -= f[0] * a[i];
        x1[i] -= f[1] * a[i];
        x2[i] -= f[2] * a[i];
        x3[i] -= f[3] * a[i];
    }
}
#endif

#endif
