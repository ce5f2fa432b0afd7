/* rounding.c -- a running estimate of the DCA's rounding error in the joint
 * accelerations (docs/math.md, "The rounding term"; issue 12, item 2).
 *
 * Model: a quantity the DCA computes as a sum carries an error of u times a
 * relative level times the magnitude of its terms. Levels go up the tree with
 * the node update (per node, in tree.rnd_node: RND_K/KB/RHO/GAM/SUB below):
 *   rk   of the reduced factors (U, E, QX, FX): max over the children +
 *        RND_G0 + the pivot ratio of Lc (the square root of the mobility
 *        across the joint's constrained directions: a near point mass or a
 *        tiny base makes it large) + the square root of the children's mass
 *        ratio (heavy and light parts in one factor: their rows' norms go
 *        like 1/sqrt(mass), docs/math.md 4a);
 *   rkb  of b: carried through beta = X b^A_k - b^B_k and through
 *        b_C = b_o + X1 E beta + X2 K2^T Sd Q with their cancellation ratios
 *        (largest term / result, from the terms' actual norms);
 *   rerho, regam: absolute errors of rho = -U beta + G2 Q and
 *        gamma = W beta + U^T Q, F u max(rk, level of beta) times their
 *        entrywise product sums.
 * The back-substitution goes down with absolute errors of the handle forces
 * (per handle, tree.rnd_x): f = gamma + FX x gets e(gamma), each handle's
 * relative error times its share |FX_h x_h|, and F u rk (|gamma| + sum |FX_h
 * x_h|); the child's handle k inherits f's error, the others keep theirs. The
 * joint's acceleration qdd = rho - QX x then has
 *   e(qdd) = e(rho) + sum_h e(x_h)/|x_h| |QX_h x_h| + F u rk sum |QX_ik x_k|
 *            + (for the parent side A) | |QX_A| e_t |,
 * F = RND_SAFETY, e_t the componentwise rounding of the transform x_A = -X^T f
 * (transport_error: it does not keep f's direction; for queued subtrees the
 * same of gamma goes into RND_SUB). A carried level grows by a cancellation
 * ratio r only past RND_R0 (terms of similar size that combine do not all
 * err the same way);
 * the sum's own rounding adds RND_G0 r. A first-order estimate with a safety
 * factor, not a theorem: tests/reference/hardcases.cpp checks it against the
 * quad reference on every family at every eps 2^-1 .. 2^-30. */
#include "rounding.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "worldbound.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#define RND_SSE2 1
#endif
/* AVX for gamma's entrywise sums (as src/solve/dca.c's kernels: a function
 * attribute, run where the tree's flag says the processor has AVX; "avx",
 * not "fma": every lane rounds as the scalar code) */
#if defined(RND_SSE2) && defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define RND_AVX 1
#define RND_TARGET_AVX __attribute__((target("avx")))
#endif

/* A node's levels in tree.rnd_node (RND_NODE_LEVELS per node). */
enum { RND_K, RND_KB, RND_RHO, RND_GAM, RND_SUB, RND_TQ, RND_KP };
#define RN(t, nd) ((t)->rnd_node + RND_NODE_LEVELS * ((nd) - (t)->nodes))

#define RND_G0 2.0
/* joint_error keeps the handles' |x_h| of its first loop for its second up to this many handles */
#define AQS_JE_MAXH 16
#define RND_R0 8.0
/* bside_entry_error: a parent composite this many times heavier than the child */
#define RND_HEAVY 1e3

static double maxd(double a, double b) { return a > b ? a : b; }
/* sqrt of a sum of squares (>= 0 or NaN): the instruction itself, without
 * the test for a negative argument (errno) the library call brings. */
static double sqrtn(double x)
{
#ifdef RND_SSE2
    const __m128d v = _mm_set_sd(x);
    return _mm_cvtsd_f64(_mm_sqrt_sd(v, v));
#else
    return sqrt(x);
#endif
}
/* Norms of spatial vectors with their linear and angular parts weighed by
 * the linkage's length scale l (model.length; il = 1/l): a motion vector
 * [w; v] as |(w, v/l)|, a force vector [n; f] as |(n/l, f)|. Each then
 * scales by one factor under a change of the unit of length, so the ratios
 * below (cancellations, relative errors) do not depend on it; the plain
 * 6-norm let the linear parts (motion) or the torques (force) dominate in
 * millimetres and the other parts in kilometres, and moved the estimate by
 * 200-600x (docs/math.md §10a, "The unit of length"). */
static double inv_length(const aqs_linkage *L) { return L->m.length > 0.0 ? 1.0 / L->m.length : 1.0; }
#if defined(__GNUC__)
#define RND_INLINE __attribute__((always_inline)) /* n6m, n6f: called per handle and term */
#else
#define RND_INLINE
#endif
static inline RND_INLINE double n6m(const double *v, double il)
{
    const double x = v[3] * il, y = v[4] * il, z = v[5] * il;
    return sqrtn(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + x * x + y * y + z * z);
}
static inline RND_INLINE double n6f(const double *f, double il)
{
    const double x = f[0] * il, y = f[1] * il, z = f[2] * il;
    return sqrtn(x * x + y * y + z * z + f[3] * f[3] + f[4] * f[4] + f[5] * f[5]);
}
/* max(1, terms / result): the growth of a relative error through a sum */
static double ratio(double terms, double result)
{
    if (!(terms > 0.0)) return 1.0;
    if (!(result > 0.0)) return INFINITY;
    return maxd(1.0, terms / result);
}
/* A level k carried through a sum with cancellation ratio r: the sum's own
 * rounding adds RND_G0 r; the carried error grows by r only where r exceeds
 * RND_R0 (terms of comparable size that combine are not a cancellation: the
 * errors of a sum of a few terms do not all add up in the same direction). */
static double carry(double k, double r) { return k * maxd(1.0, r / RND_R0) + RND_G0 * r; }

/* The level of a sum's carried error: its terms' levels weighted by their
 * norms (a term that is 0 or tiny brings its error, not its level: a
 * grounded handle's b is rounding noise of level 1e17 whose error is
 * 1e-19); 1 when every term is 0. */
static double wlevel(const double *k, const double *a, int n)
{
    double num = 0.0, den = 0.0;
    int i;
    for (i = 0; i < n; i++)
        if (a[i] > 0.0) {
            num += k[i] * a[i];
            den += a[i];
        }
    return den > 0.0 ? num / den : 1.0;
}

#ifdef RND_AVX
/* rounding_node's gamma sum with AVX, its scalar loops' arithmetic lane by
 * lane: E beta's entrywise sums four rows k at a time (the rows' 4 x 6 block
 * transposed so that lane k meets row k's entries in the order of j), then
 * the sums over k and i for j = 0..3 in one register and j = 4, 5 in
 * another, and sgam summed in j's order (each sum times its weight gw[j],
 * as in rounding_node). E: c x 6, U: d x 6. */
RND_TARGET_AVX static double gamma_sum_avx(const double *E, const double *beta, const double *U, const double *Q,
                                           int32_t c, int32_t d, const double *gw)
{
    const __m256d ab = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL)); /* fabs */
    const __m128d ab2 = _mm256_castpd256_pd128(ab);
    __m256d lo = _mm256_setzero_pd();
    __m128d hi = _mm_setzero_pd();
    double eb[6], a6[6], sg = 0.0;
    int32_t i, j, k = 0;
    if (c >= 4) {
        const __m256d ra = _mm256_loadu_pd(E), rb = _mm256_loadu_pd(E + 6), rg = _mm256_loadu_pd(E + 12),
                      rh = _mm256_loadu_pd(E + 18);
        const __m256d t0 = _mm256_unpacklo_pd(ra, rb), t1 = _mm256_unpackhi_pd(ra, rb); /* (a0 b0 a2 b2), (a1 b1 a3 b3) */
        const __m256d t2 = _mm256_unpacklo_pd(rg, rh), t3 = _mm256_unpackhi_pd(rg, rh);
        const __m128d la = _mm_loadu_pd(E + 4), lb = _mm_loadu_pd(E + 10), lg = _mm_loadu_pd(E + 16),
                      lh = _mm_loadu_pd(E + 22);
        __m256d col[6], acc = _mm256_setzero_pd();
        col[0] = _mm256_permute2f128_pd(t0, t2, 0x20); /* (a0 b0 g0 h0) */
        col[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
        col[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
        col[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
        col[4] = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_unpacklo_pd(la, lb)), _mm_unpacklo_pd(lg, lh), 1);
        col[5] = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_unpackhi_pd(la, lb)), _mm_unpackhi_pd(lg, lh), 1);
        for (j = 0; j < 6; j++) acc = _mm256_add_pd(acc, _mm256_and_pd(_mm256_mul_pd(col[j], _mm256_broadcast_sd(beta + j)), ab));
        _mm256_storeu_pd(eb, acc);
        k = 4;
    }
    for (; k < c; k++) {
        double a = 0.0;
        for (j = 0; j < 6; j++) a += fabs(E[6 * k + j] * beta[j]);
        eb[k] = a;
    }
    for (k = 0; k < c; k++) {
        const __m256d e = _mm256_broadcast_sd(eb + k);
        lo = _mm256_add_pd(lo, _mm256_mul_pd(_mm256_and_pd(_mm256_loadu_pd(E + 6 * k), ab), e));
        hi = _mm_add_pd(hi, _mm_mul_pd(_mm_and_pd(_mm_loadu_pd(E + 6 * k + 4), ab2), _mm256_castpd256_pd128(e)));
    }
    for (i = 0; i < d; i++) {
        const __m256d q = _mm256_broadcast_sd(Q + i);
        lo = _mm256_add_pd(lo, _mm256_and_pd(_mm256_mul_pd(_mm256_loadu_pd(U + 6 * i), q), ab));
        hi = _mm_add_pd(hi, _mm_and_pd(_mm_mul_pd(_mm_loadu_pd(U + 6 * i + 4), _mm256_castpd256_pd128(q)), ab2));
    }
    _mm256_storeu_pd(a6, lo);
    _mm_storeu_pd(a6 + 4, hi);
    for (j = 0; j < 6; j++) {
        const double a = a6[j] * gw[j];
        sg += a * a;
    }
    return sg;
}
#endif

static void child_levels(const tree *t, const node *c, double *k, double *kb)
{
    if (c->joint >= 0) {
        *k = RN(t, c)[RND_K];
        *kb = RN(t, c)[RND_KB];
    } else { /* a leaf: data, and b = I^-1 f rounded a few times */
        *k = 1.0;
        *kb = RND_G0;
    }
}

static double transport_error(const aqs_linkage *L, const node *C, const double *f);

void rounding_node(aqs_linkage *L, int32_t n, const double *U, const double *G2, const double *E,
                   const double *W, const double *beta, const double *Q, const double *Lc, const double *Tc,
                   int32_t ncol, double gpiv, const double *bo)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const int32_t d = C->d, c = 6 - d, orows = 6 * C->nh;
    const double *FX = t->data + nd_W(C), *bC = t->data + C->bv, *bB = t->data + B->bv;
    const double fu = RND_SAFETY * RND_U, il = inv_length(L);
    /* gamma is a force: its torques weighed by 1/l, as in n6f */
    const double gw[6] = {il, il, il, 1.0, 1.0, 1.0};
    double kA, kB, kbA, kbB, kappa, kb, kbeta, g = RND_G0, bn, srho = 0.0, sgam = 0.0, xa[6], eb[6];
    int32_t i, j, k, h;

    child_levels(t, A, &kA, &kbA);
    child_levels(t, B, &kB, &kbB);
    if (!Lc) {
        g += gpiv;
    } else if (c > 0) {
        double pmax = 0.0, pmin = INFINITY;
        for (i = 0; i < c; i++) {
            /* constraint row i is Tc's column i applied to the relative
             * acceleration: its linear part weighed by 1/l as in n6m (for a
             * purely angular or linear direction the pivot of the row so
             * weighed, exactly); squared pivots, one square root below */
            const double *tc = Tc + i, lc = Lc[(int64_t)i * ncol + i];
            const double ta = tc[0] * tc[0] + tc[6] * tc[6] + tc[12] * tc[12],
                         tl = (tc[18] * tc[18] + tc[24] * tc[24] + tc[30] * tc[30]) * il * il;
            double p = lc * lc * (ta + tl);
            pmax = maxd(pmax, p);
            if (p < pmin) pmin = p;
        }
        g += pmin > 0.0 ? sqrtn(pmax / pmin) : INFINITY;
    }
    /* heavy and light parts in one node: the square root of the children's
     * mass ratio (their mobilities' norms go like 1/sqrt(mass)) */
    {
        const double mA = t->data[nd_ic(A)], mB = t->data[nd_ic(B)];
        if (!A->grounded && !B->grounded && mA > 0.0 && mB > 0.0) g += sqrtn(maxd(mA / mB, mB / mA));
    }
    kappa = maxd(kA, kB) + g;
    /* beta = X b^A_k - b^B_k: the children's levels weighted by their terms */
    bn = n6m(beta, il);
    for (i = 0; i < 6; i++) xa[i] = beta[i] + bB[6 * C->kb + i];
    {
        const double lv[2] = {kbA, kbB}, nt[2] = {n6m(xa, il), n6m(bB + 6 * C->kb, il)};
        kbeta = maxd(carry(wlevel(lv, nt, 2), ratio(maxd(nt[0], nt[1]), bn)), kappa);
    }
    /* b_C(h) = b_o(h) + X1E_h beta + X2_h K2^T Sd Q with X1 E = -FX^T: the
     * three terms' norms (the last as b_C - b_o - X1E_h beta), b_o at its
     * child's level, the others at beta's and the factors' */
    kb = 1.0;
    for (h = 0; h < C->nh; h++) {
        const double *bch = bC + 6 * h, *boh = bo + 6 * h;
        double v[6], w[6], lv[3], nt[3];
        for (i = 0; i < 6; i++) {
            const int32_t o = 6 * h + i;
            const double *fx = FX + o;
            v[i] = -(fx[0] * beta[0] + fx[orows] * beta[1] + fx[2 * orows] * beta[2] + fx[3 * orows] * beta[3] +
                     fx[4 * orows] * beta[4] + fx[5 * orows] * beta[5]);
            w[i] = bch[i] - boh[i] - v[i];
        }
        lv[0] = h < A->nh - 1 ? kbA : kbB;
        lv[1] = kbeta;
        lv[2] = kappa;
        nt[0] = n6m(boh, il);
        nt[1] = n6m(v, il);
        nt[2] = n6m(w, il);
        kb = maxd(kb, carry(maxd(wlevel(lv, nt, 3), kappa), ratio(maxd(maxd(nt[0], nt[1]), nt[2]), n6m(bch, il))));
    }
    /* rho = -U beta + G2 Q, gamma = E^T (E beta) + U^T Q: entrywise sums;
     * a free joint's rho [dw; dv] as |(dw, dv / l)| (n6m: the world
     * measures, its one reader, docs/math.md §10b) */
    for (i = 0; i < d; i++) {
        double a = 0.0;
        for (j = 0; j < 6; j++) a += fabs(U[6 * i + j] * beta[j]);
        for (j = 0; j < d; j++) a += fabs(G2[d * i + j] * Q[j]);
        if (i >= 3 && L->joints[L->m.eff_joint[C->joint]].type == AQS_JOINT_FREE) a *= il; /* only d = 6 gets here */
        srho += a * a;
    }
#ifdef RND_AVX
    if (E && t->avx) {
        sgam = gamma_sum_avx(E, beta, U, Q, c, d, gw);
    } else
#endif
    if (E) {
        for (k = 0; k < c; k++) {
            double a = 0.0;
            for (j = 0; j < 6; j++) a += fabs(E[6 * k + j] * beta[j]);
            eb[k] = a;
        }
#ifdef RND_SSE2
        { /* two j at a time, each sum as below; sgam summed in j's order */
            const __m128d ab = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL)); /* fabs */
            for (j = 0; j < 6; j += 2) {
                __m128d a = _mm_setzero_pd();
                double a2[2];
                for (k = 0; k < c; k++)
                    a = _mm_add_pd(a, _mm_mul_pd(_mm_and_pd(_mm_loadu_pd(E + 6 * k + j), ab), _mm_set1_pd(eb[k])));
                for (i = 0; i < d; i++)
                    a = _mm_add_pd(a, _mm_and_pd(_mm_mul_pd(_mm_loadu_pd(U + 6 * i + j), _mm_set1_pd(Q[i])), ab));
                _mm_storeu_pd(a2, a);
                a2[0] *= gw[j];
                a2[1] *= gw[j + 1];
                sgam += a2[0] * a2[0];
                sgam += a2[1] * a2[1];
            }
        }
#else
        for (j = 0; j < 6; j++) {
            double a = 0.0;
            for (k = 0; k < c; k++) a += fabs(E[6 * k + j]) * eb[k];
            for (i = 0; i < d; i++) a += fabs(U[6 * i + j] * Q[i]);
            a *= gw[j];
            sgam += a * a;
        }
#endif
    } else { /* the rigid join: W itself */
        for (j = 0; j < 6; j++) {
            double a = 0.0;
            for (k = 0; k < 6; k++) a += fabs(W[6 * j + k] * beta[k]);
            for (i = 0; i < d; i++) a += fabs(U[6 * i + j] * Q[i]);
            a *= gw[j];
            sgam += a * a;
        }
    }
    RN(t, C)[RND_RHO] = fu * kbeta * sqrtn(srho);
    RN(t, C)[RND_GAM] = fu * kbeta * sqrtn(sgam);
    RN(t, C)[RND_K] = kappa;
    RN(t, C)[RND_KB] = kb;
    { /* F u |Kp|: G2 = Kp Kp^T (the joint's mobility), its trace; read by
         * bside_entry_error */
        double tr = 0.0;
        for (i = 0; i < d; i++) tr += G2[d * i + i];
        RN(t, C)[RND_KP] = fu * sqrtn(tr);
    }
    {
        double sub = RN(t, C)[RND_RHO];
        /* and the transport of gamma (C's joint force with its handles free:
         * the loads inside C) into A's joint, for a C whose children stay
         * queued: the back-substitution's own term (RND_TQ) needs the force */
        if (A->joint >= 0) sub = maxd(sub, maxd(RN(t, A)[RND_SUB], transport_error(L, C, t->data + nd_gamma(C))));
        if (B->joint >= 0) sub = maxd(sub, RN(t, B)[RND_SUB]);
        RN(t, C)[RND_SUB] = sub;
    }
}

void rounding_solve_start(aqs_linkage *L)
{
    solve_state *s = &L->s;
    tree *t = &L->t;
    s->rc_sq = s->rc_max = s->rk_max = s->rf_max = s->rfe_max = s->rfn_max = 0.0;
    s->rnd_ok = t->rnd_x != NULL && t->rnd_node != NULL; /* allocated by dca_enable with the coefficients */
}

/* The rounding of x_A = -X_J^T f (dca_node_backsub) for A's handle ka,
 * taken componentwise: each component a sum of three products (3 u |R| |f|),
 * the torques' p x (R f) with its rounding and the error of R f it carries;
 * then what it makes of A's joint acceleration through QX_A's entries,
 * |QX_A| e (returned; A internal: leaves have no joint). The
 * back-substitution puts it into A's RND_TQ with C's force; the node update
 * into C's RND_SUB with gamma, C's force with its handles free, for the
 * joints of a subtree the adaptive solve leaves queued.
 * The relative error of f that joint_error carries goes through the
 * product QX x; this one does not keep f's direction: a large force on a
 * light part on A's side, nearly orthogonal to that part's mobility (a
 * light body between two heavy ones, or between a heavy one and the
 * ground), turns u |f| into an acceleration error however accurate f is
 * (docs/math.md 10a, "The transport of a force"). */
static double transport_error(const aqs_linkage *L, const node *C, const double *f)
{
    const tree *t = &L->t;
    const node *A = &t->nodes[C->a];
    const pose *J = t->poses + nd_J(C);
    const double fu = RND_SAFETY * RND_U, *p = J->p;
    const double *QXa = t->data + nd_U(A);
    const int32_t rows = 6 * A->nh, o = 6 * C->ka;
    double e[6], ol[3], el[3], sq = 0.0;
    int32_t i, r;
    for (i = 0; i < 3; i++) {
        const double *R = J->R + 3 * i;
        ol[i] = fabs(R[0] * f[3] + R[1] * f[4] + R[2] * f[5]);
        el[i] = 3.0 * fu * (fabs(R[0] * f[3]) + fabs(R[1] * f[4]) + fabs(R[2] * f[5]));
        e[3 + i] = el[i];
        e[i] = 3.0 * fu * (fabs(R[0] * f[0]) + fabs(R[1] * f[1]) + fabs(R[2] * f[2]));
    }
    e[0] += 2.0 * fu * (fabs(p[1]) * ol[2] + fabs(p[2]) * ol[1]) + fabs(p[1]) * el[2] + fabs(p[2]) * el[1];
    e[1] += 2.0 * fu * (fabs(p[2]) * ol[0] + fabs(p[0]) * ol[2]) + fabs(p[2]) * el[0] + fabs(p[0]) * el[2];
    e[2] += 2.0 * fu * (fabs(p[0]) * ol[1] + fabs(p[1]) * ol[0]) + fabs(p[0]) * el[1] + fabs(p[1]) * el[0];
    for (r = 0; r < A->d; r++) {
        const double *q = QXa + (int64_t)r * rows + o;
        const double a = fabs(q[0]) * e[0] + fabs(q[1]) * e[1] + fabs(q[2]) * e[2] + fabs(q[3]) * e[3] +
                         fabs(q[4]) * e[4] + fabs(q[5]) * e[5];
        sq += a * a;
    }
    return sqrtn(sq);
}

/* The rounding of QX's entries for the handles C takes from B, where the
 * joint's child composite is light next to its parent composite (at most
 * 1/RND_HEAVY of its mass; the world does not count): QX = -Kp X2^T is read
 * off rows X_o of the stacked matrix after the constraint's reflections, and
 * each such row carries an absolute error of about u ||X_o|| (the
 * reflections keep the rows' norms). An entry that comes out small from a
 * row of large norm is then wrong by about u |Kp| ||X_o||, not by u times
 * itself: a light link between two heavy ones, whose far handle carries the
 * heavy link's weight along the light link (docs/math.md 10a, "The rounding
 * of QX's entries"). ||X_o||^2 is at most the diagonal of B's mobility at
 * that handle, G I^-1 G^T + Lambda Lambda^T (the rigid part from B's mass
 * properties and handle pose; none when B is grounded). Measured: without
 * the light-child condition, or on A's handles, the bound made the
 * estimates of uniform chains in oblique frames 200-1e4x larger and changed
 * no failure (the parent's force there comes from the same rounded rows). */
static double bside_entry_error(const aqs_linkage *L, const node *C, const double *x)
{
    const tree *t = &L->t;
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const int32_t nAo = A->nh - 1, rB = B->rank, pc = L->m.eff_parent[C->joint], cc = L->m.eff_child[C->joint];
    const double *LB = t->data + nd_lam(B), *ic = t->data + nd_ic(B);
    const pose *PB = t->poses + B->poses;
    double Ii[9], sum = 0.0, im = 0.0;
    int32_t ci, k, j, rigid = 0;
    if (B->grounded || pc == L->m.ncomp || C->nh <= nAo) return 0.0; /* no handle from B, or a heavy world */
    {
        const double mp = t->data[nd_ic(&t->nodes[t->leaf_of_comp[pc]])],
                     mc = t->data[nd_ic(&t->nodes[t->leaf_of_comp[cc]])];
        if (!(mc > 0.0) || !(mp > RND_HEAVY * mc)) return 0.0;
    }
    if (ic[0] > 0.0) {
        if (dense_spd_inverse(ic + 4, Ii, 3) != 0) return INFINITY;
        rigid = 1;
        im = 1.0 / ic[0];
    }
    for (ci = nAo; ci < C->nh; ci++) {
        const int32_t i = ci - nAo < C->kb ? ci - nAo : ci - nAo + 1; /* B's handle */
        const double *xh = x + 6 * ci;
        const pose *P = PB + i; /* its pose in B's frame */
        const double dd[3] = {P->p[0] - ic[1], P->p[1] - ic[2], P->p[2] - ic[3]};
        for (k = 0; k < 6; k++) {
            double phi = 0.0;
            if (xh[k] == 0.0) continue;
            for (j = 0; j < rB; j++) {
                const double l = LB[(int64_t)(6 * i + k) * rB + j];
                phi += l * l;
            }
            if (rigid) {
                const int32_t m = k % 3;
                const double tv[3] = {P->R[m], P->R[3 + m], P->R[6 + m]}; /* the handle's axis m */
                double u[3], w[3];
                if (k < 3) { /* a torque about tv: tv^T I^-1 tv */
                    memcpy(u, tv, sizeof u);
                } else { /* a force along tv at the handle: 1/m + (d x tv)^T I^-1 (d x tv) */
                    vec3_cross(dd, tv, u);
                    phi += im;
                }
                mat3_vec(Ii, u, w);
                phi += vec3_dot(u, w);
            }
            sum += sqrtn(phi) * fabs(xh[k]);
        }
    }
    return RN(t, C)[RND_KP] * sum;
}

void rounding_backsub_products(aqs_linkage *L, int32_t n, const double *x, double *qdd, double *f)
{
    tree *t = &L->t;
    double *qa = t->rnd_x + t->nhandles + 1, *qq = qa + 6, *fv = qq + t->max_handles;
    const node *C = &t->nodes[n];
    const double *FX = t->data + nd_W(C), *QX = t->data + nd_U(C);
    const double *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C);
    const int32_t d = C->d, nh = C->nh, rows = 6 * nh;
    int32_t i, h, k;
    for (h = 0; h < nh; h++) qq[h] = 0.0;
    /* each product once: into the running sum (in k's order, as
     * dca_node_backsub, src/solve/dca.c) and into its handle's sums (from the handle's first
     * product, in k's order) */
    for (i = 0; i < d; i++) {
        const double *qr = QX + (int64_t)i * rows;
        double s = rho[i], a = 0.0;
        for (h = 0; h < nh; h++) {
            const double *qh = qr + 6 * h, *xh = x + 6 * h;
            double p = qh[0] * xh[0], q = p, b = fabs(p);
            s -= p;
            for (k = 1; k < 6; k++) {
                p = qh[k] * xh[k];
                s -= p;
                q += p;
                b += fabs(p);
            }
            a += b;
            qq[h] += q * q;
        }
        qdd[i] = s;
        qa[i] = a;
    }
    if (!f) return;
    i = 0;
#ifdef RND_SSE2
    for (; i < 6; i += 2) { /* rows i and i + 1 in the two lanes, each as the loop below */
        const double *fr = FX + (int64_t)i * rows, *gr = fr + rows;
        __m128d sv = _mm_loadu_pd(gamma + i);
        for (h = 0; h < nh; h++) {
            const double *fh = fr + 6 * h, *gh = gr + 6 * h, *xh = x + 6 * h;
            __m128d p = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(fh), gh), _mm_set1_pd(xh[0])), q = p;
            sv = _mm_add_pd(sv, p);
            for (k = 1; k < 6; k++) {
                p = _mm_mul_pd(_mm_loadh_pd(_mm_load_sd(fh + k), gh + k), _mm_set1_pd(xh[k]));
                sv = _mm_add_pd(sv, p);
                q = _mm_add_pd(q, p);
            }
            _mm_storel_pd(fv + 6 * h + i, q);
            _mm_storeh_pd(fv + 6 * h + i + 1, q);
        }
        _mm_storeu_pd(f + i, sv);
    }
#endif
    for (; i < 6; i++) {
        const double *fr = FX + (int64_t)i * rows;
        double s = gamma[i];
        for (h = 0; h < nh; h++) {
            const double *fh = fr + 6 * h, *xh = x + 6 * h;
            double p = fh[0] * xh[0], q = p;
            s += p;
            for (k = 1; k < 6; k++) {
                p = fh[k] * xh[k];
                s += p;
                q += p;
            }
            fv[6 * h + i] = q;
        }
        f[i] = s;
    }
}

/* The estimated error (2-norm) of node n's joint acceleration from its
 * handle forces; with set, also the children's handle-force errors. Only
 * the internal children's are set unless the world measures are active:
 * a leaf's handle-force errors are read by worldbound.c alone (comp_accel,
 * right after its parent is processed), never by joint_error. */
static double joint_error(aqs_linkage *L, int32_t n, int set)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const double *x = t->data + nd_xf(C), *ex = t->rnd_x + C->handles;
    const int32_t d = C->d;
    const double fu = RND_SAFETY * RND_U, ku = fu * RN(t, C)[RND_K], il = inv_length(L);
    const double *qa = t->rnd_x + t->nhandles + 1, *qq = qa + 6, *fv = qq + t->max_handles;
    double sq = 0.0, qe = 0.0, xns[AQS_JE_MAXH];
    int32_t h, i;
    /* qdd_i = rho_i - sum_k QX_ik x_k: the products' magnitudes (rounding and
     * QX's error), and each handle's relative error carried by its share
     * QX_h x_h. With set, the back-substitution (dca_node_backsub_sums) has
     * put the sums by handle there (and FX_h x_h's); else they are summed here. */
    if (!set) {
        double qdd[6];
        rounding_backsub_products(L, n, x, qdd, NULL);
    }
    for (h = 0; h < C->nh; h++) {
        const double xn = n6f(x + 6 * h, il), w = xn > 0.0 ? ex[h] / xn : 0.0;
        if (h < AQS_JE_MAXH) xns[h] = xn;
        qe += w * sqrtn(qq[h]);
    }
    for (i = 0; i < d; i++) sq += qa[i] * qa[i];
    if (set) {
        /* f = gamma + FX x: each handle force's relative error carried by its
         * share FX_h x_h, plus the rounding; the children's handle k gets f
         * (its relative error kept through the transform), the others keep
         * theirs (the order of dca_node_backsub). The joint's own force error
         * and size go into the solve's largest (the adaptive refinement's
         * trigger: the estimate of the accelerations does not cover them). */
        node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
        const int all = worldbound_active(L), setA = all || A->joint >= 0, setB = all || B->joint >= 0;
        if (A->joint >= 0) RN(t, A)[RND_TQ] = transport_error(L, C, L->cforce + 6 * L->m.eff_joint[C->joint]);
        {
            const double fn = n6f(L->cforce + 6 * L->m.eff_joint[C->joint], il);
            double ef = RN(t, C)[RND_GAM], sf = n6f(t->data + nd_gamma(C), il), *exA = t->rnd_x + A->handles,
                   *exB = t->rnd_x + B->handles;
            int32_t ci;
            for (h = 0; h < C->nh; h++) {
                const int32_t o = 6 * h;
                const double xn = h < AQS_JE_MAXH ? xns[h] : n6f(x + o, il);
                double vn;
                if (xn == 0.0) continue;
                vn = n6f(fv + o, il);
                ef += ex[h] / xn * vn;
                sf += vn;
            }
            ef += ku * sf;
            L->s.rfe_max = maxd(L->s.rfe_max, ef);
            L->s.rfn_max = maxd(L->s.rfn_max, fn);
            if (setA) {
                for (i = 0, ci = 0; i < A->nh; i++) {
                    if (i == C->ka) {
                        const double xk = n6f(t->data + nd_xf(A) + 6 * i, il);
                        exA[i] = fn > 0.0 ? ef * maxd(1.0, xk / fn) : ef;
                    } else
                        exA[i] = ex[ci++];
                }
            }
            if (setB)
                for (i = 0, ci = A->nh - 1; i < B->nh; i++) {
                    if (i == C->kb) exB[i] = ef;
                    else exB[i] = ex[ci++];
                }
        }
    }
    qe += bside_entry_error(L, C, x);
    return RN(t, C)[RND_RHO] + RN(t, C)[RND_TQ] + qe + ku * sqrtn(sq);
}

/* A free joint's estimated error as |(dw, dv / l)| (the world measures'
 * e_free, docs/math.md §10b): joint_error's sums with the linear rows
 * divided by l (its RND_RHO is so weighted already, rounding_node). */
#if defined(__GNUC__)
__attribute__((noinline)) /* rare: kept out of rounding_backsub, called per node */
#endif
static double free_joint_error(const aqs_linkage *L, int32_t n)
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const double *x = t->data + nd_xf(C), *QX = t->data + nd_U(C), *ex = t->rnd_x + C->handles;
    const int32_t rows = 6 * C->nh;
    const double ku = RND_SAFETY * RND_U * RN(t, C)[RND_K], il = inv_length(L);
    double a[6] = {0, 0, 0, 0, 0, 0}, sq = 0.0, qe = 0.0;
    int32_t h, i, k;
    for (h = 0; h < C->nh; h++) {
        const double *xh = x + 6 * h;
        const double xn = n6f(xh, il), w = xn > 0.0 ? ex[h] / xn : 0.0;
        double qq = 0.0;
        for (i = 0; i < 6; i++) {
            const double *qr = QX + (int64_t)i * rows + 6 * h;
            double q = 0.0;
            for (k = 0; k < 6; k++) {
                const double p = qr[k] * xh[k];
                a[i] += fabs(p);
                q += p;
            }
            if (i >= 3) q *= il;
            qq += q * q;
        }
        qe += w * sqrtn(qq);
    }
    for (i = 0; i < 6; i++) {
        const double v = i >= 3 ? a[i] * il : a[i];
        sq += v * v;
    }
    return RN(t, C)[RND_RHO] + RN(t, C)[RND_TQ] + qe + ku * sqrtn(sq);
}

void rounding_backsub(aqs_linkage *L, int32_t n, int counted)
{
    solve_state *s = &L->s;
    double e;
    /* the inverse-inertia form's rounding is not estimated (rounding_finish
     * reports it unbounded): nothing to carry */
    if (L->dca_form == AQS_DCA_FORM_PHI) return;
    e = joint_error(L, n, 1);
    s->rk_max = maxd(s->rk_max, RN(&L->t, &L->t.nodes[n])[RND_K]);
    if (counted) {
        s->rc_sq += e * e;
        s->rc_max = maxd(s->rc_max, e);
    } else
        s->rf_max = maxd(s->rf_max, free_joint_error(L, n)); /* a free joint: moves its bodies (world measures) */
}

void rounding_finish(aqs_linkage *L)
{
    solve_state *s = &L->s;
    tree *t = &L->t;
    double ru_sq = 0.0, ru_max = 0.0, kmax = s->rk_max, r2, rmax, tabs, den, tot, T, top = 0.0;
    int valid = s->rnd_ok;
    int32_t i;
    if (t->nnodes == 0) {
        s->rounding = s->rounding_rel = 0.0;
        s->certified = 1;
        return;
    }
    if (L->dca_form == AQS_DCA_FORM_PHI) { /* not estimated in that form: unbounded, uncertified */
        rounding_none(L);
        return;
    }
    if (!s->all)
        for (i = 0; i < s->heap_size; i++) {
            int32_t n = s->heap_item[i];
            const node *nd = &t->nodes[n];
            /* its own joint from its handle forces, or any rho below it */
            double e = maxd(joint_error(L, n, 0), t->rnd_node ? RN(t, nd)[RND_SUB] : 0.0);
            ru_sq += (double)nd->ncount * e * e;
            ru_max = maxd(ru_max, e);
            top = maxd(top, s->heap_key[i]);
            if (t->rnd_node) kmax = maxd(kmax, RN(t, nd)[RND_K]);
        }
    r2 = sqrt(s->rc_sq + ru_sq);
    rmax = maxd(s->rc_max, ru_max);
    T = s->all ? 0.0 : s->bound;
    switch (s->metric) {
    case AQS_METRIC_ABS_LINKAGE: tot = T + r2; break;
    case AQS_METRIC_ABS_JOINT: tot = T + rmax; break;
    case AQS_METRIC_ABS_WORLD:
    case AQS_METRIC_REL_WORLD: {
        /* every joint's estimated error (free ones too: they move bodies)
         * carried to the bodies along their paths (worldbound_rounding);
         * rel_world divides by the reached bodies' accelerations less their
         * own estimated errors (docs/math.md §10b, "Rounding") */
        const double wr = L->wb ? worldbound_rounding(L, sqrt(s->rc_sq + ru_sq), s->rf_max) : INFINITY;
        if (s->metric == AQS_METRIC_ABS_WORLD) tot = T + wr;
        else {
            /* the numerator of error_bound: min(sum E_n, top + sum E_h) */
            tabs = s->all || s->heap_size == 0 ? 0.0 : maxd(fmin(s->sum, top + maxd(s->sum_h, 0.0)), 0.0);
            den = L->wb ? L->wb->lower_r : 0.0;
            if (tabs + wr == 0.0) tot = T;
            else if (den > 0.0) tot = maxd(T, (tabs + wr) / den);
            else tot = INFINITY;
        }
        break;
    }
    case AQS_METRIC_REL_LINKAGE:
        /* ||ref_all|| >= sqrt(A(root)) - r2 */
        tabs = s->all || s->heap_size == 0 ? 0.0 : sqrt(s->sum > 0.0 ? s->sum : 0.0);
        den = s->all ? s->comp_sq : (s->a_root >= 0.0 ? s->a_root : s->comp_sq + s->sum);
        den = sqrt(den > 0.0 ? den : 0.0);
        if (tabs + r2 == 0.0) tot = T;
        else if (den > r2) tot = maxd(T, (tabs + r2) / (den - r2));
        else tot = INFINITY;
        break;
    default: /* REL_JOINT: sqrt(top) / L, max_j ||ref_j|| >= L - rmax */
        tabs = s->all || s->heap_size == 0 ? 0.0 : sqrt(maxd(s->joint_bound == AQS_JOINT_BOUND_SUM ? s->sum : top, 0.0));
        den = s->lower;
        if (tabs + rmax == 0.0) tot = T;
        else if (den > rmax) tot = maxd(T, (tabs + rmax) / (den - rmax));
        else tot = INFINITY;
        break;
    }
    if (!(kmax * RND_SAFETY * RND_U <= RND_KAPPA_MAX) || !isfinite(tot)) valid = 0;
    s->rounding = valid ? maxd(tot - T, 0.0) : INFINITY;
    s->certified = valid && (s->eps == 0.0 || s->rounding <= s->eps);
    /* The same relative to the solution's size in the measure (the rounding
     * fallback's test, api.c): the relative measures are relative already;
     * abs_linkage over the DCA's 2-norm of every counted joint (computed
     * and queued), abs_joint over L (the largest computed joint is at least
     * that), abs_world over the reached bodies' lower bound. */
    {
        double scale;
        switch (s->metric) {
        case AQS_METRIC_ABS_LINKAGE:
            scale = sqrt(s->comp_sq + (s->all ? 0.0 : maxd(s->sum, 0.0)));
            break;
        case AQS_METRIC_ABS_JOINT: scale = maxd(s->lower, sqrt(maxd(top, 0.0))); break;
        case AQS_METRIC_ABS_WORLD: scale = L->wb ? L->wb->lower_r : 0.0; break;
        default: scale = 1.0; break;
        }
        if (!valid) s->rounding_rel = INFINITY;
        else if (s->rounding == 0.0) s->rounding_rel = 0.0;
        else s->rounding_rel = scale > 0.0 ? s->rounding / scale : INFINITY;
    }
}

void rounding_none(aqs_linkage *L)
{
    L->s.rounding = L->s.rounding_rel = INFINITY;
    L->s.certified = 0;
}

double rounding_coeff_level(const aqs_linkage *L, int32_t n)
{
    const tree *t = &L->t;
    return t->rnd_node ? maxd(RN(t, &t->nodes[n])[RND_K], RN(t, &t->nodes[n])[RND_KB]) : 0.0;
}
