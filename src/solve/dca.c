/* dca.c -- Featherstone's divide-and-conquer articulated-body algorithm for
 * quasi-statics, in the symbols of MATH.md §3. Every handle carries its own
 * frame: the child body frame for the joint a cluster hangs from, the joint
 * frame (fixed in the parent body) for the joints it holds up (§3.6). */
#include "dca.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "avx.h"
#include "dense.h"
#include "frames.h"
#include "kintree.h"
#include "model.h"
#include "rounding.h"
#include "stale.h"

#if defined(__GNUC__)
#define DCA_INLINE __attribute__((always_inline)) /* reflect_row_body at fixed sizes */
#else
#define DCA_INLINE
#endif
#if defined(__SSE2__)
#include <emmintrin.h>
#define DCA_SSE2 1
#endif
/* AVX (four doubles a register) for the hottest kernel, reflect_row's row updates:
 * compiled for AVX by a function attribute whatever the build's flags, and run only
 * where the processor has it (dca_avx_wanted, once per linkage in dca_enable). "avx",
 * not "avx2" or "fma": no fused multiply-add, every lane rounds as the scalar code. */
#if defined(DCA_SSE2) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define DCA_AVX 1
#define DCA_TARGET_AVX __attribute__((target("avx")))
#endif

static int mp_inverse_factor(const double *mp, double *Y);
static void xform_cols(const pose *P, const double *Z, double *out, int32_t ld, int avx);

static void dca_leaf_phi(aqs_linkage *L, int32_t n);

/* Whether the AVX kernels run: the processor and the operating system support AVX
 * (__builtin_cpu_supports: CPUID and XCR0), and the environment variable AQS_SIMD is not
 * "sse2" (which forces the SSE2 kernels: make check-scalar compares the two paths and the
 * scalar build; docs/testing.md). Both paths give the same results, bit for bit. */
static int dca_avx_wanted(void)
{
#ifdef DCA_AVX
    const char *e = getenv("AQS_SIMD");
    if (e && strcmp(e, "sse2") == 0) return 0;
    return __builtin_cpu_supports("avx") != 0;
#else
    return 0;
#endif
}

aqs_status dca_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    int32_t n;
    if (t->data) return AQS_OK;
    /* The DCA multiplies masses together (the two-body rule's m_A m_B / m,
     * the mass properties' factors): below 1e-150 such a product underflows,
     * and with subnormals flushed (src/base/fpenv.c) becomes 0, so a pendulum
     * of 1e-155 kg came out at rest, certified; above 1e150 it overflows.
     * The articulated-body solver takes any positive mass. A massless body
     * (welded to a massive one) adds nothing and is fine. */
    for (n = 0; n < L->nbodies; n++) {
        const double m = L->bodies[n].mass;
        if (m != 0.0 && !(m >= DCA_MASS_MIN && m <= DCA_MASS_MAX))
            return lk_fail(L, AQS_EINVAL,
                           "%s: body %d has mass %g, outside [1e-150, 1e150], where the DCA (a tolerance, a cap "
                           "or AQS_EXACT_DCA) computes: products of masses would underflow or overflow; "
                           "the articulated-body solver (the default exact solver) takes it",
                           fn, (int)n, m);
    }
    /* src/solve/rounding.c: per handle, then the back-substitution's sums by handle (rounding_backsub_products) */
    if (!t->rnd_x && !(t->rnd_x = lk_calloc_in(L, LK_MEM_DCA, (size_t)t->nhandles + 7 + 7 * (size_t)t->max_handles,
                                                sizeof(double))))
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for the rounding estimate", fn);
    if (!t->rnd_node && !(t->rnd_node = lk_calloc_in(L, LK_MEM_DCA, RND_NODE_LEVELS * (size_t)t->nnodes + 1, sizeof(double))))
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for the rounding estimate", fn);
    { /* the adaptive solver's per-node arrays (src/solve/adaptive.c), not held by a
         linkage solved only by the articulated-body algorithm */
        solve_state *s = &L->s;
        size_t nn = (size_t)t->nnodes + 1;
        if (!s->heap_key) s->heap_key = lk_calloc_in(L, LK_MEM_DCA, nn, sizeof(double));
        if (!s->heap_item) s->heap_item = lk_calloc_in(L, LK_MEM_DCA, nn, sizeof(int32_t));
        if (!s->pred) s->pred = lk_calloc_in(L, LK_MEM_DCA, nn, 1);
        if (!s->tstale) s->tstale = lk_calloc_in(L, LK_MEM_DCA, nn, 1);
        if (!s->aval) s->aval = lk_calloc_in(L, LK_MEM_DCA, nn, sizeof(double));
        if (!s->plist) s->plist = lk_calloc_in(L, LK_MEM_DCA, nn, sizeof(int32_t));
        if (!s->heap_key || !s->heap_item || !s->pred || !s->tstale || !s->aval || !s->plist)
            return lk_fail(L, AQS_ENOMEM, "%s: out of memory for the adaptive solver", fn);
    }
    if (frames_poses_alloc(L) != AQS_OK ||
        (L->dca_form == AQS_DCA_FORM_PHI && model_inverse_alloc(L) != AQS_OK)) /* dca_phi_leaf's Phi */
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for the assembly tree's poses or the inverse inertias", fn);
    t->avx = dca_avx_wanted();
    t->data = lk_calloc_in(L, LK_MEM_DCA, (size_t)t->ndata + 1, sizeof(double));
    if (!t->data)
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for %lld DCA coefficients", fn,
                       (long long)t->ndata);
    for (n = 0; n < t->nnodes; n++)
        if (t->nodes[n].joint < 0) {
            if (L->dca_form == AQS_DCA_FORM_PHI) dca_phi_leaf(L, n);
            else dca_leaf_phi(L, n);
        }
    /* every b and internal node from scratch, loads and gravity included */
    stale_tree(L);
    return AQS_OK;
}

/* Leaf set-up of the square-root form: mass properties, rank 0 (constant
 * after finalize; the world leaf is grounded). */
static void dca_leaf_phi(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *nd = &t->nodes[n];
    nd->rank = 0; /* a rigid group: Phi = G I^-1 G^T exactly, no Lambda */
    nd->jw = 0;
    nd->grounded = nd->comp == L->m.ncomp;
    if (nd->grounded) memset(t->data + nd_ic(nd), 0, 13 * sizeof(double));
    else model_comp_mass(L, nd->comp, t->data + nd_ic(nd));
}

void dca_leaf_b(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *nd = &t->nodes[n];
    double *b = t->data + nd->bv;
    const pose *P = t->poses + nd->poses;
    double acc[6], X[36];
    int32_t i;
    if (nd->comp == L->m.ncomp) {
        /* Root trick (MATH.md §3.7): the world accelerates by a0 = -g, here
         * in the world leaf's frame (tree.world_frame, frames.h) */
        const double mg[3] = {-L->gravity[0], -L->gravity[1], -L->gravity[2]};
        acc[0] = acc[1] = acc[2] = 0.0;
        mat3_tvec(t->world_frame.R, mg, acc + 3);
    } else {
        const double *f = L->m.comp_force + 6 * nd->comp;
        double Y[36], w[6];
        /* acc = I^-1 f = Y (Y^T f), through the centre of mass (the square-root
         * form's mass properties); the inverse-inertia form keeps finalize's */
        if (L->dca_form == AQS_DCA_FORM_PHI || mp_inverse_factor(t->data + nd_ic(nd), Y) != 0) {
            model_inverse_apply(L, nd->comp, f, acc);
        } else {
            dense_tmatvec6(Y, f, w);
            dense_matvec6(Y, w, acc);
        }
    }
    for (i = 0; i < nd->nh; i++) {
        spatial_from_parent(&P[i], X);
        dense_matvec(X, acc, b + 6 * i, 6, 6);
    }
}


/* ---- Mass properties: a node's composite inertia is kept as mass, centre of
 * mass and rotational inertia about it (mp[0] = m, mp[1..3] = c, mp[4..12] =
 * Ic, 3x3 row-major; node frame), combined by the two-body parallel-axis rule
 * (only sums of positive terms), and inverted through the centre of mass:
 * I^-1 = E^T diag(Ic^-1, 1/m) E exactly, so neither a lever arm nor a tiny
 * Ic costs digits (a 6x6 Cholesky of I in a far frame does). */

/* The centre-of-mass part of the factor below: Jc (3x3, Ic^-1 = Jc Jc^T,
 * Jc = Lc^-T, Ic = Lc Lc^T) and sm = 1/sqrt(m). -1 if Ic is not positive
 * definite (or a mass property is not finite). */
static int mp_factor(const double *mp, double Jc[9], double *sm)
{
    const double m = mp[0], *Ic = mp + 4;
    double l00, l10, l11, l20, l21, l22, Li[9];
    int i, j;
#ifdef DCA_SSE2
    { /* the same test: x * 0 is NaN only for x not finite, and a sum of zeros is not NaN */
        const __m128d z = _mm_setzero_pd();
        __m128d b = _mm_mul_pd(_mm_load_sd(mp + 12), z);
        for (i = 0; i < 12; i += 2) b = _mm_add_pd(b, _mm_mul_pd(_mm_loadu_pd(mp + i), z));
        if (_mm_movemask_pd(_mm_cmpunord_pd(b, b)) != 0) return -1; /* a part 1e300 m out: its inertia overflowed */
    }
#else
    for (i = 0; i < 13; i++) /* a part 1e300 m out: its inertia overflowed */
        if (!isfinite(mp[i])) return -1;
#endif
    if (!(m > 0.0)) return -1;
    l00 = Ic[0];
    if (!(l00 > 0.0)) return -1;
    l00 = sqrt(l00);
    l10 = Ic[3] / l00;
    l11 = Ic[4] - l10 * l10;
    if (!(l11 > 0.0)) return -1;
    l11 = sqrt(l11);
    l20 = Ic[6] / l00;
    l21 = (Ic[7] - l20 * l10) / l11;
    l22 = Ic[8] - l20 * l20 - l21 * l21;
    if (!(l22 > 0.0) || !isfinite(l22)) return -1;
    l22 = sqrt(l22);
    /* Li = Lc^-1 (lower) */
    memset(Li, 0, sizeof Li);
    Li[0] = 1.0 / l00;
    Li[4] = 1.0 / l11;
    Li[8] = 1.0 / l22;
    Li[3] = -l10 * Li[0] / l11;
    Li[7] = -l21 * Li[4] / l22;
    Li[6] = -(l20 * Li[0] + l21 * Li[3]) / l22;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) Jc[3 * i + j] = Li[3 * j + i];
    *sm = 1.0 / sqrt(m);
    return 0;
}

/* N = -S^T Jc (S = skew(c)) as mp_y sums it, k = 0, 1, 2 from 0.0, less
 * the products with S's zero diagonal (which subtract an exact zero from a
 * sum that is never -0: the same N, bit for bit). */
static inline void mp_n(const double Jc[9], const double *c, double N[9])
{
    int j;
    for (j = 0; j < 3; j++) {
        double s0 = 0.0, s1 = 0.0, s2 = 0.0;
        s0 -= c[2] * Jc[3 + j];  /* S[3] = c2 */
        s0 -= -c[1] * Jc[6 + j]; /* S[6] = -c1 */
        s1 -= -c[2] * Jc[j];     /* S[1] = -c2 */
        s1 -= c[0] * Jc[6 + j];  /* S[7] = c0 */
        s2 -= c[1] * Jc[j];      /* S[2] = c1 */
        s2 -= -c[0] * Jc[3 + j]; /* S[5] = -c0 */
        N[j] = s0;
        N[3 + j] = s1;
        N[6 + j] = s2;
    }
}

/* Y (6x6) = [Jc 0; -S^T Jc  sm 1], S = skew(c): I^-1 = Y Y^T for the mass
 * properties of mp_factor with their centre of mass at c. */
static void mp_y(const double Jc[9], double sm, const double *c, double *Y)
{
    double N[9];
    int i, j;
    mp_n(Jc, c, N);
    memset(Y, 0, 36 * sizeof(double));
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) {
            Y[6 * i + j] = Jc[3 * i + j];
            Y[6 * (3 + i) + j] = N[3 * i + j]; /* -S^T Jc */
        }
    for (i = 0; i < 3; i++) Y[6 * (3 + i) + 3 + i] = sm;
}

/* The squared Frobenius norm of mp_y's Y, summed in the same order (row by
 * row) with the same entries: Y's zero entries, left out, add exact zeros
 * (the sum starts at +0.0 and holds squares), so the sum is bit for bit that
 * over the 36 entries of mp_y's Y. */
static double mp_y_norm2(const double Jc[9], double sm, const double *c)
{
    double w = 0.0, N[9];
    int i, j;
    mp_n(Jc, c, N);
    for (i = 0; i < 9; i++) w += Jc[i] * Jc[i];
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) w += N[3 * i + j] * N[3 * i + j];
        w += sm * sm;
    }
    return w;
}

/* Y (6x6) with I^-1 = Y Y^T: Y = [Jc 0; -S^T Jc  1/sqrt(m)], S = skew(c),
 * Ic^-1 = Jc Jc^T (Jc = Lc^-T, Ic = Lc Lc^T). -1 if Ic is not positive definite. */
static int mp_inverse_factor(const double *mp, double *Y)
{
    double Jc[9], sm;
    if (mp_factor(mp, Jc, &sm) != 0) return -1;
    mp_y(Jc, sm, mp + 1, Y);
    return 0;
}

/* ---- Accurate Phi: rigid part from the composite inertia, internal part as
 * a square-root factor (docs/math.md, "Accurate Phi").
 *
 * Phi of a node = G I^-1 G^T + Lambda Lambda^T, G the handles' motion
 * transforms from the node frame, I the subassembly's composite inertia
 * (a sum, formed without cancellation) and Lambda (6nh x rank) the mobility
 * its internal joints add. Joining A and B at joint k: the two bodies'
 * motions split into the common rigid motion (I_C = I_A + I_B) and the
 * relative one, factored by Lm Lm^T = I_A^-1 + I_B^-1; the rows of the
 * relative acceleration across k in the directions the joint does not free
 * (Tc^T, Tc spanning S's orthogonal complement) are reduced by Householder
 * reflections from the right, and what the outer rows keep beyond them is
 * Lambda_C (compressed to 6nh columns the same way). Nothing is subtracted:
 * Phi_C is a Gram matrix of reflected rows, so a rigid direction's tiny
 * mobility (1/I of a long chain) keeps its relative accuracy, and a point
 * mass's 1/k rotational mobility is removed by an orthogonal projection,
 * not by a difference of 1/k-sized terms. */

/* The kernels of reflect_row: each row's dot product summed in column order
 * from 0.0, each entry updated as a[j] -= s v[j], exactly as the scalar loops
 * would; with SSE2 two rows' sums share a register (dot2) and two entries of
 * a row are updated at once (axpy1, axpy4), lane by lane the same IEEE
 * operations, so the results are bit for bit those of the scalar code
 * (docs/bench.md, "A cheaper square-root node"). */
static inline void dot2(const double *a, const double *b, const double *v, int32_t m, double *s, double *t)
{
    double x = 0.0, y = 0.0;
    int32_t j;
    for (j = 0; j < m; j++) {
        x += a[j] * v[j];
        y += b[j] * v[j];
    }
    *s = x;
    *t = y;
}

#ifdef DCA_SSE2
#define DCA_VDUP 64 /* reflect_row's vectors up to this length are kept broadcast */
/* dot2 with vd[j] = (v[j], v[j]) */
static inline void dot2_dup(const double *a, const double *b, const __m128d *vd, int32_t m, double *s, double *t)
{
    __m128d acc = _mm_setzero_pd();
    int32_t j;
    for (j = 0; j < m; j++) acc = _mm_add_pd(acc, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(a + j), b + j), vd[j]));
    _mm_storel_pd(s, acc);
    _mm_storeh_pd(t, acc);
}
#define DOT2(a, b, s, t) (m <= DCA_VDUP ? dot2_dup(a, b, vd, m, s, t) : dot2(a, b, v, m, s, t))
#else
#define DOT2(a, b, s, t) dot2(a, b, v, m, s, t)
#endif

static inline void axpy1(double *a, double s, const double *v, int32_t m)
{
    int32_t j = 0;
#ifdef DCA_SSE2
    const __m128d ss = _mm_set1_pd(s);
    for (; j + 1 < m; j += 2)
        _mm_storeu_pd(a + j, _mm_sub_pd(_mm_loadu_pd(a + j), _mm_mul_pd(ss, _mm_loadu_pd(v + j))));
#endif
    for (; j < m; j++) a[j] -= s * v[j];
}

static inline void axpy4(double *a, double *b, double *g, double *h, double s, double t, double u, double z,
                         const double *v, int32_t m)
{
    int32_t j = 0;
#ifdef DCA_SSE2
    const __m128d ss = _mm_set1_pd(s), tt = _mm_set1_pd(t), uu = _mm_set1_pd(u), zz = _mm_set1_pd(z);
    for (; j + 1 < m; j += 2) {
        const __m128d vv = _mm_loadu_pd(v + j);
        _mm_storeu_pd(a + j, _mm_sub_pd(_mm_loadu_pd(a + j), _mm_mul_pd(ss, vv)));
        _mm_storeu_pd(b + j, _mm_sub_pd(_mm_loadu_pd(b + j), _mm_mul_pd(tt, vv)));
        _mm_storeu_pd(g + j, _mm_sub_pd(_mm_loadu_pd(g + j), _mm_mul_pd(uu, vv)));
        _mm_storeu_pd(h + j, _mm_sub_pd(_mm_loadu_pd(h + j), _mm_mul_pd(zz, vv)));
    }
#endif
    for (; j < m; j++) {
        a[j] -= s * v[j];
        b[j] -= t * v[j];
        g[j] -= u * v[j];
        h[j] -= z * v[j];
    }
}

#ifdef DCA_AVX
/* reflect_row_body's row updates (rows i .. nrows-1, f = 2 / v^T v) with AVX,
 * each row's arithmetic that of the scalar loops: four rows' sums in the four
 * lanes of one register, each summed in column order from 0.0 (a 4 x 4 block of
 * the rows is transposed so that lane k meets row k's entries column by column),
 * then multiplied by f and tested for zero as there; four entries of a row
 * updated at once, a[j] - s v[j] in each lane. The two-row and one-row tails as
 * in reflect_row_body (the one-row sum tested before its product by f). */
DCA_TARGET_AVX static inline DCA_INLINE void reflect_apply_avx_body(double *A, int32_t ld, int32_t i, int32_t nrows,
                                                                     int32_t p, const double *v, int32_t m, double f)
{
    __m256d vb[DCA_VDUP];
    const __m256d ff = _mm256_set1_pd(f), zero = _mm256_setzero_pd();
    int32_t j;
    for (j = 0; j < m; j++) vb[j] = _mm256_set1_pd(v[j]);
    for (; i + 3 < nrows; i += 4) {
        double *a = A + (int64_t)ld * i + p, *b = a + ld, *g = b + ld, *h = g + ld;
        __m256d acc = zero;
        double s[4];
        for (j = 0; j + 3 < m; j += 4) {
            const __m256d ra = _mm256_loadu_pd(a + j), rb = _mm256_loadu_pd(b + j), rg = _mm256_loadu_pd(g + j),
                          rh = _mm256_loadu_pd(h + j);
            const __m256d t0 = _mm256_unpacklo_pd(ra, rb), t1 = _mm256_unpackhi_pd(ra, rb); /* (a0 b0 a2 b2), (a1 b1 a3 b3) */
            const __m256d t2 = _mm256_unpacklo_pd(rg, rh), t3 = _mm256_unpackhi_pd(rg, rh);
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_permute2f128_pd(t0, t2, 0x20), vb[j])); /* (a0 b0 g0 h0) */
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_permute2f128_pd(t1, t3, 0x20), vb[j + 1]));
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_permute2f128_pd(t0, t2, 0x31), vb[j + 2]));
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_permute2f128_pd(t1, t3, 0x31), vb[j + 3]));
        }
        for (; j < m; j++) {
            const __m128d lo = _mm_loadh_pd(_mm_load_sd(a + j), b + j), hi = _mm_loadh_pd(_mm_load_sd(g + j), h + j);
            acc = _mm256_add_pd(acc, _mm256_mul_pd(_mm256_insertf128_pd(_mm256_castpd128_pd256(lo), hi, 1), vb[j]));
        }
        acc = _mm256_mul_pd(acc, ff);
        _mm256_storeu_pd(s, acc);
        if (_mm256_movemask_pd(_mm256_cmp_pd(acc, zero, _CMP_EQ_OQ)) == 0) {
            avx_axpy4(a, b, g, h, s, v, m);
        } else {
            if (s[0] != 0.0) avx_axpy1(a, s[0], v, m);
            if (s[1] != 0.0) avx_axpy1(b, s[1], v, m);
            if (s[2] != 0.0) avx_axpy1(g, s[2], v, m);
            if (s[3] != 0.0) avx_axpy1(h, s[3], v, m);
        }
    }
    for (; i + 1 < nrows; i += 2) {
        double *a = A + (int64_t)ld * i + p, *b = a + ld, s, t;
        __m128d acc = _mm_setzero_pd();
        for (j = 0; j < m; j++)
            acc = _mm_add_pd(acc, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(a + j), b + j), _mm256_castpd256_pd128(vb[j])));
        acc = _mm_mul_pd(acc, _mm256_castpd256_pd128(ff));
        _mm_storel_pd(&s, acc);
        _mm_storeh_pd(&t, acc);
        if (s != 0.0) avx_axpy1(a, s, v, m);
        if (t != 0.0) avx_axpy1(b, t, v, m);
    }
    if (i < nrows) {
        double *a = A + (int64_t)ld * i + p, s = 0.0;
        for (j = 0; j < m; j++) s += a[j] * v[j];
        if (s == 0.0) return;
        s *= f;
        avx_axpy1(a, s, v, m);
    }
}

/* the body at the molecule's lengths m as constants (its loops unrolled) */
DCA_TARGET_AVX static void reflect_apply_avx(double *A, int32_t ld, int32_t i, int32_t nrows, int32_t p,
                                             const double *v, int32_t m, double f)
{
    switch (m) {
    case 4: reflect_apply_avx_body(A, ld, i, nrows, p, v, 4, f); break;
    case 5: reflect_apply_avx_body(A, ld, i, nrows, p, v, 5, f); break;
    case 6: reflect_apply_avx_body(A, ld, i, nrows, p, v, 6, f); break;
    case 7: reflect_apply_avx_body(A, ld, i, nrows, p, v, 7, f); break;
    case 8: reflect_apply_avx_body(A, ld, i, nrows, p, v, 8, f); break;
    case 9: reflect_apply_avx_body(A, ld, i, nrows, p, v, 9, f); break;
    case 10: reflect_apply_avx_body(A, ld, i, nrows, p, v, 10, f); break;
    default: reflect_apply_avx_body(A, ld, i, nrows, p, v, m, f); break;
    }
}
#endif

/* Reflect row r of the row-major A (ld columns) so that its entries in
 * columns p+1 .. ncol-1 vanish (Householder from the right, LAPACK-scaled),
 * applying the reflection to rows r0 .. nrows-1. v: ncol scratch doubles. */
static inline DCA_INLINE void reflect_row_body(double *A, int32_t ld, int32_t r0, int32_t nrows, int32_t r, int32_t p,
                        int32_t ncol, double *v, int avx)
{
    const double *x = A + (int64_t)ld * r + p;
    int32_t m = ncol - p, i, j;
    double scale = 0.0, ss = 0.0, alpha, f;
#ifdef DCA_SSE2
    __m128d vd[DCA_VDUP];
#endif
    /* the copy v = x and its sum of squares (in column order from 0.0, as
     * below) in the same pass as the scale */
    v[0] = x[0];
    ss = x[0] * x[0];
    j = 1;
#ifdef DCA_SSE2
    { /* two entries at a time: the squares added in column order, the largest
         magnitude by maxpd (order-free; a NaN entry is skipped, as below) */
        const __m128d ab = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
        __m128d mx = _mm_setzero_pd();
        for (; j + 1 < m; j += 2) {
            const __m128d y = _mm_loadu_pd(x + j), y2 = _mm_mul_pd(y, y);
            _mm_storeu_pd(v + j, y);
            ss += _mm_cvtsd_f64(y2);
            ss += _mm_cvtsd_f64(_mm_unpackhi_pd(y2, y2));
            mx = _mm_max_pd(_mm_and_pd(y, ab), mx);
        }
        scale = _mm_cvtsd_f64(_mm_max_sd(_mm_unpackhi_pd(mx, mx), mx));
    }
#endif
    for (; j < m; j++) {
        const double y = x[j];
        v[j] = y;
        ss += y * y;
        if (fabs(y) > scale) scale = fabs(y);
    }
    if (scale == 0.0) return; /* nothing right of the pivot */
    if (fabs(x[0]) > scale) scale = fabs(x[0]);
    /* v = x / scale - alpha e1 (the direction is all that H = 1 - 2 v v^T / v^T v
     * needs): every quantity is O(1), so neither tiny (subnormal) nor huge
     * entries underflow or overflow in alpha v0. A power-of-two scale changes
     * every later quantity by an exact power of two, and the reflected rows not
     * at all, so between 2^-100 and 2^100, where nothing can underflow or
     * overflow, it is left out: the same results, bit for bit (v and ss are
     * then the ones computed above). */
    if (!(scale >= 0x1p-100 && scale <= 0x1p100)) {
        int e;
        ss = 0.0;
        frexp(scale, &e);
        scale = ldexp(1.0, e); /* a power of two: x / scale is exact */
        for (j = 0; j < m; j++) {
            v[j] = x[j] / scale;
            ss += v[j] * v[j];
        }
    }
    alpha = sqrt(ss);
    if (v[0] > 0.0) alpha = -alpha;
    v[0] -= alpha; /* |v0| = |x0| / scale + ||x|| / scale: no cancellation */
    f = -1.0 / (alpha * v[0]); /* 2 / v^T v, since v^T v = -2 alpha v0 */
#ifdef DCA_AVX
    if (avx && m <= DCA_VDUP) {
        reflect_apply_avx(A, ld, r0, nrows, p, v, m, f);
        return;
    }
#else
    (void)avx;
#endif
#ifdef DCA_SSE2
    if (m <= DCA_VDUP)
        for (j = 0; j < m; j++) vd[j] = _mm_set1_pd(v[j]);
#endif
    i = r0;
#ifdef DCA_SSE2
    if (m <= DCA_VDUP) { /* the loop below with its sums, products by f and zero tests in registers */
        const __m128d ff = _mm_set1_pd(f), zero = _mm_setzero_pd();
        for (; i + 3 < nrows; i += 4) {
            double *a = A + (int64_t)ld * i + p, *b = a + ld, *g = b + ld, *h = g + ld;
            __m128d st = zero, uz = zero;
            for (j = 0; j < m; j++) {
                st = _mm_add_pd(st, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(a + j), b + j), vd[j]));
                uz = _mm_add_pd(uz, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(g + j), h + j), vd[j]));
            }
            st = _mm_mul_pd(st, ff);
            uz = _mm_mul_pd(uz, ff);
            if ((_mm_movemask_pd(_mm_cmpeq_pd(st, zero)) | _mm_movemask_pd(_mm_cmpeq_pd(uz, zero))) == 0) {
                const __m128d sa = _mm_unpacklo_pd(st, st), tt = _mm_unpackhi_pd(st, st);
                const __m128d uu = _mm_unpacklo_pd(uz, uz), zz = _mm_unpackhi_pd(uz, uz);
                for (j = 0; j + 1 < m; j += 2) {
                    const __m128d vv = _mm_loadu_pd(v + j);
                    _mm_storeu_pd(a + j, _mm_sub_pd(_mm_loadu_pd(a + j), _mm_mul_pd(sa, vv)));
                    _mm_storeu_pd(b + j, _mm_sub_pd(_mm_loadu_pd(b + j), _mm_mul_pd(tt, vv)));
                    _mm_storeu_pd(g + j, _mm_sub_pd(_mm_loadu_pd(g + j), _mm_mul_pd(uu, vv)));
                    _mm_storeu_pd(h + j, _mm_sub_pd(_mm_loadu_pd(h + j), _mm_mul_pd(zz, vv)));
                }
                if (j < m) {
                    _mm_store_sd(a + j, _mm_sub_sd(_mm_load_sd(a + j), _mm_mul_sd(sa, vd[j])));
                    _mm_store_sd(b + j, _mm_sub_sd(_mm_load_sd(b + j), _mm_mul_sd(tt, vd[j])));
                    _mm_store_sd(g + j, _mm_sub_sd(_mm_load_sd(g + j), _mm_mul_sd(uu, vd[j])));
                    _mm_store_sd(h + j, _mm_sub_sd(_mm_load_sd(h + j), _mm_mul_sd(zz, vd[j])));
                }
            } else {
                double s, t, u, z;
                _mm_storel_pd(&s, st);
                _mm_storeh_pd(&t, st);
                _mm_storel_pd(&u, uz);
                _mm_storeh_pd(&z, uz);
                if (s != 0.0) axpy1(a, s, v, m);
                if (t != 0.0) axpy1(b, t, v, m);
                if (u != 0.0) axpy1(g, u, v, m);
                if (z != 0.0) axpy1(h, z, v, m);
            }
        }
    }
#endif
    for (; i + 3 < nrows; i += 4) { /* four rows at a time, each as alone */
        double *a = A + (int64_t)ld * i + p, *b = a + ld, *g = b + ld, *h = g + ld;
        double s, t, u, z;
        dot2(a, b, v, m, &s, &t); /* (with SSE2: only past DCA_VDUP columns) */
        dot2(g, h, v, m, &u, &z);
        s *= f;
        t *= f;
        u *= f;
        z *= f;
        if (s != 0.0 && t != 0.0 && u != 0.0 && z != 0.0) {
            axpy4(a, b, g, h, s, t, u, z, v, m);
        } else {
            if (s != 0.0) axpy1(a, s, v, m);
            if (t != 0.0) axpy1(b, t, v, m);
            if (u != 0.0) axpy1(g, u, v, m);
            if (z != 0.0) axpy1(h, z, v, m);
        }
    }
    for (; i + 1 < nrows; i += 2) { /* two rows at a time, each as alone */
        double *a = A + (int64_t)ld * i + p, *b = a + ld, s, t;
        DOT2(a, b, &s, &t);
        s *= f;
        t *= f;
        if (s != 0.0) axpy1(a, s, v, m);
        if (t != 0.0) axpy1(b, t, v, m);
    }
    if (i < nrows) {
        double *a = A + (int64_t)ld * i + p, s = 0.0;
        for (j = 0; j < m; j++) s += a[j] * v[j];
        if (s == 0.0) return;
        s *= f;
        axpy1(a, s, v, m);
    }
}

static void reflect_row(double *A, int32_t ld, int32_t r0, int32_t nrows, int32_t r, int32_t p, int32_t ncol,
                        double *v, int avx)
{
    reflect_row_body(A, ld, r0, nrows, r, p, ncol, v, avx);
}

#ifdef DCA_AVX
/* hybrid_phi's Z_A = Y_A (Lm^-1 Y_A)^T and Z_B = -Y_B (Lm^-1 Y_B)^T (see there)
 * with AVX: A's and B's entries side by side in each 128-bit half as in the SSE2
 * code, two columns of W = Lm^-1 Y (or two rows of Z) in the two halves; each
 * lane the SSE2 code's operations in its order. Rows 2 and 3 of Z share a
 * register, whose sums for the columns 3-5 run over 6 terms in row 3 and 3 in
 * row 2: row 2's lanes add +0.0 for the last three (a sum started at +0.0 is
 * never -0.0, so adding +0.0 changes nothing, not even a NaN). */
DCA_TARGET_AVX static void relative_z_avx(const double *YA, const double *YB, const double *Lm, double *ZA,
                                          double *ZB)
{
    __m128d Y2[36], W[36];
    __m256d Y4[18];
    int32_t i, j, r;
    for (i = 0; i < 36; i += 4) {
        const __m256d a = _mm256_loadu_pd(YA + i), b = _mm256_loadu_pd(YB + i);
        const __m256d lo = _mm256_unpacklo_pd(a, b), hi = _mm256_unpackhi_pd(a, b); /* (a0 b0 a2 b2), (a1 b1 a3 b3) */
        _mm256_storeu_pd((double *)(Y2 + i), _mm256_permute2f128_pd(lo, hi, 0x20));
        _mm256_storeu_pd((double *)(Y2 + i + 2), _mm256_permute2f128_pd(lo, hi, 0x31));
    }
    for (i = 0; i < 6; i++) { /* W's columns 0-1 in one register, 2 in an SSE2 one */
        const double *li = Lm + 6 * i;
        __m256d x0 = _mm256_loadu_pd((const double *)(Y2 + 6 * i));
        __m128d x1 = Y2[6 * i + 2];
        for (r = 0; r < i; r++) {
            const __m256d l = _mm256_broadcast_sd(li + r);
            x0 = _mm256_sub_pd(x0, _mm256_mul_pd(l, _mm256_loadu_pd((const double *)(W + 6 * r))));
            x1 = _mm_sub_pd(x1, _mm_mul_pd(_mm256_castpd256_pd128(l), W[6 * r + 2]));
        }
        {
            const __m256d p = _mm256_broadcast_sd(li + i);
            _mm256_storeu_pd((double *)(W + 6 * i), _mm256_div_pd(x0, p));
            W[6 * i + 2] = _mm_div_pd(x1, _mm256_castpd256_pd128(p));
        }
    }
    for (i = 3; i < 6; i++) { /* columns 3-4, 5 over rows 3-5 */
        const double *li = Lm + 6 * i;
        __m256d x0 = _mm256_loadu_pd((const double *)(Y2 + 6 * i + 3));
        __m128d x1 = Y2[6 * i + 5];
        for (r = 3; r < i; r++) {
            const __m256d l = _mm256_broadcast_sd(li + r);
            x0 = _mm256_sub_pd(x0, _mm256_mul_pd(l, _mm256_loadu_pd((const double *)(W + 6 * r + 3))));
            x1 = _mm_sub_pd(x1, _mm_mul_pd(_mm256_castpd256_pd128(l), W[6 * r + 5]));
        }
        {
            const __m256d p = _mm256_broadcast_sd(li + i);
            _mm256_storeu_pd((double *)(W + 6 * i + 3), _mm256_div_pd(x0, p));
            W[6 * i + 5] = _mm_div_pd(x1, _mm256_castpd256_pd128(p));
        }
    }
    for (i = 0; i < 3; i++) /* rows 2i, 2i+1 of Y side by side */
        for (r = 0; r < 6; r++)
            Y4[6 * i + r] = _mm256_insertf128_pd(_mm256_castpd128_pd256(Y2[12 * i + r]), Y2[12 * i + 6 + r], 1);
    {
        const __m256d neg = _mm256_set_pd(-0.0, 0.0, -0.0, 0.0);
        const __m256d hi = _mm256_castsi256_pd(_mm256_set_epi64x(-1, -1, 0, 0));
        for (i = 0; i < 3; i++)
            for (j = 0; j < 6; j++) {
                __m256d x = _mm256_setzero_pd();
                __m128d h;
                for (r = 0; r < 3; r++)
                    x = _mm256_add_pd(x, _mm256_mul_pd(Y4[6 * i + r], _mm256_broadcast_pd(W + 6 * j + r)));
                if (j >= 3 && i >= 1) {
                    for (r = 3; r < 6; r++) {
                        __m256d y = _mm256_mul_pd(Y4[6 * i + r], _mm256_broadcast_pd(W + 6 * j + r));
                        if (i == 1) y = _mm256_and_pd(y, hi); /* row 2: +0.0 */
                        x = _mm256_add_pd(x, y);
                    }
                }
                x = _mm256_xor_pd(x, neg);
                h = _mm256_extractf128_pd(x, 1);
                _mm_storel_pd(ZA + 12 * i + j, _mm256_castpd256_pd128(x));
                _mm_storeh_pd(ZB + 12 * i + j, _mm256_castpd256_pd128(x));
                _mm_storel_pd(ZA + 12 * i + 6 + j, h);
                _mm_storeh_pd(ZB + 12 * i + 6 + j, h);
            }
    }
}
#endif

/* Orthonormal basis of the orthogonal complement of the columns of S (6 x d,
 * row-major): columns q = 0 .. 5-d of Tc (row-major 6 x 6, column q). Gram-
 * Schmidt twice over S's columns, then over the unit vectors, taking the
 * largest remaining one each time. */
static int32_t complement(const double *S, int32_t d, double *Tc)
{
    double Q[36], v[6];
    int32_t nq = 0, i, j, k, pass;
    if (d == 1 && ((S[0] == 0.0 && S[1] == 0.0 && S[2] == 0.0) || (S[3] == 0.0 && S[4] == 0.0 && S[5] == 0.0))) {
        /* A revolute or prismatic axis a (unit): in its half, two unit vectors
         * orthogonal to a (Duff et al.'s branchless basis), and the other
         * half's three axes. */
        const int32_t h = S[0] == 0.0 && S[1] == 0.0 && S[2] == 0.0 ? 3 : 0, o = 3 - h;
        double a[3], nrm, sg, aa, bb;
        nrm = sqrt(S[h] * S[h] + S[h + 1] * S[h + 1] + S[h + 2] * S[h + 2]);
        if (nrm > 0.0) {
            for (i = 0; i < 3; i++) a[i] = S[h + i] / nrm;
            sg = a[2] >= 0.0 ? 1.0 : -1.0;
            aa = -1.0 / (sg + a[2]);
            bb = a[0] * a[1] * aa;
            memset(Tc, 0, 36 * sizeof(double));
            /* columns 0, 1: b1 = (1 + sg a0^2 aa, sg bb, -sg a0), b2 = (bb, sg + a1^2 aa, -a1) */
            Tc[6 * (h + 0) + 0] = 1.0 + sg * a[0] * a[0] * aa;
            Tc[6 * (h + 1) + 0] = sg * bb;
            Tc[6 * (h + 2) + 0] = -sg * a[0];
            Tc[6 * (h + 0) + 1] = bb;
            Tc[6 * (h + 1) + 1] = sg + a[1] * a[1] * aa;
            Tc[6 * (h + 2) + 1] = -a[1];
            for (i = 0; i < 3; i++) Tc[6 * (o + i) + 2 + i] = 1.0;
            return h;
        }
    }
    for (j = 0; j < d + 6 && nq < 6; j++) {
        double best = -1.0, nv;
        if (j < d) {
            for (i = 0; i < 6; i++) v[i] = S[i * d + j];
        } else {
            int32_t bi = 0;
            for (k = 0; k < 6; k++) { /* the unit vector least inside span(Q) */
                double w[6] = {0, 0, 0, 0, 0, 0}, s2 = 0.0;
                w[k] = 1.0;
                for (pass = 0; pass < 2; pass++)
                    for (i = 0; i < nq; i++) {
                        double dot = 0.0;
                        int32_t l;
                        for (l = 0; l < 6; l++) dot += Q[6 * i + l] * w[l];
                        for (l = 0; l < 6; l++) w[l] -= dot * Q[6 * i + l];
                    }
                for (i = 0; i < 6; i++) s2 += w[i] * w[i];
                if (s2 > best) {
                    best = s2;
                    bi = k;
                }
            }
            for (i = 0; i < 6; i++) v[i] = i == bi ? 1.0 : 0.0;
        }
        for (pass = 0; pass < 2; pass++)
            for (i = 0; i < nq; i++) {
                double dot = 0.0;
                for (k = 0; k < 6; k++) dot += Q[6 * i + k] * v[k];
                for (k = 0; k < 6; k++) v[k] -= dot * Q[6 * i + k];
            }
        nv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
        if (!(nv > 1e-8)) continue; /* a dependent column of S */
        for (k = 0; k < 6; k++) Q[6 * nq + k] = v[k] / nv;
        nq++;
    }
    for (j = 0; j < 6 - d; j++)
        for (i = 0; i < 6; i++) Tc[6 * i + j] = Q[6 * (d + j) + i];
    return -1;
}

#ifdef DCA_AVX
/* xform_cols with columns 0-3 in one AVX register and 4-5 in an SSE2 one,
 * each entry's expression as in its scalar loop */
DCA_TARGET_AVX static void xform_cols_avx(const pose *P, const double *Z, double *out, int32_t ld)
{
    const double *R = P->R, *p = P->p;
    const int moved = p[0] != 0.0 || p[1] != 0.0 || p[2] != 0.0;
    const __m256d r0 = _mm256_set1_pd(R[0]), r1 = _mm256_set1_pd(R[1]), r2 = _mm256_set1_pd(R[2]),
                  r3 = _mm256_set1_pd(R[3]), r4 = _mm256_set1_pd(R[4]), r5 = _mm256_set1_pd(R[5]),
                  r6 = _mm256_set1_pd(R[6]), r7 = _mm256_set1_pd(R[7]), r8 = _mm256_set1_pd(R[8]);
    const __m256d p0 = _mm256_set1_pd(p[0]), p1 = _mm256_set1_pd(p[1]), p2 = _mm256_set1_pd(p[2]);
    {
        const __m256d v0 = _mm256_loadu_pd(Z), v1 = _mm256_loadu_pd(Z + 6), v2 = _mm256_loadu_pd(Z + 12);
        __m256d t0 = _mm256_loadu_pd(Z + 18), t1 = _mm256_loadu_pd(Z + 24), t2 = _mm256_loadu_pd(Z + 30);
        if (moved) {
            t0 = _mm256_sub_pd(t0, _mm256_sub_pd(_mm256_mul_pd(p1, v2), _mm256_mul_pd(p2, v1)));
            t1 = _mm256_sub_pd(t1, _mm256_sub_pd(_mm256_mul_pd(p2, v0), _mm256_mul_pd(p0, v2)));
            t2 = _mm256_sub_pd(t2, _mm256_sub_pd(_mm256_mul_pd(p0, v1), _mm256_mul_pd(p1, v0)));
        }
        _mm256_storeu_pd(out, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r0, v0), _mm256_mul_pd(r3, v1)), _mm256_mul_pd(r6, v2)));
        _mm256_storeu_pd(out + ld, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r1, v0), _mm256_mul_pd(r4, v1)), _mm256_mul_pd(r7, v2)));
        _mm256_storeu_pd(out + (int64_t)2 * ld,
                         _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r2, v0), _mm256_mul_pd(r5, v1)), _mm256_mul_pd(r8, v2)));
        _mm256_storeu_pd(out + (int64_t)3 * ld,
                         _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r0, t0), _mm256_mul_pd(r3, t1)), _mm256_mul_pd(r6, t2)));
        _mm256_storeu_pd(out + (int64_t)4 * ld,
                         _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r1, t0), _mm256_mul_pd(r4, t1)), _mm256_mul_pd(r7, t2)));
        _mm256_storeu_pd(out + (int64_t)5 * ld,
                         _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(r2, t0), _mm256_mul_pd(r5, t1)), _mm256_mul_pd(r8, t2)));
    }
    {
#define DCA_LO(x) _mm256_castpd256_pd128(x)
        const __m128d v0 = _mm_loadu_pd(Z + 4), v1 = _mm_loadu_pd(Z + 10), v2 = _mm_loadu_pd(Z + 16);
        __m128d t0 = _mm_loadu_pd(Z + 22), t1 = _mm_loadu_pd(Z + 28), t2 = _mm_loadu_pd(Z + 34);
        if (moved) {
            t0 = _mm_sub_pd(t0, _mm_sub_pd(_mm_mul_pd(DCA_LO(p1), v2), _mm_mul_pd(DCA_LO(p2), v1)));
            t1 = _mm_sub_pd(t1, _mm_sub_pd(_mm_mul_pd(DCA_LO(p2), v0), _mm_mul_pd(DCA_LO(p0), v2)));
            t2 = _mm_sub_pd(t2, _mm_sub_pd(_mm_mul_pd(DCA_LO(p0), v1), _mm_mul_pd(DCA_LO(p1), v0)));
        }
        _mm_storeu_pd(out + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r0), v0), _mm_mul_pd(DCA_LO(r3), v1)),
                                          _mm_mul_pd(DCA_LO(r6), v2)));
        _mm_storeu_pd(out + ld + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r1), v0), _mm_mul_pd(DCA_LO(r4), v1)),
                                               _mm_mul_pd(DCA_LO(r7), v2)));
        _mm_storeu_pd(out + (int64_t)2 * ld + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r2), v0), _mm_mul_pd(DCA_LO(r5), v1)),
                                                           _mm_mul_pd(DCA_LO(r8), v2)));
        _mm_storeu_pd(out + (int64_t)3 * ld + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r0), t0), _mm_mul_pd(DCA_LO(r3), t1)),
                                                           _mm_mul_pd(DCA_LO(r6), t2)));
        _mm_storeu_pd(out + (int64_t)4 * ld + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r1), t0), _mm_mul_pd(DCA_LO(r4), t1)),
                                                           _mm_mul_pd(DCA_LO(r7), t2)));
        _mm_storeu_pd(out + (int64_t)5 * ld + 4, _mm_add_pd(_mm_add_pd(_mm_mul_pd(DCA_LO(r2), t0), _mm_mul_pd(DCA_LO(r5), t1)),
                                                           _mm_mul_pd(DCA_LO(r8), t2)));
#undef DCA_LO
    }
}
#endif

#ifdef DCA_AVX
/* out = -X_P Z for the n columns of Z (6 rows, row stride ldz; out's ld), four a
 * register (the last ones masked: nothing read or written past column n): each
 * lane spatial_xform_motion's arithmetic, then negated. */
DCA_TARGET_AVX static void xform_cols_neg_avx(const pose *P, const double *Z, int32_t ldz, int32_t n, double *out,
                                              int32_t ld)
{
    const double *R = P->R, *p = P->p;
    const int moved = p[0] != 0.0 || p[1] != 0.0 || p[2] != 0.0;
    const __m256d neg = _mm256_set1_pd(-0.0);
    int32_t j;
    for (j = 0; j < n; j += 4) {
        /* the last columns (n not a multiple of 4) through masked loads and stores */
        const __m256i mk = _mm256_castpd_si256(
            _mm256_cmp_pd(_mm256_set_pd(3.0, 2.0, 1.0, 0.0), _mm256_set1_pd((double)(n - j)), _CMP_LT_OQ));
        const __m256d v0 = _mm256_maskload_pd(Z + j, mk), v1 = _mm256_maskload_pd(Z + ldz + j, mk),
                      v2 = _mm256_maskload_pd(Z + (int64_t)2 * ldz + j, mk);
        __m256d t0 = _mm256_maskload_pd(Z + (int64_t)3 * ldz + j, mk),
                t1 = _mm256_maskload_pd(Z + (int64_t)4 * ldz + j, mk),
                t2 = _mm256_maskload_pd(Z + (int64_t)5 * ldz + j, mk);
        if (moved) {
            const __m256d p0 = _mm256_broadcast_sd(p), p1 = _mm256_broadcast_sd(p + 1), p2 = _mm256_broadcast_sd(p + 2);
            t0 = _mm256_sub_pd(t0, _mm256_sub_pd(_mm256_mul_pd(p1, v2), _mm256_mul_pd(p2, v1)));
            t1 = _mm256_sub_pd(t1, _mm256_sub_pd(_mm256_mul_pd(p2, v0), _mm256_mul_pd(p0, v2)));
            t2 = _mm256_sub_pd(t2, _mm256_sub_pd(_mm256_mul_pd(p0, v1), _mm256_mul_pd(p1, v0)));
        }
/* -(R[a] x + R[a+3] y + R[a+6] z), summed as spatial_xform_motion sums it */
#define DCA_XROW(a, x, y, z)                                                                                  \
    _mm256_xor_pd(neg, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_broadcast_sd(R + (a)), x),           \
                                                   _mm256_mul_pd(_mm256_broadcast_sd(R + (a) + 3), y)),      \
                                     _mm256_mul_pd(_mm256_broadcast_sd(R + (a) + 6), z)))
        _mm256_maskstore_pd(out + j, mk, DCA_XROW(0, v0, v1, v2));
        _mm256_maskstore_pd(out + ld + j, mk, DCA_XROW(1, v0, v1, v2));
        _mm256_maskstore_pd(out + (int64_t)2 * ld + j, mk, DCA_XROW(2, v0, v1, v2));
        _mm256_maskstore_pd(out + (int64_t)3 * ld + j, mk, DCA_XROW(0, t0, t1, t2));
        _mm256_maskstore_pd(out + (int64_t)4 * ld + j, mk, DCA_XROW(1, t0, t1, t2));
        _mm256_maskstore_pd(out + (int64_t)5 * ld + j, mk, DCA_XROW(2, t0, t1, t2));
#undef DCA_XROW
    }
}
#endif

#ifdef DCA_AVX
/* hybrid_phi's projection of the relative rows for an axis-aligned S (each new
 * row q one weighted row ix[6q], weight wt[6q]): x = 0.0 + w col, four columns
 * a register (the last ones masked), over the first w columns of the 6 rows of
 * rel (row stride ncol), in place. */
DCA_TARGET_AVX static void project_axis_avx(double *rel, int32_t ncol, int32_t w, const double *wt, const int32_t *ix)
{
    const __m256d zero = _mm256_setzero_pd();
    int32_t j, q, r;
    for (j = 0; j < w; j += 4) {
        const __m256i mk = _mm256_castpd_si256(
            _mm256_cmp_pd(_mm256_set_pd(3.0, 2.0, 1.0, 0.0), _mm256_set1_pd((double)(w - j)), _CMP_LT_OQ));
        __m256d col[6];
        for (r = 0; r < 6; r++) col[r] = _mm256_maskload_pd(rel + (int64_t)ncol * r + j, mk);
        for (q = 0; q < 6; q++)
            _mm256_maskstore_pd(rel + (int64_t)ncol * q + j, mk,
                                _mm256_add_pd(zero, _mm256_mul_pd(_mm256_broadcast_sd(wt + 6 * q), col[ix[6 * q]])));
    }
}
#endif

/* out (6 x 6) = X_P Z for the motion transform X = spatial_from_parent(P),
 * column by column: spatial_xform_motion's arithmetic, written out. */
static void xform_cols(const pose *P, const double *Z, double *out, int32_t ld, int avx)
{
    const double *R = P->R, *p = P->p;
    const int moved = p[0] != 0.0 || p[1] != 0.0 || p[2] != 0.0;
    int32_t j;
#ifdef DCA_AVX
    if (avx) {
        xform_cols_avx(P, Z, out, ld);
        return;
    }
#else
    (void)avx;
#endif
#ifdef DCA_SSE2
    /* two columns at a time: each entry's expression as in the scalar loop below */
    const __m128d r0 = _mm_set1_pd(R[0]), r1 = _mm_set1_pd(R[1]), r2 = _mm_set1_pd(R[2]), r3 = _mm_set1_pd(R[3]),
                  r4 = _mm_set1_pd(R[4]), r5 = _mm_set1_pd(R[5]), r6 = _mm_set1_pd(R[6]), r7 = _mm_set1_pd(R[7]),
                  r8 = _mm_set1_pd(R[8]);
    for (j = 0; j < 6; j += 2) {
        const __m128d v0 = _mm_loadu_pd(Z + j), v1 = _mm_loadu_pd(Z + 6 + j), v2 = _mm_loadu_pd(Z + 12 + j);
        __m128d t0 = _mm_loadu_pd(Z + 18 + j), t1 = _mm_loadu_pd(Z + 24 + j), t2 = _mm_loadu_pd(Z + 30 + j);
        if (moved) {
            const __m128d p0 = _mm_set1_pd(p[0]), p1 = _mm_set1_pd(p[1]), p2 = _mm_set1_pd(p[2]);
            t0 = _mm_sub_pd(t0, _mm_sub_pd(_mm_mul_pd(p1, v2), _mm_mul_pd(p2, v1)));
            t1 = _mm_sub_pd(t1, _mm_sub_pd(_mm_mul_pd(p2, v0), _mm_mul_pd(p0, v2)));
            t2 = _mm_sub_pd(t2, _mm_sub_pd(_mm_mul_pd(p0, v1), _mm_mul_pd(p1, v0)));
        }
        _mm_storeu_pd(out + j, _mm_add_pd(_mm_add_pd(_mm_mul_pd(r0, v0), _mm_mul_pd(r3, v1)), _mm_mul_pd(r6, v2)));
        _mm_storeu_pd(out + ld + j, _mm_add_pd(_mm_add_pd(_mm_mul_pd(r1, v0), _mm_mul_pd(r4, v1)), _mm_mul_pd(r7, v2)));
        _mm_storeu_pd(out + (int64_t)2 * ld + j,
                      _mm_add_pd(_mm_add_pd(_mm_mul_pd(r2, v0), _mm_mul_pd(r5, v1)), _mm_mul_pd(r8, v2)));
        _mm_storeu_pd(out + (int64_t)3 * ld + j,
                      _mm_add_pd(_mm_add_pd(_mm_mul_pd(r0, t0), _mm_mul_pd(r3, t1)), _mm_mul_pd(r6, t2)));
        _mm_storeu_pd(out + (int64_t)4 * ld + j,
                      _mm_add_pd(_mm_add_pd(_mm_mul_pd(r1, t0), _mm_mul_pd(r4, t1)), _mm_mul_pd(r7, t2)));
        _mm_storeu_pd(out + (int64_t)5 * ld + j,
                      _mm_add_pd(_mm_add_pd(_mm_mul_pd(r2, t0), _mm_mul_pd(r5, t1)), _mm_mul_pd(r8, t2)));
    }
#else
    for (j = 0; j < 6; j++) {
        const double v0 = Z[j], v1 = Z[6 + j], v2 = Z[12 + j];
        double t0 = Z[18 + j], t1 = Z[24 + j], t2 = Z[30 + j];
        if (moved) {
            t0 -= p[1] * v2 - p[2] * v1;
            t1 -= p[2] * v0 - p[0] * v2;
            t2 -= p[0] * v1 - p[1] * v0;
        }
        out[j] = R[0] * v0 + R[3] * v1 + R[6] * v2;
        out[(int64_t)ld + j] = R[1] * v0 + R[4] * v1 + R[7] * v2;
        out[(int64_t)2 * ld + j] = R[2] * v0 + R[5] * v1 + R[8] * v2;
        out[(int64_t)3 * ld + j] = R[0] * t0 + R[3] * t1 + R[6] * t2;
        out[(int64_t)4 * ld + j] = R[1] * t0 + R[4] * t1 + R[7] * t2;
        out[(int64_t)5 * ld + j] = R[2] * t0 + R[5] * t1 + R[8] * t2;
    }
#endif
}


/* The joint's coefficients of node n from the rows reduced by the constraint
 * reflections (ld = ncol columns; only the first w can be non-zero in the
 * constraint and relative rows): X = [X1 X2] the outer rows, Lc the first c columns of the c constraint rows (lower
 * triangular), Kp = [Kp1 Kp2] the reflected Sd^T L_k (d rows). With
 * E = Lc^-1 Tc^T and Sd = S (S^T S)^-1:
 *   FX = W M^T = -E^T X1^T,  QX = U M^T = -Kp2 X2^T,
 *   U = Sd^T (1 - K1 E) = Sd^T - Kp1 E,  rho = -U beta + Kp2 Kp2^T Q,
 *   gamma = E^T E beta + U^T Q,
 *   b_C = b_o + X2 Kp2^T Q + X1 E beta,
 * (M = -L_o L_k^T, W = E^T E = Tc (Tc^T T Tc)^-1 Tc^T, T = L_k L_k^T):
 * products of reduced factors only, no large mobility subtracted from
 * another (docs/math.md, "Accurate Phi"). bo: the outer handles' b; kq: w
 * scratch doubles. */
#ifdef DCA_AVX
#define DCA_AVX_W 24 /* jc_outer_avx: at most this many columns w */
/* joint_coefficients' loop over the outer rows, four rows o .. o+3 at a time
 * with AVX, the rows in the lanes: their entries transposed column by column
 * (xc[k] = row o..o+3's entry k), then every sum of the scalar loop (FX, b_C,
 * QX) in its order, lane by lane. Returns the first row left (orows is a
 * multiple of 6: the last two rows when it is not a multiple of 4). */
DCA_TARGET_AVX static inline DCA_INLINE int32_t jc_outer_avx_body(const double *X, int32_t ncol, int32_t orows,
                                                                   int32_t c, int32_t d, int32_t w, const double *E,
                                                                   const double *Eb, const double *kq, const double *Kp,
                                                                   const double *bo, double *FX, double *QX, double *bC)
{
    __m256d eb[36], ebb[6], kqb[DCA_AVX_W], kb[6 * DCA_AVX_W], xc[DCA_AVX_W];
    int32_t o, i, k, r;
    for (k = 0; k < c; k++) {
        for (i = 0; i < 6; i++) eb[6 * k + i] = _mm256_set1_pd(E[6 * k + i]);
        ebb[k] = _mm256_set1_pd(Eb[k]);
    }
    for (k = c; k < w; k++) kqb[k] = _mm256_set1_pd(kq[k - c]);
    for (r = 0; r < d; r++)
        for (k = c; k < w; k++) kb[DCA_AVX_W * r + k] = _mm256_set1_pd(Kp[(int64_t)r * ncol + k]);
    for (o = 0; o + 3 < orows; o += 4) {
        const double *x1 = X + (int64_t)o * ncol, *x2 = x1 + ncol, *x3 = x2 + ncol, *x4 = x3 + ncol;
        __m256d sb;
        for (k = 0; k + 3 < w; k += 4) {
            const __m256d ra = _mm256_loadu_pd(x1 + k), rb = _mm256_loadu_pd(x2 + k), rg = _mm256_loadu_pd(x3 + k),
                          rh = _mm256_loadu_pd(x4 + k);
            const __m256d t0 = _mm256_unpacklo_pd(ra, rb), t1 = _mm256_unpackhi_pd(ra, rb);
            const __m256d t2 = _mm256_unpacklo_pd(rg, rh), t3 = _mm256_unpackhi_pd(rg, rh);
            xc[k] = _mm256_permute2f128_pd(t0, t2, 0x20);
            xc[k + 1] = _mm256_permute2f128_pd(t1, t3, 0x20);
            xc[k + 2] = _mm256_permute2f128_pd(t0, t2, 0x31);
            xc[k + 3] = _mm256_permute2f128_pd(t1, t3, 0x31);
        }
        for (; k < w; k++)
            xc[k] = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadh_pd(_mm_load_sd(x1 + k), x2 + k)),
                                         _mm_loadh_pd(_mm_load_sd(x3 + k), x4 + k), 1);
        for (i = 0; i < 6; i++) {
            __m256d f = _mm256_setzero_pd();
            for (k = 0; k < c; k++) f = _mm256_sub_pd(f, _mm256_mul_pd(eb[6 * k + i], xc[k]));
            _mm256_storeu_pd(FX + (int64_t)i * orows + o, f);
        }
        sb = _mm256_loadu_pd(bo + o);
        for (k = 0; k < c; k++) sb = _mm256_add_pd(sb, _mm256_mul_pd(xc[k], ebb[k]));
        for (k = c; k < w; k++) sb = _mm256_add_pd(sb, _mm256_mul_pd(xc[k], kqb[k]));
        _mm256_storeu_pd(bC + o, sb);
        for (r = 0; r < d; r++) {
            __m256d x = _mm256_setzero_pd();
            for (k = c; k < w; k++) x = _mm256_sub_pd(x, _mm256_mul_pd(kb[DCA_AVX_W * r + k], xc[k]));
            _mm256_storeu_pd(QX + (int64_t)r * orows + o, x);
        }
    }
    return o;
}

/* joint_coefficients' E = Lc^-1 Tc^T (c x 6) with AVX: columns 0-3 of E in one
 * register, 4-5 in an SSE2 one, each lane the SSE2 loop's operations (x = Tc's
 * entry, less Lc_ik E_kj for k = 0 .. i-1 in order, then / Lc_ii); -1 if an entry
 * before its division is not finite (x * 0 is NaN only then). */
DCA_TARGET_AVX static inline DCA_INLINE int jc_e_avx_body(const double *Tc, const double *Lc, int32_t ncol, int32_t c,
                                                          double *E)
{
    __m256d e0[6], bad0 = _mm256_setzero_pd();
    __m128d e1[6], bad1 = _mm_setzero_pd();
    int32_t i, k;
    for (i = 0; i < c; i++) {
        const double *li = Lc + (int64_t)i * ncol;
        double t[4];
        __m256d x0;
        __m128d x1;
        t[0] = Tc[i];
        t[1] = Tc[6 + i];
        t[2] = Tc[12 + i];
        t[3] = Tc[18 + i];
        x0 = _mm256_loadu_pd(t);
        x1 = _mm_loadh_pd(_mm_load_sd(Tc + 24 + i), Tc + 30 + i);
        for (k = 0; k < i; k++) {
            const __m256d l = _mm256_broadcast_sd(li + k);
            x0 = _mm256_sub_pd(x0, _mm256_mul_pd(l, e0[k]));
            x1 = _mm_sub_pd(x1, _mm_mul_pd(_mm256_castpd256_pd128(l), e1[k]));
        }
        bad0 = _mm256_add_pd(bad0, _mm256_mul_pd(x0, _mm256_setzero_pd()));
        bad1 = _mm_add_pd(bad1, _mm_mul_pd(x1, _mm_setzero_pd()));
        {
            const __m256d p = _mm256_broadcast_sd(li + i);
            e0[i] = _mm256_div_pd(x0, p);
            e1[i] = _mm_div_pd(x1, _mm256_castpd256_pd128(p));
        }
        _mm256_storeu_pd(E + 6 * i, e0[i]);
        _mm_storeu_pd(E + 6 * i + 4, e1[i]);
    }
    if (_mm256_movemask_pd(_mm256_cmp_pd(bad0, bad0, _CMP_UNORD_Q)) != 0 ||
        _mm_movemask_pd(_mm_cmpunord_pd(bad1, bad1)) != 0)
        return -1;
    return 0;
}

/* joint_coefficients' gamma = E^T Eb + U^T Q: entries 0-3 in one register, 4-5 in an
 * SSE2 one, each sum as the SSE2 loop's (from 0.0, E's terms, then U's) */
DCA_TARGET_AVX static void jc_gamma_avx(const double *E, const double *Eb, const double *U, const double *Q, int32_t c,
                                        int32_t d, double *gw)
{
    __m256d x0 = _mm256_setzero_pd();
    __m128d x1 = _mm_setzero_pd();
    int32_t k;
    for (k = 0; k < c; k++) {
        const __m256d b = _mm256_broadcast_sd(Eb + k);
        x0 = _mm256_add_pd(x0, _mm256_mul_pd(_mm256_loadu_pd(E + 6 * k), b));
        x1 = _mm_add_pd(x1, _mm_mul_pd(_mm_loadu_pd(E + 6 * k + 4), _mm256_castpd256_pd128(b)));
    }
    for (k = 0; k < d; k++) {
        const __m256d q = _mm256_broadcast_sd(Q + k);
        x0 = _mm256_add_pd(x0, _mm256_mul_pd(_mm256_loadu_pd(U + 6 * k), q));
        x1 = _mm_add_pd(x1, _mm_mul_pd(_mm_loadu_pd(U + 6 * k + 4), _mm256_castpd256_pd128(q)));
    }
    _mm256_storeu_pd(gw, x0);
    _mm_storeu_pd(gw + 4, x1);
}

DCA_TARGET_AVX static int jc_e_avx(const double *Tc, const double *Lc, int32_t ncol, int32_t c, double *E)
{
    if (c == 5) return jc_e_avx_body(Tc, Lc, ncol, 5, E);
    return jc_e_avx_body(Tc, Lc, ncol, c, E);
}

/* the body for a revolute or prismatic joint (c = 5, d = 1) at the molecule's widths w as constants */
DCA_TARGET_AVX static int32_t jc_outer_avx(const double *X, int32_t ncol, int32_t orows, int32_t c, int32_t d,
                                           int32_t w, const double *E, const double *Eb, const double *kq,
                                           const double *Kp, const double *bo, double *FX, double *QX, double *bC)
{
    if (c == 5 && d == 1) switch (w) {
        case 6: return jc_outer_avx_body(X, ncol, orows, 5, 1, 6, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 7: return jc_outer_avx_body(X, ncol, orows, 5, 1, 7, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 8: return jc_outer_avx_body(X, ncol, orows, 5, 1, 8, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 9: return jc_outer_avx_body(X, ncol, orows, 5, 1, 9, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 10: return jc_outer_avx_body(X, ncol, orows, 5, 1, 10, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 11: return jc_outer_avx_body(X, ncol, orows, 5, 1, 11, E, Eb, kq, Kp, bo, FX, QX, bC);
        case 12: return jc_outer_avx_body(X, ncol, orows, 5, 1, 12, E, Eb, kq, Kp, bo, FX, QX, bC);
        default: break;
        }
    return jc_outer_avx_body(X, ncol, orows, c, d, w, E, Eb, kq, Kp, bo, FX, QX, bC);
}
#endif

/* ---- The load factors (dca_loads_enable): what rho, gamma and b_C take from
 * the loads, rho = -U beta + G2 Q, gamma = W beta + U^T Q (W = E^T E, or the
 * rigid join's), b_C = b_o - FX^T beta - QX^T Q, kept per node when enabled so
 * that a change of loads alone (src/solve/arefine.c's corrections) costs no
 * reflection. Layout per internal node at lfoff: W (36), U (6 d), G2 (d d). */

static void keep_load_factors(tree *t, int32_t n, const double *U, const double *G2, const double *E,
                              const double *W, int32_t c)
{
    const node *C = &t->nodes[n];
    double *o;
    int32_t i, j, k;
    if (!t->lf) return;
    o = t->lf + t->lfoff[n];
    if (E) {
        for (i = 0; i < 6; i++)
            for (j = 0; j < 6; j++) {
                double x = 0.0;
                for (k = 0; k < c; k++) x += E[6 * k + i] * E[6 * k + j];
                o[6 * i + j] = x;
            }
    } else {
        memcpy(o, W, 36 * sizeof(double));
    }
    memcpy(o + 36, U, 6 * (size_t)C->d * sizeof(double));
    memcpy(o + 36 + 6 * C->d, G2, (size_t)C->d * C->d * sizeof(double));
    t->lfok[n] = 1;
}

aqs_status dca_loads_enable(aqs_linkage *L)
{
    tree *t = &L->t;
    int64_t off = 0;
    int32_t k;
    if (t->lf) return AQS_OK;
    t->lfoff = lk_calloc_in(L, LK_MEM_DCA, (size_t)t->nnodes + 1, sizeof(int64_t));
    t->lfok = lk_calloc_in(L, LK_MEM_DCA, (size_t)t->nnodes + 1, 1);
    if (!t->lfoff || !t->lfok) {
        dca_loads_free(L);
        return AQS_ENOMEM;
    }
    for (k = 0; k < t->nnodes; k++) {
        const node *nd = &t->nodes[k];
        t->lfoff[k] = off;
        if (nd->joint >= 0) off += 36 + 6 * (int64_t)nd->d + (int64_t)nd->d * nd->d;
    }
    if (!(t->lf = lk_calloc_in(L, LK_MEM_DCA, (size_t)off + 1, sizeof(double)))) {
        dca_loads_free(L);
        return AQS_ENOMEM;
    }
    return AQS_OK;
}

void dca_loads_free(aqs_linkage *L)
{
    tree *t = &L->t;
    lk_free(L, t->lf);
    lk_free(L, t->lfoff);
    lk_free(L, t->lfok);
    t->lf = NULL;
    t->lfoff = NULL;
    t->lfok = NULL;
}

int dca_node_loads(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *Q = L->tau + jd->voff, *bA = t->data + A->bv, *bB = t->data + B->bv;
    const double *FX = t->data + nd_W(C), *QX = t->data + nd_U(C), *o, *W, *U, *G2;
    double *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C), *bC = t->data + C->bv;
    double beta[6], bk[6];
    const int32_t d = C->d, orows = 6 * C->nh, nAo = A->nh - 1;
    int32_t i, j, r, ci;
    if (!t->lf || !t->lfok[n] || L->dca_form != AQS_DCA_FORM_SQRT) return -1;
    o = t->lf + t->lfoff[n];
    W = o;
    U = o + 36;
    G2 = o + 36 + 6 * d;
    spatial_xform_motion(t->poses + nd_J(C), bA + 6 * C->ka, bk);
    for (i = 0; i < 6; i++) beta[i] = bk[i] - bB[6 * C->kb + i];
    for (r = 0; r < d; r++) {
        double x = 0.0;
        for (j = 0; j < 6; j++) x -= U[6 * r + j] * beta[j];
        for (j = 0; j < d; j++) x += G2[d * r + j] * Q[j];
        rho[r] = x;
    }
    for (i = 0; i < 6; i++) {
        double x = 0.0;
        for (j = 0; j < 6; j++) x += W[6 * i + j] * beta[j];
        for (r = 0; r < d; r++) x += U[6 * r + i] * Q[r];
        gamma[i] = x;
    }
    for (ci = 0; ci < C->nh; ci++) {
        const int a = ci < nAo;
        const int32_t src = a ? (ci < C->ka ? ci : ci + 1) : (ci - nAo < C->kb ? ci - nAo : ci - nAo + 1);
        const double *bs = (a ? bA : bB) + 6 * src;
        for (r = 0; r < 6; r++) {
            const int32_t ro = 6 * ci + r;
            double x = bs[r];
            for (i = 0; i < 6; i++) x -= FX[(int64_t)i * orows + ro] * beta[i];
            for (j = 0; j < d; j++) x -= QX[(int64_t)j * orows + ro] * Q[j];
            bC[ro] = x;
        }
    }
    return 0;
}

static int joint_coefficients(aqs_linkage *L, int32_t n, const double *Sd, int32_t d, const double *Tc,
                              const double *X, const double *Lc, const double *Kp, int32_t ncol, int32_t w,
                              const double beta[6], const double *Q, const double *bo, double *kq)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    double *FX = t->data + nd_W(C), *QX = t->data + nd_U(C), *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C);
    double *bC = t->data + C->bv;
    const int32_t c = 6 - d, orows = 6 * C->nh;
    double E[36], U[36], G2[36], Eb[6], gw[6];
    int32_t i, j, k, r, o;
    /* E = Lc^-1 Tc^T (c x 6), forward substitution per column; -1 if a pivot
     * is zero or not finite, or an entry before its division is not finite */
    for (i = 0; i < c; i++)
        if (!(fabs(Lc[(int64_t)i * ncol + i]) > 0.0)) return -1;
#ifdef DCA_AVX
    if (t->avx) {
        if (jc_e_avx(Tc, Lc, ncol, c, E) != 0) return -1;
    } else
#endif
#ifdef DCA_SSE2
    { /* two columns at a time, each lane as below; x * 0 is NaN only for x not finite */
        __m128d bad = _mm_setzero_pd();
        for (j = 0; j < 6; j += 2)
            for (i = 0; i < c; i++) {
                __m128d x = _mm_loadh_pd(_mm_load_sd(Tc + 6 * j + i), Tc + 6 * (j + 1) + i);
                for (k = 0; k < i; k++)
                    x = _mm_sub_pd(x, _mm_mul_pd(_mm_set1_pd(Lc[(int64_t)i * ncol + k]), _mm_loadu_pd(E + 6 * k + j)));
                bad = _mm_add_pd(bad, _mm_mul_pd(x, _mm_setzero_pd()));
                _mm_storeu_pd(E + 6 * i + j, _mm_div_pd(x, _mm_set1_pd(Lc[(int64_t)i * ncol + i])));
            }
        if (_mm_movemask_pd(_mm_cmpunord_pd(bad, bad)) != 0) return -1;
    }
#else
    for (j = 0; j < 6; j++)
        for (i = 0; i < c; i++) {
            double x = Tc[6 * j + i];
            double piv = Lc[(int64_t)i * ncol + i];
            for (k = 0; k < i; k++) x -= Lc[(int64_t)i * ncol + k] * E[6 * k + j];
            if (!isfinite(x)) return -1;
            E[6 * i + j] = x / piv;
        }
#endif
    /* U = Sd^T - Kp1 E */
#ifdef DCA_SSE2
    for (r = 0; r < d; r++) /* two entries of U's row at a time, each sum as below */
        for (j = 0; j < 6; j += 2) {
            __m128d x = _mm_loadh_pd(_mm_load_sd(Sd + j * d + r), Sd + (j + 1) * d + r);
            for (k = 0; k < c; k++)
                x = _mm_sub_pd(x, _mm_mul_pd(_mm_set1_pd(Kp[(int64_t)r * ncol + k]), _mm_loadu_pd(E + 6 * k + j)));
            _mm_storeu_pd(U + 6 * r + j, x);
        }
#else
    for (r = 0; r < d; r++)
        for (j = 0; j < 6; j++) {
            double x = Sd[j * d + r];
            for (k = 0; k < c; k++) x -= Kp[(int64_t)r * ncol + k] * E[6 * k + j];
            U[6 * r + j] = x;
        }
#endif
    for (k = 0; k < c; k++) {
        double x = 0.0;
        for (j = 0; j < 6; j++) x += E[6 * k + j] * beta[j];
        Eb[k] = x;
    }
    /* G2 = Kp2 Kp2^T; kq = Kp2^T Q (columns c .. w-1; zero beyond) */
    for (r = 0; r < d; r++)
        for (j = 0; j <= r; j++) {
            const double *kr = Kp + (int64_t)r * ncol, *kj = Kp + (int64_t)j * ncol;
            double x = 0.0;
            for (k = c; k < w; k++) x += kr[k] * kj[k];
            G2[d * r + j] = G2[d * j + r] = x;
        }
    k = c;
#ifdef DCA_SSE2
    for (; k + 1 < w; k += 2) { /* two entries at a time, each sum as below */
        __m128d x = _mm_setzero_pd();
        for (r = 0; r < d; r++)
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(Kp + (int64_t)r * ncol + k), _mm_set1_pd(Q[r])));
        _mm_storeu_pd(kq + k - c, x);
    }
#endif
    for (; k < w; k++) {
        double x = 0.0;
        for (r = 0; r < d; r++) x += Kp[(int64_t)r * ncol + k] * Q[r];
        kq[k - c] = x;
    }
    /* per outer row: FX = -E^T X1^T, QX = -Kp2 X2^T, b_C = b_o + X1 E beta + X2 Kp2^T Q */
#ifdef DCA_SSE2
    /* two outer rows at a time (orows is a multiple of 6): E's rows two
     * entries at a time for FX, the two rows' b_C and QX sums in the two
     * lanes; every sum as in the scalar loops below, lane by lane */
    o = 0;
#ifdef DCA_AVX
    if (t->avx && w <= DCA_AVX_W) o = jc_outer_avx(X, ncol, orows, c, d, w, E, Eb, kq, Kp, bo, FX, QX, bC);
#endif
    for (; o < orows; o += 2) {
        const double *x1 = X + (int64_t)o * ncol, *x2 = x1 + ncol;
        __m128d sb = _mm_loadu_pd(bo + o);
        int32_t h;
        for (h = 0; h < 2; h++) {
            const double *xr = h ? x2 : x1;
            __m128d f0 = _mm_setzero_pd(), f1 = f0, f2 = f0;
            for (k = 0; k < c; k++) {
                const __m128d xk = _mm_set1_pd(xr[k]);
                f0 = _mm_sub_pd(f0, _mm_mul_pd(_mm_loadu_pd(E + 6 * k), xk));
                f1 = _mm_sub_pd(f1, _mm_mul_pd(_mm_loadu_pd(E + 6 * k + 2), xk));
                f2 = _mm_sub_pd(f2, _mm_mul_pd(_mm_loadu_pd(E + 6 * k + 4), xk));
            }
            _mm_storel_pd(FX + o + h, f0);
            _mm_storeh_pd(FX + orows + o + h, f0);
            _mm_storel_pd(FX + (int64_t)2 * orows + o + h, f1);
            _mm_storeh_pd(FX + (int64_t)3 * orows + o + h, f1);
            _mm_storel_pd(FX + (int64_t)4 * orows + o + h, f2);
            _mm_storeh_pd(FX + (int64_t)5 * orows + o + h, f2);
        }
        for (k = 0; k < c; k++)
            sb = _mm_add_pd(sb, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(x1 + k), x2 + k), _mm_set1_pd(Eb[k])));
        for (k = c; k < w; k++)
            sb = _mm_add_pd(sb, _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(x1 + k), x2 + k), _mm_set1_pd(kq[k - c])));
        _mm_storeu_pd(bC + o, sb);
        for (r = 0; r < d; r++) {
            const double *kr = Kp + (int64_t)r * ncol;
            __m128d x = _mm_setzero_pd();
            for (k = c; k < w; k++)
                x = _mm_sub_pd(x, _mm_mul_pd(_mm_set1_pd(kr[k]), _mm_loadh_pd(_mm_load_sd(x1 + k), x2 + k)));
            _mm_storeu_pd(QX + (int64_t)r * orows + o, x);
        }
    }
#else
    for (o = 0; o < orows; o++) {
        const double *x1 = X + (int64_t)o * ncol;
        double sb = bo[o];
        for (i = 0; i < 6; i++) {
            double x = 0.0;
            for (k = 0; k < c; k++) x -= E[6 * k + i] * x1[k];
            FX[(int64_t)i * orows + o] = x;
        }
        for (k = 0; k < c; k++) sb += x1[k] * Eb[k];
        for (k = c; k < w; k++) sb += x1[k] * kq[k - c];
        bC[o] = sb;
        for (r = 0; r < d; r++) {
            const double *kr = Kp + (int64_t)r * ncol;
            double x = 0.0;
            for (k = c; k < w; k++) x -= kr[k] * x1[k];
            QX[(int64_t)r * orows + o] = x;
        }
    }
#endif
    for (r = 0; r < d; r++) {
        double x = 0.0;
        for (j = 0; j < 6; j++) x -= U[6 * r + j] * beta[j];
        for (j = 0; j < d; j++) x += G2[d * r + j] * Q[j];
        rho[r] = x;
        if (!isfinite(x)) return -2; /* the loads overflowed (the pivots above are fine) */
    }
#ifdef DCA_AVX
    if (t->avx) jc_gamma_avx(E, Eb, U, Q, c, d, gw);
    else
#endif
#ifdef DCA_SSE2
    for (i = 0; i < 6; i += 2) { /* two entries at a time, each sum as below */
        __m128d x = _mm_setzero_pd();
        for (k = 0; k < c; k++) x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(E + 6 * k + i), _mm_set1_pd(Eb[k])));
        for (r = 0; r < d; r++) x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(U + 6 * r + i), _mm_set1_pd(Q[r])));
        _mm_storeu_pd(gw + i, x);
    }
#else
    for (i = 0; i < 6; i++) {
        double x = 0.0;
        for (k = 0; k < c; k++) x += E[6 * k + i] * Eb[k];
        for (r = 0; r < d; r++) x += U[6 * r + i] * Q[r];
        gw[i] = x;
    }
#endif
    memcpy(gamma, gw, sizeof gw);
    rounding_node(L, n, U, G2, E, NULL, beta, Q, Lc, Tc, ncol, 0.0, bo);
    keep_load_factors(t, n, U, G2, E, NULL, c);
    return 0;
}

/* ---- The rigid join in inertia form (docs/math.md 4a, "Rigid sides: the
 * join in inertia form"). Where both children are rigid (no Lambda) and
 * neither holds the world, the node is two rigid bodies and joint k. With
 * every quantity in k's child frame K, I_A, I_B the sides' spatial inertias,
 * I_C = I_A + I_B (inverted through its centre of mass, mp_y), Pa = I_C^-1 I_A
 * and Pb = I_C^-1 I_B (Pa + Pb = 1), the joint's mode moves A by -Pb S and B
 * by Pa S, and its inertia is the Schur complement
 *   D = S^T I_A I_C^-1 I_B S  (= S^T (I_A^-1 + I_B^-1)^-1 S),
 * as the ABA forms it. With V = I_A I_C^-1 I_B (the reduced inertia), U =
 * D^-1 S^T V and Pr = 1 - U^T S^T, the section-4 outputs are
 *   rho = D^-1 Q - U beta,      gamma = V beta + V S rho,
 *   FX_h = Pr Pb^T G_h^T (A's handles), -Pr Pa^T G_h^T (B's),
 *   QX_h = D^-1 (Pb S)^T G_h^T,         -D^-1 (Pa S)^T G_h^T,
 *   b_C,h = b^A_h - G_h Pb (beta + S rho),   b^B_h + G_h Pa (beta + S rho),
 *   Lambda_C,h = -G_h Pb S R^-T,             G_h Pa S R^-T      (D = R R^T),
 * (G_h: K to handle h). None of them goes through I_A^-1 or I_B^-1: a side's
 * near-free rotation (a near point mass, a tiny floating base), whose mobility
 * 1/k the square-root form reduces by reflections with an absolute error
 * u/sqrt(k), never appears; the spin about the joint axis enters as the
 * inertia k + m r^2 in D. */

/* The frames of node n's join: Pk (B's frame in C's = A's frame) and Pkb (k's
 * child frame in C's), and B's mass properties in C's frame (IB). -1 when a
 * frame is farther out than 1e150 m: no digit of the metre-sized geometry is
 * left (and m r^2 overflows past 1e154), numerically singular, as the
 * articulated-body and the inverse-inertia forms find by overflow. */
static inline int join_frames(const tree *t, const node *C, pose *Pk, pose *Pkb, double IB[13])
{
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *P = t->poses + C->poses;
    int32_t ci;
    pose_compose(t->poses + A->poses + C->ka, t->poses + nd_J(C), Pk);
    pose_compose(Pk, t->poses + B->poses + C->kb, Pkb);
    for (ci = 0; ci <= C->nh; ci++) {
        const double *p = ci < C->nh ? P[ci].p : Pkb->p;
        if (!(fabs(p[0]) < 1e150 && fabs(p[1]) < 1e150 && fabs(p[2]) < 1e150)) return -1;
    }
    memset(IB, 0, 13 * sizeof(double));
    model_mass_add_posed(IB, Pk, t->data + nd_ic(B));
    return 0;
}

/* The sides' mobility is dominated by a near-free rotation: a side's
 * rotational mobility (trace Ic^-1) times the mass and squared distance of the
 * other side's centre of mass (the lever the joint adds), above RJ_RATIO. */
#define RJ_RATIO 1e3

/* 1 if a join of two rigid sides takes the inertia form (rigid_join): a side's
 * rotational mobility trace(Ic^-1) = |Jc|^2 times the reduced mass and the
 * squared distance between the centres of mass (what turns a relative
 * rotation into a relative translation) above RJ_RATIO. mpA, mpB: the sides'
 * mass properties in one frame; JA, JB their mp_factor. */
static int rigid_join_wanted(const double *mpA, const double *mpB, const double JA[9], const double JB[9])
{
    /* Jc is upper triangular (mp_factor): its six entries on and above the diagonal */
    const double trA = JA[0] * JA[0] + JA[1] * JA[1] + JA[2] * JA[2] + JA[4] * JA[4] + JA[5] * JA[5] + JA[8] * JA[8];
    const double trB = JB[0] * JB[0] + JB[1] * JB[1] + JB[2] * JB[2] + JB[4] * JB[4] + JB[5] * JB[5] + JB[8] * JB[8];
    const double e0 = mpB[1] - mpA[1], e1 = mpB[2] - mpA[2], e2 = mpB[3] - mpA[3];
    return (trA > trB ? trA : trB) * (mpA[0] * mpB[0]) * (e0 * e0 + e1 * e1 + e2 * e2) > RJ_RATIO * (mpA[0] + mpB[0]);
}

/* Node n's update in inertia form (both children rigid and not grounded): the
 * same outputs as hybrid_phi (mass properties, Lambda of rank d, b, FX, QX,
 * rho, gamma) by the formulas above. Returns 0, -1 when a composite
 * inertia or D is not positive definite, -2 when rho came out non-finite
 * from finite D and U (the loads overflowed). */
static int rigid_join(aqs_linkage *L, int32_t n, const double *S, int32_t d, const double beta[6],
                      const double *Q)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *PB = t->poses + B->poses, *P = t->poses + C->poses;
    const double *IA = t->data + nd_ic(A), *IBb = t->data + nd_ic(B);
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    double *IC = t->data + nd_ic(C), *LC = t->data + nd_lam(C), *bC = t->data + C->bv;
    double *FX = t->data + nd_W(C), *QX = t->data + nd_U(C), *rho = t->data + nd_rho(C),
           *gamma = t->data + nd_gamma(C);
    const int32_t nA = A->nh, nh = C->nh, nAo = nA - 1, orows = 6 * nh;
    double IB[13], mA[13], mB[13], mC[13], Ia[36], Ib[36], Yc[36], Pa[36], Pb[36], T6[36];
    double PaS[36], PbS[36], VS[36], D[36], Di[36], R[36], U[36], Pr[36], W[36], Za[36], Zb[36];
    double La[36], Lb[36], Qa[36], Qb[36], g[6], z[6], Vb[6], G2[36];
    pose Pk, Pkb, Kin, PBi, Ph;
    int32_t i, j, r, s, ci;

    if (join_frames(t, C, &Pk, &Pkb, IB) != 0) return -1;
    C->grounded = 0;
    memcpy(IC, IA, 13 * sizeof(double));
    model_mass_add(IC, IB[0], IB + 1, IB + 4);
    /* the sides' and the composite's mass properties in K */
    pose_inverse(&Pkb, &Kin);
    pose_inverse(&PB[C->kb], &PBi);
    memset(mA, 0, sizeof mA);
    memset(mB, 0, sizeof mB);
    model_mass_add_posed(mA, &Kin, IA);
    model_mass_add_posed(mB, &PBi, IBb);
    memcpy(mC, mA, sizeof mC);
    model_mass_add(mC, mB[0], mB + 1, mB + 4);
    if (mp_inverse_factor(mC, Yc) != 0) return -1;
    spatial_inertia(mA[0], mA + 1, mA + 4, Ia);
    spatial_inertia(mB[0], mB + 1, mB + 4, Ib);
    /* Pa = I_C^-1 I_A = Yc (Yc^T I_A), Pb likewise */
    dense_mul_tn(Yc, Ia, T6, 6, 6, 6);
    dense_mul66(Yc, T6, Pa);
    dense_mul_tn(Yc, Ib, T6, 6, 6, 6);
    dense_mul66(Yc, T6, Pb);
    /* Pa S, Pb S (6 x d); V S = I_A Pb S; D = S^T V S (symmetrized) */
    dense_mul(Pa, S, PaS, 6, 6, d);
    dense_mul(Pb, S, PbS, 6, 6, d);
    dense_mul(Ia, PbS, VS, 6, 6, d);
    /* D (d x d) in the top left of the 6 x 6 D = [D 0; 0 1]: its Cholesky
     * factor R and inverse Di have the same blocks (stride 6) */
    memset(D, 0, sizeof D);
    for (r = d; r < 6; r++) D[7 * r] = 1.0;
    for (r = 0; r < d; r++)
        for (s = 0; s <= r; s++) {
            double x = 0.0, y = 0.0;
            for (i = 0; i < 6; i++) {
                x += S[i * d + r] * VS[i * d + s];
                y += S[i * d + s] * VS[i * d + r];
            }
            D[6 * r + s] = D[6 * s + r] = 0.5 * (x + y);
        }
    if (dense_cholesky6(D, R) != 0) return -1;
    dense_cholesky6_inverse(R, Di);
    /* U = D^-1 (V S)^T (d x 6); Pr = 1 - U^T S^T; W = Pr V (for the rounding estimate) */
    for (r = 0; r < d; r++)
        for (j = 0; j < 6; j++) {
            double x = 0.0;
            for (s = 0; s < d; s++) x += Di[6 * r + s] * VS[j * d + s];
            U[6 * r + j] = x;
        }
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) {
            double x = i == j ? 1.0 : 0.0;
            for (r = 0; r < d; r++) x -= U[6 * r + i] * S[j * d + r];
            Pr[6 * i + j] = x;
        }
    dense_mul66(Ia, Pb, T6); /* V */
    dense_mul66(Pr, T6, W);
    /* rho = D^-1 Q - U beta; gamma = V beta + V S rho */
    dense_matvec6(T6, beta, Vb);
    for (r = 0; r < d; r++) {
        double x = 0.0;
        for (s = 0; s < d; s++) x += Di[6 * r + s] * Q[s];
        for (j = 0; j < 6; j++) x -= U[6 * r + j] * beta[j];
        if (!isfinite(x)) return -2; /* the loads overflowed (D, U are finite) */
        rho[r] = x;
    }
    for (i = 0; i < 6; i++) {
        double x = Vb[i];
        for (r = 0; r < d; r++) x += VS[i * d + r] * rho[r];
        gamma[i] = x;
        z[i] = beta[i];
        for (r = 0; r < d; r++) z[i] += S[i * d + r] * rho[r]; /* beta + S rho */
    }
    /* per-side matrices, columns K-frame motions moved to each handle below:
     * Za = (Pr Pb^T)^T = Pb Pr^T, Zb = -Pa Pr^T (FX_h^T = G_h Z);
     * La = -Pb S R^-T, Lb = Pa S R^-T (Lambda); Qa = Pb S D^-1, Qb = -Pa S D^-1 (QX_h^T) */
    dense_mul66_nt(Pb, Pr, Za);
    dense_mul66_nt(Pa, Pr, Zb);
    for (i = 0; i < 36; i++) Zb[i] = -Zb[i];
    memset(La, 0, sizeof La);
    memset(Lb, 0, sizeof Lb);
    memset(Qa, 0, sizeof Qa);
    memset(Qb, 0, sizeof Qb);
    { /* La^T = R^-1 (-Pb S)^T, Lb^T = R^-1 (Pa S)^T: six right-hand sides
         each (rows d..5 of R are the identity's and of the sides zero) */
        double ra[36] = {0}, rb[36] = {0}, wa[36], wb[36];
        for (i = 0; i < 6; i++)
            for (j = 0; j < d; j++) {
                ra[6 * j + i] = -PbS[i * d + j];
                rb[6 * j + i] = PaS[i * d + j];
            }
        dense_cholesky6_lower_solve(R, ra, wa, 6);
        dense_cholesky6_lower_solve(R, rb, wb, 6);
        for (i = 0; i < 6; i++)
            for (j = 0; j < d; j++) {
                La[6 * i + j] = wa[6 * j + i];
                Lb[6 * i + j] = wb[6 * j + i];
            }
    }
    for (i = 0; i < 6; i++) {
        for (j = 0; j < d; j++) {
            double xa = 0.0, xb = 0.0;
            for (s = 0; s < d; s++) {
                xa += PbS[i * d + s] * Di[6 * s + j];
                xb -= PaS[i * d + s] * Di[6 * s + j];
            }
            Qa[6 * i + j] = xa;
            Qb[6 * i + j] = xb;
        }
    }
    /* g = Pb (beta + S rho) moves A's handles, -Pa (beta + S rho) B's */
    {
        double ga[6], gb[6];
        dense_matvec6(Pb, z, ga);
        dense_matvec6(Pa, z, gb);
        for (i = 0; i < 6; i++) {
            g[i] = -ga[i];
            z[i] = gb[i];
        }
    }
    for (ci = 0; ci < nh; ci++) {
        const int a = ci < nAo;
        const int32_t src = a ? (ci < C->ka ? ci : ci + 1) : (ci - nAo < C->kb ? ci - nAo : ci - nAo + 1);
        const double *bs = (a ? bA : bB) + 6 * src;
        double F6[36], L6[36], Q6[36], db[6];
        pose_compose(&Kin, &P[ci], &Ph); /* handle ci in K */
        xform_cols(&Ph, a ? Za : Zb, F6, 6, t->avx);
        xform_cols(&Ph, a ? La : Lb, L6, 6, t->avx);
        xform_cols(&Ph, a ? Qa : Qb, Q6, 6, t->avx);
        spatial_xform_motion(&Ph, a ? g : z, db);
        for (r = 0; r < 6; r++) {
            const int32_t o = 6 * ci + r;
            for (i = 0; i < 6; i++) FX[(int64_t)i * orows + o] = F6[6 * r + i];
            for (j = 0; j < d; j++) QX[(int64_t)j * orows + o] = Q6[6 * r + j];
            memcpy(LC + (int64_t)o * C->lld, L6 + 6 * r, sizeof(double) * (size_t)d);
            bC[o] = bs[r] + db[r];
        }
    }
    C->rank = d;
    C->jw = d;
    for (r = 0; r < d; r++)
        for (s = 0; s < d; s++) G2[d * r + s] = Di[6 * r + s];
    {
        double *bov = t->hscratch; /* the outer handles' b, for the rounding estimate */
        for (ci = 0; ci < nh; ci++) {
            const int a = ci < nAo;
            const int32_t src = a ? (ci < C->ka ? ci : ci + 1) : (ci - nAo < C->kb ? ci - nAo : ci - nAo + 1);
            memcpy(bov + 6 * ci, (a ? bA : bB) + 6 * src, 6 * sizeof(double));
        }
        /* the level of the reduction: Pa, Pb's size (the levers they carry)
         * times the cancellation in D = S^T V S */
        double pm = 0.0, dn = 0.0, dt = 0.0;
        /* Pa, Pb map motions to motions: their entries weighed as the
         * rounding estimate weighs motions (the linear parts by 1/l), so that
         * pm does not depend on the unit of length (src/solve/rounding.c n6m) */
        for (i = 0; i < 36; i++) {
            const int r_lin = i / 6 >= 3, c_lin = i % 6 >= 3;
            const double l = L->m.length > 0.0 ? L->m.length : 1.0, sc = r_lin == c_lin ? 1.0 : r_lin ? 1.0 / l : l;
            pm = fmax(pm, fmax(fabs(Pa[i]), fabs(Pb[i])) * sc);
        }
        for (r = 0; r < d; r++) {
            dn += D[7 * r];
            for (i = 0; i < 6; i++) dt += fabs(S[i * d + r] * VS[i * d + r]);
        }
        rounding_node(L, n, U, G2, NULL, W, beta, Q, NULL, NULL, 0, pm * (dt / dn), bov);
    }
    keep_load_factors(t, n, U, G2, NULL, W, 0);
    return 0;
}

/* Row q of the rows x ncol matrix M has a zero at its pivot column p: the
 * column in (p, end) where row q's entry is largest swapped into p (every
 * row), so the reflection's vector stays within row q's non-zeros and rows
 * with no non-zero in common with it are left exactly as they are. */
static void pivot_column(double *M, int32_t ncol, int32_t q, int32_t rows, int32_t p, int32_t end)
{
    const double *mq = M + (int64_t)q * ncol;
    double best = 0.0;
    int32_t j, r, s = -1;
    for (j = p + 1; j < end; j++)
        if (fabs(mq[j]) > best) {
            best = fabs(mq[j]);
            s = j;
        }
    if (s < 0) return;
    for (r = 0; r < rows; r++) {
        double *mr = M + (int64_t)r * ncol, x = mr[p];
        mr[p] = mr[s];
        mr[s] = x;
    }
}

/* Node n's composite inertia, Lambda and Phi from its children's, for the
 * principal joint's subspace S (6 x d), and the joint's coefficients from the
 * same reduction: with L_k the rows of the relative acceleration across k
 * (T = L_k L_k^T), reflected into [K1 K2] while Tc^T L_k becomes [Lc 0]:
 * E = Lc^-1 Tc^T (W = E^T E = Tc (Tc^T T Tc)^-1 Tc^T), U = Sd^T (1 - K1 E),
 * rho = D^-1-free: -U beta + Sd^T K2 K2^T Sd Q, gamma = W beta + U^T Q, with
 * Sd = S (S^T S)^-1 (docs/math.md, "Accurate Phi"). Returns 0, or -1 when a
 * composite inertia is not positive definite or the joint cannot take a
 * constraint force (Lc singular), -2 when rho came out non-finite from
 * finite factors (the loads overflowed); 1, having written nothing but the composite
 * inertia, when both sides are rigid and rigid_join_wanted: the caller then
 * takes rigid_join (called from there, so that it is not inlined here). */
static int hybrid_phi(aqs_linkage *L, int32_t n, const double *S, int32_t d, const double beta[6],
                      const double *Q)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *P = t->poses + C->poses;
    const pose *J = t->poses + nd_J(C);
    const double *IA = t->data + nd_ic(A);
    const double *LA = t->data + nd_lam(A), *LB = t->data + nd_lam(B);
    double *IC = t->data + nd_ic(C), *LC = t->data + nd_lam(C);
    const int32_t nA = A->nh, nB = B->nh, nh = C->nh, nAo = nA - 1, rA = A->rank, rB = B->rank;
    /* Lambda's row stride (node.lld) is its rank: the structural rank layout() gave it */
    const int32_t ldA = rA, ldB = rB, c = 6 - d, ncol = 6 + rA + rB, orows = 6 * nh;
    /* Columns: [relative rigid mode (6) | A's first jw | B's first jw | A's rest | B's rest]:
     * the children's join blocks (A's handle ka, B's kb) use only their first
     * jw columns, so the constraint and relative rows span the first w columns
     * and the reflections touch only those. */
    const int32_t a6 = A->jw, b6 = B->jw, w = 6 + a6 + b6;
    const int32_t rows = orows + 6; /* outer rows, c constraint rows, d relative rows */
    /* the handle C's parent joins */
    const int32_t jh = C->parent < 0 ? -1 : t->nodes[C->parent].a == n ? t->nodes[C->parent].ka
                                                                        : t->nodes[C->parent].kb;
    /* M: the c constraint rows and the d relative rows first (rel), then the outer rows (X) */
    double *M = t->hscratch, *rel = M, *X = M + (int64_t)6 * ncol, *v = M + (int64_t)rows * ncol;
    double IB[13], Lm[36], ZA[36], ZB[36], Tc[36], Sd[36];
    pose Pk, Pkb, PkbF, *PF = (pose *)(t->hscratch + (int64_t)(6 * t->max_handles + 14) * (12 * t->max_handles + 6));
    int32_t i, j, r, q, ci, rank;

    if (join_frames(t, C, &Pk, &Pkb, IB) != 0) return -1;
    C->grounded = A->grounded || B->grounded;
    memset(IC, 0, 13 * sizeof(double));
    if (!C->grounded) {
        memcpy(IC, IA, 13 * sizeof(double));
        model_mass_add(IC, IB[0], IB + 1, IB + 4);
    }
    /* The relative rigid mode, in square-root form, in the frame F at the
     * centre of mass of the side with the larger mobility (C's axes): there
     * that side's I^-1 = Y Y^T is block diagonal, so its large rotational
     * mobility (a near point mass, a light part) stays out of the
     * translational rows. [Y_A Y_B] is reflected from the right into
     * [Lm 0], Lm Lm^T = I_A^-1 + I_B^-1 (nothing summed or inverted), and
     * Z_A = I_A^-1 Lm^-T = Y_A (Lm^-1 Y_A)^T, Z_B = -Y_B (Lm^-1 Y_B)^T by
     * forward substitution. */
    {
        double G[36], H[27], vr[9], YA[36], YB[36], JA[9], JB[9], cA[3], cB[3], cF[3] = {0, 0, 0};
        double sA = 0.0, sB = 0.0, wa = -1.0, wb = -1.0;
        if (!A->grounded) {
            if (mp_factor(IA, JA, &sA) != 0) return -1;
            wa = mp_y_norm2(JA, sA, IA + 1);
        }
        if (!B->grounded) {
            if (mp_factor(IB, JB, &sB) != 0) return -1;
            wb = mp_y_norm2(JB, sB, IB + 1);
        }
        if (rA == 0 && rB == 0 && !A->grounded && !B->grounded && nh >= 1 && rigid_join_wanted(IA, IB, JA, JB))
            return 1; /* the caller takes rigid_join */
        memcpy(cF, (wa >= wb ? IA : IB) + 1, sizeof cF);
        for (i = 0; i < 3; i++) {
            cA[i] = IA[1 + i] - cF[i];
            cB[i] = IB[1 + i] - cF[i];
        }
        if (A->grounded) memset(YA, 0, sizeof YA);
        else mp_y(JA, sA, cA, YA);
        if (B->grounded) memset(YB, 0, sizeof YB);
        else mp_y(JB, sB, cB, YB);
        for (ci = 0; ci < nh; ci++) { /* the handles and k's child frame, seen from F */
            PF[ci] = P[ci];
            for (i = 0; i < 3; i++) PF[ci].p[i] -= cF[i];
        }
        PkbF = Pkb;
        for (i = 0; i < 3; i++) PkbF.p[i] -= cF[i];
        /* [Y_A Y_B] = [J_A 0 J_B 0; N_A sA 1 N_B sB 1] (N = -S^T J) reflected
         * into [Lm 0] without its zero blocks: rows 0-2 over the columns of
         * J_A and J_B (G, 6 x 6), then rows 3-5 over [sA 1 | what rows 0-2 left
         * in J_B's columns | sB 1] (H, 3 x 9): the same operations, in the same
         * order, as on the full 6 x 12 matrix, less the products with zeros. */
        for (i = 0; i < 6; i++)
            for (j = 0; j < 3; j++) {
                G[6 * i + j] = YA[6 * i + j];
                G[6 * i + 3 + j] = YB[6 * i + j];
            }
        reflect_row_body(G, 6, 0, 6, 0, 0, 6, vr, 0);
        reflect_row_body(G, 6, 1, 6, 1, 1, 6, vr, 0);
        reflect_row_body(G, 6, 2, 6, 2, 2, 6, vr, 0);
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) {
                H[9 * i + j] = i == j ? sA : 0.0;
                H[9 * i + 3 + j] = G[6 * (3 + i) + 3 + j];
                H[9 * i + 6 + j] = i == j ? sB : 0.0;
            }
        reflect_row_body(H, 9, 0, 3, 0, 0, 9, vr, 0);
        reflect_row_body(H, 9, 1, 3, 1, 1, 9, vr, 0);
        reflect_row_body(H, 9, 2, 3, 2, 2, 9, vr, 0);
        memset(Lm, 0, sizeof Lm);
        for (i = 0; i < 3; i++)
            for (j = 0; j <= i; j++) Lm[6 * i + j] = G[6 * i + j];
        for (i = 0; i < 3; i++) {
            for (j = 0; j < 3; j++) Lm[6 * (3 + i) + j] = G[6 * (3 + i) + j];
            for (j = 0; j <= i; j++) Lm[6 * (3 + i) + 3 + j] = H[9 * i + j];
        }
        for (i = 0; i < 6; i++)
            if (!(fabs(Lm[7 * i]) > 0.0) || !isfinite(Lm[7 * i])) return -1;
#ifdef DCA_AVX
        if (t->avx) relative_z_avx(YA, YB, Lm, ZA, ZB);
        else
#endif
#ifdef DCA_SSE2
        { /* the same, A's sums in the low lanes and B's in the high ones */
            __m128d W[36], Y2[36];
            for (i = 0; i < 36; i++) Y2[i] = _mm_loadh_pd(_mm_load_sd(YA + i), YB + i);
            __m128d Lb[36];
            for (i = 0; i < 6; i++) /* Lm broadcast once (its lower triangle) */
                for (r = 0; r <= i; r++) Lb[6 * i + r] = _mm_set1_pd(Lm[6 * i + r]);
            for (j = 0; j < 3; j++)
                for (i = 0; i < 6; i++) {
                    __m128d x = Y2[6 * i + j];
                    for (r = 0; r < i; r++) x = _mm_sub_pd(x, _mm_mul_pd(Lb[6 * i + r], W[6 * r + j]));
                    W[6 * i + j] = _mm_div_pd(x, Lb[7 * i]);
                }
            for (j = 3; j < 6; j++)
                for (i = 3; i < 6; i++) {
                    __m128d x = Y2[6 * i + j];
                    for (r = 3; r < i; r++) x = _mm_sub_pd(x, _mm_mul_pd(Lb[6 * i + r], W[6 * r + j]));
                    W[6 * i + j] = _mm_div_pd(x, Lb[7 * i]);
                }
            for (i = 0; i < 6; i++)
                for (j = 0; j < 6; j++) {
                    const int32_t re = i < 3 || j < 3 ? 3 : 6;
                    __m128d x = _mm_setzero_pd();
                    for (r = 0; r < re; r++) x = _mm_add_pd(x, _mm_mul_pd(Y2[6 * i + r], W[6 * j + r]));
                    _mm_storel_pd(ZA + 6 * i + j, x);
                    _mm_storeh_pd(ZB + 6 * i + j, _mm_xor_pd(x, _mm_set1_pd(-0.0))); /* -sb, sign flipped */
                }
        }
#else
        {
            double Wa[36], Wb[36];
            /* Y's upper right 3x3 block is zero, so are Wa's and Wb's (Lm is
             * lower triangular): left out of the sums (which they do not change) */
            for (j = 0; j < 6; j++)
                for (i = j < 3 ? 0 : 3; i < 6; i++) {
                    double xa = YA[6 * i + j], xb = YB[6 * i + j];
                    for (r = j < 3 ? 0 : 3; r < i; r++) {
                        xa -= Lm[6 * i + r] * Wa[6 * r + j];
                        xb -= Lm[6 * i + r] * Wb[6 * r + j];
                    }
                    Wa[6 * i + j] = xa / Lm[7 * i];
                    Wb[6 * i + j] = xb / Lm[7 * i];
                }
            for (i = 0; i < 6; i++)
                for (j = 0; j < 6; j++) {
                    const int32_t re = i < 3 || j < 3 ? 3 : 6;
                    double sa = 0.0, sb = 0.0;
                    for (r = 0; r < re; r++) {
                        sa += YA[6 * i + r] * Wa[6 * j + r];
                        sb += YB[6 * i + r] * Wb[6 * j + r];
                    }
                    ZA[6 * i + j] = sa;
                    ZB[6 * i + j] = -sb;
                }
        }
#endif
    }
    /* (M is not cleared: every entry the reflections and the coefficients read is
     * written below, the other side's columns of the outer rows as zeros; the
     * constraint and relative rows are read only in their first w columns) */
    for (ci = 0; ci < nh; ci++) xform_cols(&PF[ci], ci < nAo ? ZA : ZB, X + (int64_t)6 * ci * ncol, ncol, t->avx);
    /* The children's outer rows, each in its own columns (a piece that is empty, a rigid
     * side's or a factor's rest past its join block, is skipped: a memcpy of no bytes still
     * costs its call, 2 % of an adaptive step). */
    for (i = 0, ci = 0; i < nA; i++) {
        const double *la;
        double *m;
        if (i == C->ka) continue;
        la = LA + (int64_t)6 * i * ldA;
        m = X + (int64_t)6 * ci * ncol;
        for (r = 0; r < 6; r++) {
            double *mr = m + (int64_t)r * ncol;
            if (a6 > 0) memcpy(mr + 6, la + (int64_t)r * ldA, sizeof(double) * (size_t)a6);
            for (j = 6 + a6; j < w; j++) mr[j] = 0.0;
            if (rA > a6) memcpy(mr + w, la + (int64_t)r * ldA + a6, sizeof(double) * (size_t)(rA - a6));
            for (j = w + rA - a6; j < ncol; j++) mr[j] = 0.0;
        }
        ci++;
    }
    for (i = 0; i < nB; i++) {
        const double *lb;
        double *m;
        if (i == C->kb) continue;
        lb = LB + (int64_t)6 * i * ldB;
        m = X + (int64_t)6 * ci * ncol;
        for (r = 0; r < 6; r++) {
            double *mr = m + (int64_t)r * ncol;
            for (j = 6; j < 6 + a6; j++) mr[j] = 0.0;
            if (b6 > 0) memcpy(mr + 6 + a6, lb + (int64_t)r * ldB, sizeof(double) * (size_t)b6);
            for (j = w; j < w + rA - a6; j++) mr[j] = 0.0;
            if (rB > b6) memcpy(mr + w + rA - a6, lb + (int64_t)r * ldB + b6, sizeof(double) * (size_t)(rB - b6));
        }
        ci++;
    }
    /* The relative acceleration across k (B's minus A's), in k's child frame. */
    xform_cols(&PkbF, Lm, rel, ncol, t->avx);
    for (r = 0; r < 6; r++)
        for (j = 0; j < 6; j++) rel[ncol * r + j] = -rel[ncol * r + j];
    j = 0;
#ifdef DCA_AVX
    if (t->avx) {
        xform_cols_neg_avx(J, LA + (int64_t)6 * C->ka * ldA, ldA, a6, rel + 6, ncol);
        j = a6;
    }
#endif
    for (; j < a6; j++) {
        double col[6], o[6];
        for (r = 0; r < 6; r++) col[r] = LA[(int64_t)(6 * C->ka + r) * ldA + j];
        spatial_xform_motion(J, col, o);
        for (r = 0; r < 6; r++) rel[ncol * r + 6 + j] = -o[r];
    }
    for (r = 0; r < 6; r++)
        if (b6 > 0) memcpy(rel + ncol * r + 6 + a6, LB + (int64_t)(6 * C->kb + r) * ldB, sizeof(double) * (size_t)b6);
    /* Sd = S (S^T S)^-1 */
    {
        double StS[36], StSi[36];
        for (i = 0; i < d; i++)
            for (j = 0; j < d; j++) {
                double x = 0.0;
                for (r = 0; r < 6; r++) x += S[r * d + i] * S[r * d + j];
                StS[d * i + j] = x;
            }
        if (d == 1 && StS[0] == 1.0) { /* a unit axis: (S^T S)^-1 = 1 exactly, as dense_spd_inverse gives it */
            for (i = 0; i < 6; i++) Sd[i] = 0.0 + S[i];
        } else {
            if (dense_spd_inverse(StS, StSi, d) != 0) return -1;
            for (i = 0; i < 6; i++)
                for (j = 0; j < d; j++) {
                    double x = 0.0;
                    for (r = 0; r < d; r++) x += S[i * d + r] * StSi[d * r + j];
                    Sd[i * d + j] = x;
                }
        }
    }
    /* In place, column by column: the c constraint rows Tc^T L_k, then the d
     * rows Sd^T L_k (all the joint's coefficients read of the reflected L_k). */
    {
        const int32_t h = complement(S, d, Tc);
        /* the non-zero weights of each new row (a revolute or prismatic joint's
         * Tc and Sd are mostly zeros; skipping them changes no sum) */
        double wt[36];
        int32_t nz[6], ix[36];
        if (h >= 0 && Sd[3 - h] == 0.0 && Sd[4 - h] == 0.0 && Sd[5 - h] == 0.0) {
            /* complement's revolute or prismatic axis in rows h .. h+2, and Sd
             * there too: columns 0, 1 and Sd have their non-zeros in those rows,
             * columns 2-4 one 1.0 each in the other half (the same tables) */
            for (q = 0; q < 6; q++) {
                nz[q] = 0;
                if (q >= 2 && q < 5) {
                    wt[6 * q] = Tc[6 * (3 - h + q - 2) + q];
                    ix[6 * q] = 3 - h + q - 2;
                    nz[q] = 1;
                    continue;
                }
                for (r = h; r < h + 3; r++) {
                    const double x = q < c ? Tc[6 * r + q] : Sd[r];
                    if (x == 0.0) continue;
                    wt[6 * q + nz[q]] = x;
                    ix[6 * q + nz[q]++] = r;
                }
            }
        } else
            for (q = 0; q < 6; q++) {
                nz[q] = 0;
                for (r = 0; r < 6; r++) {
                    const double x = q < c ? Tc[6 * r + q] : Sd[r * d + q - c];
                    if (x == 0.0) continue;
                    wt[6 * q + nz[q]] = x;
                    ix[6 * q + nz[q]++] = r;
                }
            }
        j = 0;
#ifdef DCA_SSE2
        if (nz[0] == 1 && nz[1] == 1 && nz[2] == 1 && nz[3] == 1 && nz[4] == 1 && nz[5] == 1) {
            /* an axis-aligned S (each new row one weighted row): the loop below
             * with its weights kept broadcast and its sums of one term written out */
            __m128d wq[6];
            const __m128d zero = _mm_setzero_pd();
#ifdef DCA_AVX
            if (t->avx) {
                project_axis_avx(rel, ncol, w, wt, ix);
                j = w;
            }
#endif
            for (q = 0; q < 6; q++) wq[q] = _mm_set1_pd(wt[6 * q]);
            for (; j + 1 < w; j += 2) {
                __m128d col[6];
                for (r = 0; r < 6; r++) col[r] = _mm_loadu_pd(rel + ncol * r + j);
                for (q = 0; q < 6; q++) _mm_storeu_pd(rel + ncol * q + j, _mm_add_pd(zero, _mm_mul_pd(wq[q], col[ix[6 * q]])));
            }
        }
        for (; j + 1 < w; j += 2) { /* two columns at a time, each sum as below */
            __m128d col[6];
            for (r = 0; r < 6; r++) col[r] = _mm_loadu_pd(rel + ncol * r + j);
            for (q = 0; q < 6; q++) {
                __m128d x = _mm_setzero_pd();
                for (r = 0; r < nz[q]; r++) x = _mm_add_pd(x, _mm_mul_pd(_mm_set1_pd(wt[6 * q + r]), col[ix[6 * q + r]]));
                _mm_storeu_pd(rel + ncol * q + j, x);
            }
        }
#endif
        for (; j < w; j++) {
            double col[6];
            for (r = 0; r < 6; r++) col[r] = rel[ncol * r + j];
            for (q = 0; q < 6; q++) {
                double x = 0.0;
                for (r = 0; r < nz[q]; r++) x += wt[6 * q + r] * col[ix[6 * q + r]];
                rel[ncol * q + j] = x;
            }
        }
    }
    /* (the rows above q are reduced already: zero from column q on) */
    for (q = 0; q < c; q++) {
        if (M[(int64_t)q * ncol + q] == 0.0) pivot_column(M, ncol, q, rows, q, w);
        reflect_row(M, ncol, q, rows, q, q, w, v, t->avx);
    }
    {
        /* b of the outer handles, in C's handle order */
        double *bo = v + ncol, *kq = bo + orows; /* after the reflection vector */
        const double *bA = t->data + A->bv, *bB = t->data + B->bv;
        for (i = 0, ci = 0; i < nA; i++)
            if (i != C->ka) memcpy(bo + 6 * ci++, bA + 6 * i, 6 * sizeof(double));
        for (i = 0; i < nB; i++)
            if (i != C->kb) memcpy(bo + 6 * ci++, bB + 6 * i, 6 * sizeof(double));
        const int e = joint_coefficients(L, n, Sd, d, Tc, X, rel, rel + (int64_t)c * ncol, ncol, w, beta, Q, bo, kq);
        if (e != 0) return e;
    }
    /* Lambda_C: X2 as it is while it has at most 6nh columns (the subassembly's
     * internal dofs), else compressed to lower-trapezoidal form by reflections:
     * then handle 0's rows use only the first 6 columns (the parent's join
     * block, when it is handle 0, for the parent's reflections). */
    rank = ncol - c;
    C->jw = rank;
    if (rank > orows) {
        /* A's outer rows are zero in B's last rB - b6 columns (Lambda_B's rest,
         * which no constraint reflection touched), and each of their
         * reflections keeps those zeros in every row: A's rows are reflected
         * without them (the same results, fewer products with zeros) */
        const int32_t endA = ncol - (rB - b6);
        for (i = 0; i < orows; i++) {
            const int32_t end = i < 6 * nAo ? endA : ncol;
            if (X[(int64_t)i * ncol + c + i] == 0.0) pivot_column(X, ncol, i, orows, c + i, end);
            reflect_row(X, ncol, i, orows, i, c + i, end, v, t->avx);
        }
        rank = orows;
        C->jw = jh == 0 && orows >= 6 ? 6 : rank;
    }
    for (r = 0; r < orows; r++)
        memcpy(LC + (int64_t)r * rank, X + (int64_t)r * ncol + c, sizeof(double) * (size_t)rank);
    C->rank = rank;
    return 0;
}

int dca_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *q = L->q + jd->qoff, *Q = L->tau + jd->voff;
    const pose *J = t->poses + nd_J(C);
    double *S = t->data + nd_S(C);
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    double beta[6], bk[6];
    int32_t i;

    if (t->lf) t->lfok[n] = 0; /* kept again by a successful update (keep_load_factors) */
    if (L->dca_form == AQS_DCA_FORM_PHI) return dca_phi_node_update(L, n);
    /* J = J(q_k), refreshed by frames_node; X = spatial_from_parent(J)
     * maps k's joint frame to its child frame. */
    joint_subspace_aligned(jd, q, S); /* the aligned frames (joint.h) */
    spatial_xform_motion(J, bA + 6 * C->ka, bk); /* b^A_k in the child frame */
    for (i = 0; i < 6; i++) beta[i] = bk[i] - bB[6 * C->kb + i];
    i = hybrid_phi(L, n, S, C->d, beta, Q);
    return i == 1 ? rigid_join(L, n, S, C->d, beta, Q) : i;
}

/* M W g = (W M^T)^T g = FX^T g. */
void dca_mw_apply(const aqs_linkage *L, int32_t n, const double g[6], double *out)
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const double *FX = t->data + nd_W(C);
    const int32_t rows = 6 * C->nh;
    int32_t i = 0;
#ifdef DCA_SSE2
    { /* entries i and i + 1 (adjacent in each row of FX) in the two lanes, each sum as below */
        const __m128d g0 = _mm_set1_pd(g[0]), g1 = _mm_set1_pd(g[1]), g2 = _mm_set1_pd(g[2]), g3 = _mm_set1_pd(g[3]),
                      g4 = _mm_set1_pd(g[4]), g5 = _mm_set1_pd(g[5]);
        for (; i + 1 < rows; i += 2) {
            const double *f = FX + i;
            __m128d x = _mm_mul_pd(_mm_loadu_pd(f), g0);
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(f + rows), g1));
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(f + 2 * rows), g2));
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(f + 3 * rows), g3));
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(f + 4 * rows), g4));
            x = _mm_add_pd(x, _mm_mul_pd(_mm_loadu_pd(f + 5 * rows), g5));
            _mm_storeu_pd(out + i, x);
        }
    }
#endif
    for (; i < rows; i++)
        out[i] = FX[i] * g[0] + FX[rows + i] * g[1] + FX[2 * rows + i] * g[2] + FX[3 * rows + i] * g[3] +
                 FX[4 * rows + i] * g[4] + FX[5 * rows + i] * g[5];
}

/* Row r of U M^T = QX. */
void dca_um_row(const aqs_linkage *L, int32_t n, int32_t r, double *out)
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const int32_t rows = 6 * C->nh;
    memcpy(out, t->data + nd_U(C) + (int64_t)r * rows, sizeof(double) * (size_t)rows);
}

/* (Phi x + b) from node n's stored handle forces x, every handle in its own
 * frame: Phi = G I^-1 G^T + Lambda Lambda^T (square-root form; I^-1 = 0 when
 * grounded). Returns 0, or -1 when the mass properties have no inverse. */
int dca_handle_accels(const aqs_linkage *L, int32_t n, double *a)
{
    return dca_handle_accels_mag(L, n, a, NULL);
}

int dca_handle_accels_mag(const aqs_linkage *L, int32_t n, double *a, double *mag)
{
    const tree *t = &L->t;
    const node *nd = &t->nodes[n];
    const double *b = t->data + nd->bv, *x = t->data + nd_xf(nd);
    const pose *P = t->poses + nd->poses;
    const int32_t rows = 6 * nd->nh;
    int32_t i, j, c;
    memcpy(a, b, (size_t)rows * sizeof(double));
    if (mag)
        for (i = 0; i < rows; i++) mag[i] = fabs(b[i]);
    if (!nd->grounded) {
        double w[6] = {0, 0, 0, 0, 0, 0}, tmp[6], acc[6], Y[36];
        for (j = 0; j < nd->nh; j++) {
            spatial_xform_force_back(&P[j], x + 6 * j, tmp);
            for (i = 0; i < 6; i++) w[i] += tmp[i];
        }
        if (mp_inverse_factor(t->data + nd_ic(nd), Y) == 0) {
            dense_tmatvec6(Y, w, tmp);
            dense_matvec6(Y, tmp, acc);
        } else if (nd->joint < 0) {
            model_inverse_apply(L, nd->comp, w, acc);
        } else {
            return -1;
        }
        for (j = 0; j < nd->nh; j++) {
            spatial_xform_motion(&P[j], acc, tmp);
            for (i = 0; i < 6; i++) a[6 * j + i] += tmp[i];
            if (mag)
                for (i = 0; i < 6; i++) mag[6 * j + i] += fabs(tmp[i]);
        }
    }
    for (c = 0; c < nd->rank; c++) {
        const double *lam = t->data + nd_lam(nd) + c;
        double s = 0.0, sa = 0.0;
        for (i = 0; i < rows; i++) s += lam[(int64_t)i * nd->lld] * x[i];
        for (i = 0; i < rows; i++) a[i] += lam[(int64_t)i * nd->lld] * s;
        if (mag) {
            for (i = 0; i < rows; i++) sa += fabs(lam[(int64_t)i * nd->lld] * x[i]);
            for (i = 0; i < rows; i++) mag[i] += fabs(lam[(int64_t)i * nd->lld]) * sa;
        }
    }
    return 0;
}

/* Node n's outputs to its children from C's handle forces x and the joint's
 * constraint force f: A's handles but ka and B's but kb take theirs from x
 * in order, A's ka gets -X_J^T f, B's kb gets f. */
static inline DCA_INLINE void hand_out(aqs_linkage *L, const node *C, const double *x, const double *f)
{
    tree *t = &L->t;
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *J = (t->poses + nd_J(C));
    double *xA = t->data + nd_xf(A), *xB = t->data + nd_xf(B), tmp[6];
    int32_t nA = A->nh, nB = B->nh, i, ci;
    for (i = 0, ci = 0; i < nA; i++) {
        if (i == C->ka) continue;
        memcpy(xA + 6 * i, x + 6 * ci, 6 * sizeof(double));
        ci++;
    }
    spatial_xform_force_back(J, f, tmp);
    for (i = 0; i < 6; i++) xA[6 * C->ka + i] = -tmp[i];
    for (i = 0; i < nB; i++) {
        if (i == C->kb) continue;
        memcpy(xB + 6 * i, x + 6 * ci, 6 * sizeof(double));
        ci++;
    }
    memcpy(xB + 6 * C->kb, f, 6 * sizeof(double));
}

void dca_node_backsub(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *x = t->data + nd_xf(C), *FX = t->data + nd_W(C), *QX = t->data + nd_U(C);
    const double *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C);
    double *qdd = L->qdd + jd->voff, *f = L->cforce + 6 * L->m.eff_joint[C->joint];
    int32_t i, k, d = C->d, rows = 6 * C->nh;

    /* qdd = rho - QX x, f = gamma + FX x (x: C's handle forces) */
    for (i = 0; i < d; i++) {
        const double *qr = QX + (int64_t)i * rows;
        double s = rho[i];
        for (k = 0; k < rows; k++) s -= qr[k] * x[k];
        qdd[i] = s;
    }
    for (i = 0; i < 6; i++) {
        const double *fr = FX + (int64_t)i * rows;
        double s = gamma[i];
        for (k = 0; k < rows; k++) s += fr[k] * x[k];
        f[i] = s;
    }
    hand_out(L, C, x, f);
}

void dca_node_backsub_sums(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    const int32_t j = L->m.eff_joint[C->joint];
    const double *x = t->data + nd_xf(C);
    double *f = L->cforce + 6 * j;
    rounding_backsub_products(L, n, x, L->qdd + L->joints[j].voff, f);
    hand_out(L, C, x, f);
}

/* Acceleration minus g (root trick) of a composite, in its frame, from its
 * leaf's handle forces x: a' = I^{-1} (f + sum_h X_h^T x_h). The world's is -g. */
static void comp_acceleration(const aqs_linkage *L, int32_t c, const double *x, double a[6])
{
    const tree *t = &L->t;
    const node *nd;
    const pose *P;
    double f[6], tmp[6];
    int32_t h, i;
    if (c == L->m.ncomp) {
        a[0] = a[1] = a[2] = 0.0;
        for (i = 0; i < 3; i++) a[3 + i] = -L->gravity[i];
        return;
    }
    nd = &t->nodes[t->leaf_of_comp[c]];
    P = t->poses + nd->poses; /* not the world leaf's: its own frame */
    memcpy(f, L->m.comp_force + 6 * c, sizeof f);
    for (h = 0; h < nd->nh; h++) {
        spatial_xform_force_back(&P[h], x + 6 * h, tmp);
        for (i = 0; i < 6; i++) f[i] += tmp[i];
    }
    model_inverse_apply(L, c, f, a);
}

/* Newton's law on each welded subtree S hanging from fixed joint j:
 * f_j = sum_{i in S} (I_i a'_i - f_i) + sum_{joints e leaving S} f_e,
 * accumulated children first in the composite's frame (MATH.md §2). The
 * forces f_e of the moving joints held by the composite come from its
 * leaf's handle forces (f_e = -x_h in e's joint frame), so only the leaf's
 * forces are needed. */
void dca_welded_forces_comp(aqs_linkage *L, int32_t c, const double *x)
{
    const model *m = &L->m;
    const tree *t = &L->t;
    const node *leaf = &t->nodes[t->leaf_of_comp[c]];
    const pose *P = t->poses + leaf->poses;
    double *acc = L->welded_acc, ca[6];
    int32_t k, h, i, first = m->member_start[c], last = m->member_start[c + 1];
    pose Pc;
    int have_pose = 0;
    comp_acceleration(L, c, x, ca);
    for (k = first; k < last; k++) memset(acc + 6 * m->members[k], 0, 6 * sizeof(double));
    for (h = 0; h < leaf->nh; h++) {
        int32_t e = t->handles[leaf->handles + h], p = L->joints[m->eff_joint[e]].parent;
        double fe[6], fc[6];
        if (m->eff_child[e] == c || p < 0) continue; /* the composite's own parent joint */
        for (i = 0; i < 6; i++) fe[i] = -x[6 * h + i];
        if (c == m->ncomp) { /* the world leaf's poses are in world_frame */
            pose Ph;
            frames_leaf_handle(L, t->leaf_of_comp[c], h, &Ph);
            spatial_xform_force_back(&Ph, fe, fc);
        } else {
            spatial_xform_force_back(&P[h], fe, fc);
        }
        for (i = 0; i < 6; i++) acc[6 * p + i] += fc[i];
    }
    for (k = last - 1; k >= first; k--) {
        int32_t b = m->members[k], pj = m->parent_joint[b];
        const joint_def *jd = &L->joints[pj];
        double Ib[36], Ic[36], w[6];
        pose B;
        kin_body_in_comp(L, b, &B);
        model_body_inertia(L, b, Ib);
        spatial_inertia_to_parent(&B, Ib, Ic);
        dense_matvec6(Ic, ca, w);
        for (i = 0; i < 6; i++) acc[6 * b + i] += w[i];
        if (L->load_slot[b] >= 0) {
            double fb[6];
            if (!have_pose) {
                frames_comp_world(L, c, &Pc);
                have_pose = 1;
            }
            frames_load_in_comp(L, b, &Pc, fb);
            for (i = 0; i < 6; i++) acc[6 * b + i] -= fb[i];
        }
        if (jd->type != AQS_JOINT_FIXED) continue;
        /* In b's frame about its origin. */
        spatial_force_from_parent(&B, acc + 6 * b, L->cforce + 6 * pj);
        if (jd->parent >= 0)
            for (i = 0; i < 6; i++) acc[6 * jd->parent + i] += acc[6 * b + i];
    }
}
