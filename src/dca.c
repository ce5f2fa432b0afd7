/* dca.c -- Featherstone's divide-and-conquer articulated-body algorithm for
 * quasi-statics, in the symbols of MATH.md §3. Every handle carries its own
 * frame: the child body frame for the joint a cluster hangs from, the joint
 * frame (fixed in the parent body) for the joints it holds up (§3.6). */
#include "dca.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "model.h"
#include "update.h"

/* Phi is stored block-major: the 6x6 block (i, j) of an nh-handle node is
 * contiguous at 36 (nh i + j), row-major inside. */
static double *blk(double *phi, int32_t nh, int32_t i, int32_t j)
{
    return phi + 36 * ((int64_t)nh * i + j);
}

static const double *cblk(const double *phi, int32_t nh, int32_t i, int32_t j)
{
    return phi + 36 * ((int64_t)nh * i + j);
}

static void transpose6(const double *A, double *T)
{
    int i, j;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) T[6 * j + i] = A[6 * i + j];
}

/* Make block (j, i) the transpose of block (i, j) for i < j, and (when
 * diagonal is set) the diagonal blocks symmetric. */
static void symmetrize_blocks(double *phi, int32_t nh, int diagonal)
{
    int32_t i, j;
    for (i = 0; i < nh; i++) {
        if (diagonal) dense_symmetrize(blk(phi, nh, i, i), 6);
        for (j = i + 1; j < nh; j++) transpose6(blk(phi, nh, i, j), blk(phi, nh, j, i));
    }
}

aqs_status dca_enable(aqs_linkage *L, const char *fn)
{
    tree *t = &L->t;
    int32_t n;
    if (t->data) return AQS_OK;
    t->data = lk_calloc(L, (size_t)t->ndata + 1, sizeof(double));
    if (!t->data)
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory for %lld DCA coefficients", fn,
                       (long long)t->ndata);
    for (n = 0; n < t->nnodes; n++)
        if (t->nodes[n].joint < 0) dca_leaf_phi(L, n);
    /* every b and internal node from scratch, loads and gravity included */
    t->all_dirty = 1;
    L->loads_dirty = L->gravity_dirty = 1;
    return AQS_OK;
}

void dca_leaf_phi(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *nd = &t->nodes[n];
    double *phi = t->data + nd->phi;
    const pose *P = t->poses + nd->poses;
    int32_t i, j;
    nd->rank = 0; /* a rigid group: Phi = G I^-1 G^T exactly, no Lambda */
    nd->grounded = nd->comp == L->m.ncomp;
    if (nd->grounded) {
        memset(phi, 0, sizeof(double) * 36 * nd->nh * nd->nh); /* the world does not move */
        memset(t->data + nd->ic, 0, 36 * sizeof(double));
        return;
    }
    memcpy(t->data + nd->ic, L->m.comp_inertia + 36 * nd->comp, 36 * sizeof(double));
    {
        const double *Iinv = L->m.comp_inverse + 36 * nd->comp;
        double *Y = t->scratch; /* nh blocks X_h I^{-1} */
        double *X = t->scratch + 36 * nd->nh;
        for (i = 0; i < nd->nh; i++) {
            spatial_from_parent(&P[i], X);
            dense_mul66(X, Iinv, Y + 36 * i);
        }
        /* Phi_{hh'} = X_h I^{-1} X_h'^T */
        for (j = 0; j < nd->nh; j++) {
            spatial_from_parent(&P[j], X);
            for (i = 0; i <= j; i++) dense_mul66_nt(Y + 36 * i, X, blk(phi, nd->nh, i, j));
        }
        symmetrize_blocks(phi, nd->nh, 1);
    }
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
        /* Root trick (MATH.md §3.7): the world accelerates by a0 = -g. */
        acc[0] = acc[1] = acc[2] = 0.0;
        acc[3] = -L->gravity[0];
        acc[4] = -L->gravity[1];
        acc[5] = -L->gravity[2];
    } else {
        dense_matvec(L->m.comp_inverse + 36 * nd->comp, L->m.comp_force + 6 * nd->comp, acc, 6, 6);
    }
    for (i = 0; i < nd->nh; i++) {
        spatial_from_parent(&P[i], X);
        dense_matvec(X, acc, b + 6 * i, 6, 6);
    }
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

/* Reflect row r of the row-major A (ld columns) so that its entries in
 * columns p+1 .. ncol-1 vanish (Householder from the right, LAPACK-scaled),
 * applying the reflection to rows r0 .. nrows-1. v: ncol scratch doubles. */
static void reflect_row(double *A, int32_t ld, int32_t r0, int32_t nrows, int32_t r, int32_t p,
                        int32_t ncol, double *v)
{
    const double *x = A + (int64_t)ld * r + p;
    int32_t m = ncol - p, i, j;
    double scale = 0.0, ss = 0.0, alpha, f;
    for (j = 1; j < m; j++)
        if (fabs(x[j]) > scale) scale = fabs(x[j]);
    if (scale == 0.0) return; /* nothing right of the pivot */
    if (fabs(x[0]) > scale) scale = fabs(x[0]);
    for (j = 0; j < m; j++) {
        double y = x[j] / scale;
        ss += y * y;
    }
    alpha = scale * sqrt(ss);
    if (x[0] > 0.0) alpha = -alpha;
    for (j = 0; j < m; j++) v[j] = x[j];
    v[0] -= alpha; /* |v0| = |x0| + ||x||: no cancellation */
    f = -1.0 / (alpha * v[0]); /* 2 / v^T v, since v^T v = -2 alpha v0 */
    for (i = r0; i < nrows; i++) {
        double *a = A + (int64_t)ld * i + p, s = 0.0;
        for (j = 0; j < m; j++) s += a[j] * v[j];
        if (s == 0.0) continue;
        s *= f;
        for (j = 0; j < m; j++) a[j] -= s * v[j];
    }
}

/* Orthonormal basis of the orthogonal complement of the columns of S (6 x d,
 * row-major): columns q = 0 .. 5-d of Tc (row-major 6 x 6, column q). Gram-
 * Schmidt twice over S's columns, then over the unit vectors, taking the
 * largest remaining one each time. */
static void complement(const double *S, int32_t d, double *Tc)
{
    double Q[36], v[6];
    int32_t nq = 0, i, j, k, pass;
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
}

/* Iinv = I^-1 by Cholesky (I symmetric positive definite); -1 if not. */
static int inverse6(const double *I, double *Iinv)
{
    double Cf[36];
    if (dense_cholesky6(I, Cf) != 0) return -1;
    dense_cholesky6_inverse(Cf, Iinv);
    dense_symmetrize(Iinv, 6);
    return 0;
}

/* out (6 x 6) = X_P Z for the motion transform X = spatial_from_parent(P),
 * column by column. */
static void xform_cols(const pose *P, const double *Z, double *out, int32_t ld)
{
    double col[6], o[6];
    int32_t i, j;
    for (j = 0; j < 6; j++) {
        for (i = 0; i < 6; i++) col[i] = Z[6 * i + j];
        spatial_xform_motion(P, col, o);
        for (i = 0; i < 6; i++) out[(int64_t)ld * i + j] = o[i];
    }
}

/* Node n's composite inertia, Lambda and Phi from its children's, for the
 * principal joint's subspace S (6 x d). Returns 0, or -1 when a composite
 * inertia is not positive definite. */
static int hybrid_phi(aqs_linkage *L, int32_t n, const double *S, int32_t d)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *PA = t->poses + A->poses, *PB = t->poses + B->poses, *P = t->poses + C->poses;
    const pose *J = t->poses + C->J;
    const double *IA = t->data + A->ic, *IBb = t->data + B->ic;
    const double *LA = t->data + A->lam, *LB = t->data + B->lam;
    double *IC = t->data + C->ic, *LC = t->data + C->lam, *phi = t->data + C->phi;
    const int32_t nA = A->nh, nB = B->nh, nh = C->nh, nAo = nA - 1, rA = A->rank, rB = B->rank;
    const int32_t ldA = 6 * nA, ldB = 6 * nB, c = 6 - d, ncol = 6 + rA + rB, orows = 6 * nh;
    const int32_t rows = orows + c;
    double *M = t->hscratch, *v = t->hscratch + (int64_t)rows * ncol, *rel = v + ncol;
    double IB[36], IAi[36], IBi[36], Ms[36], Lm[36], Wm[36], ZA[36], ZB[36], Tc[36];
    static const double id6[36] = {1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0,
                                   0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1};
    pose Pk, Pkb;
    int32_t i, j, r, q, ci, rank;

    pose_compose(&PA[C->ka], J, &Pk); /* B's frame in C's (= A's) frame */
    pose_compose(&Pk, &PB[C->kb], &Pkb);
    spatial_inertia_to_parent(&Pk, IBb, IB);
    C->grounded = A->grounded || B->grounded;
    for (i = 0; i < 36; i++) IC[i] = C->grounded ? 0.0 : IA[i] + IB[i];
    if (A->grounded) memset(IAi, 0, sizeof IAi);
    else if (inverse6(IA, IAi) != 0) return -1;
    if (B->grounded) memset(IBi, 0, sizeof IBi);
    else if (inverse6(IB, IBi) != 0) return -1;
    for (i = 0; i < 36; i++) Ms[i] = IAi[i] + IBi[i];
    dense_symmetrize(Ms, 6);
    if (dense_cholesky6(Ms, Lm) != 0) return -1;
    dense_cholesky6_lower_solve(Lm, id6, Wm, 6); /* Wm = Lm^-1 */
    /* Z_A = I_A^-1 Lm^-T, Z_B = -I_B^-1 Lm^-T: the relative rigid mode's columns */
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++) {
            double sa = 0.0, sb = 0.0;
            for (r = 0; r < 6; r++) {
                sa += IAi[6 * i + r] * Wm[6 * j + r];
                sb += IBi[6 * i + r] * Wm[6 * j + r];
            }
            ZA[6 * i + j] = sa;
            ZB[6 * i + j] = -sb;
        }
    memset(M, 0, sizeof(double) * (size_t)rows * (size_t)ncol);
    for (ci = 0; ci < nh; ci++) xform_cols(&P[ci], ci < nAo ? ZA : ZB, M + (int64_t)6 * ci * ncol, ncol);
    for (i = 0, ci = 0; i < nA; i++) {
        if (i == C->ka) continue;
        for (r = 0; r < 6; r++) memcpy(M + (int64_t)(6 * ci + r) * ncol + 6, LA + (int64_t)(6 * i + r) * ldA,
                                       sizeof(double) * (size_t)rA);
        ci++;
    }
    for (i = 0; i < nB; i++) {
        if (i == C->kb) continue;
        for (r = 0; r < 6; r++) memcpy(M + (int64_t)(6 * ci + r) * ncol + 6 + rA, LB + (int64_t)(6 * i + r) * ldB,
                                       sizeof(double) * (size_t)rB);
        ci++;
    }
    /* The relative acceleration across k (B's minus A's), in k's child frame. */
    xform_cols(&Pkb, Lm, rel, ncol);
    for (r = 0; r < 6; r++)
        for (j = 0; j < 6; j++) rel[ncol * r + j] = -rel[ncol * r + j];
    for (j = 0; j < rA; j++) {
        double col[6], o[6];
        for (r = 0; r < 6; r++) col[r] = LA[(int64_t)(6 * C->ka + r) * ldA + j];
        spatial_xform_motion(J, col, o);
        for (r = 0; r < 6; r++) rel[ncol * r + 6 + j] = -o[r];
    }
    for (r = 0; r < 6; r++)
        for (j = 0; j < rB; j++) rel[ncol * r + 6 + rA + j] = LB[(int64_t)(6 * C->kb + r) * ldB + j];
    complement(S, d, Tc);
    for (q = 0; q < c; q++) {
        double *row = M + (int64_t)(orows + q) * ncol;
        for (r = 0; r < 6; r++) {
            double w = Tc[6 * r + q];
            if (w == 0.0) continue;
            for (j = 0; j < ncol; j++) row[j] += w * rel[ncol * r + j];
        }
    }
    for (q = 0; q < c; q++) reflect_row(M, ncol, 0, rows, orows + q, q, ncol, v);
    /* What the outer rows keep right of the c pivots is Lambda_C, compressed
     * to lower-trapezoidal form (at most 6nh columns). */
    rank = ncol - c < orows ? ncol - c : orows;
    for (i = 0; i < rank && i < orows; i++) reflect_row(M, ncol, i, orows, i, c + i, ncol, v);
    for (r = 0; r < orows; r++) {
        for (j = 0; j < rank; j++) LC[(int64_t)r * orows + j] = M[(int64_t)r * ncol + c + j];
    }
    C->rank = rank;
    /* Phi_C = G I_C^-1 G^T + Lambda_C Lambda_C^T as one Gram matrix of the
     * rows [G Lc^-T, Lambda_C] (I_C = Lc Lc^T). */
    {
        const int32_t w = 6 + rank;
        double *R = M; /* orows x w */
        if (C->grounded) {
            for (r = 0; r < orows; r++)
                for (j = 0; j < 6; j++) R[(int64_t)r * w + j] = 0.0;
        } else {
            double Lc[36], Wc[36], WcT[36];
            if (dense_cholesky6(IC, Lc) != 0) return -1;
            dense_cholesky6_lower_solve(Lc, id6, Wc, 6);
            for (i = 0; i < 6; i++)
                for (j = 0; j < 6; j++) WcT[6 * i + j] = Wc[6 * j + i];
            for (ci = 0; ci < nh; ci++) xform_cols(&P[ci], WcT, R + (int64_t)6 * ci * w, w);
        }
        for (r = 0; r < orows; r++)
            for (j = 0; j < rank; j++) R[(int64_t)r * w + 6 + j] = LC[(int64_t)r * orows + j];
        for (ci = 0; ci < nh; ci++)
            for (i = ci; i < nh; i++) {
                double *out = blk(phi, nh, ci, i);
                int32_t a, b2;
                for (a = 0; a < 6; a++)
                    for (b2 = 0; b2 < 6; b2++) {
                        const double *x = R + (int64_t)(6 * ci + a) * w, *y = R + (int64_t)(6 * i + b2) * w;
                        double s = 0.0;
                        for (j = 0; j < w; j++) s += x[j] * y[j];
                        out[6 * a + b2] = s;
                    }
            }
        symmetrize_blocks(phi, nh, 0);
    }
    return 0;
}

/* y = C^{-1} m for the lower-triangular 6x6 factor C (forward substitution). */
static void lower_solve_row6(const double *Cf, const double *m, double *y)
{
    int i, k;
    for (i = 0; i < 6; i++) {
        double v = m[i];
        for (k = 0; k < i; k++) v -= Cf[6 * i + k] * y[k];
        y[i] = v / Cf[7 * i];
    }
}

/* Index among a child's handles of the outer handle at position c of the
 * merged list [A-outer; B-outer]. */
static int32_t child_index(int32_t c, int32_t k)
{
    return c < k ? c : c + 1;
}

/* T = Phi^A_kk + Phi^B_kk is positive definite in exact arithmetic, but at
 * extreme mass ratios rounding can leave it indefinite by a hair (MATH.md
 * §3.8: plain Cholesky failed on 1e12 ratios). Retry with a diagonal shift
 * at the rounding level of T (1e-13, then 1e-11, 1e-9 of its largest
 * diagonal entry): the perturbation is below what the data resolve, while
 * an LU inverse of an indefinite T yields a negative S^T V S and garbage. */
static int guarded_cholesky(const double *T, double *C)
{
    double shifted[36], scale = 0.0, shift;
    int i, k;
    if (dense_cholesky6(T, C) == 0) return 0;
    for (i = 0; i < 6; i++)
        if (fabs(T[7 * i]) > scale) scale = fabs(T[7 * i]);
    for (k = 0, shift = 1e-13 * scale; k < 3; k++, shift *= 100.0) {
        memcpy(shifted, T, sizeof shifted);
        for (i = 0; i < 6; i++) shifted[7 * i] += shift;
        if (dense_cholesky6(shifted, C) == 0) return 0;
    }
    return -1;
}

int dca_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *q = L->q + jd->qoff, *Q = L->tau + jd->voff;
    const pose *J = t->poses + C->J;
    double *Cf = t->data + C->W, *U = t->data + C->U, *VS = t->data + C->VS;
    double *rho = t->data + C->rho, *gamma = t->data + C->gamma, *S = t->data + C->S;
    double *M = t->mscratch, *bC = t->data + C->bv;
    const double *phiA = t->data + A->phi, *phiB = t->data + B->phi;
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    int32_t nA = A->nh, nB = B->nh, ka = C->ka, kb = C->kb, nh = C->nh, d = C->d;
    int32_t nAo = nA - 1, i, j, ci;
    double T[36], Ws[36], D[36], Dinv[36], beta[6], bk[6], tmp[6], Vb[6];

    /* J = J(q_k), refreshed by update_node_poses; X = spatial_from_parent(J)
     * maps k's joint frame to its child frame. */
    joint_subspace(jd, q, S);

    /* T = X Phi^A_kk X^T + Phi^B_kk, with A's k blocks moved into the child
     * frame of k (§3.6); V = T^{-1} is used only through T's Cholesky
     * factor C: V = C^{-T} C^{-1}. */
    spatial_xform_congruence(J, cblk(phiA, nA, ka, ka), T);
    {
        const double *Bkk = cblk(phiB, nB, kb, kb);
        for (i = 0; i < 36; i++) T[i] += Bkk[i]; /* both exactly symmetric: so is T */
    }
    if (guarded_cholesky(T, Cf) != 0) return -1;

    /* M = [Phi^A_ok X^T ; -Phi^B_ok], one 6x6 block per outer handle. */
    for (ci = 0; ci < nAo; ci++) spatial_xform_rows(J, cblk(phiA, nA, child_index(ci, ka), ka), M + 36 * ci);
    for (ci = nAo; ci < nh; ci++) {
        const double *src = cblk(phiB, nB, child_index(ci - nAo, kb), kb);
        for (i = 0; i < 36; i++) M[36 * ci + i] = -src[i];
    }

    spatial_xform_motion(J, bA + 6 * ka, bk); /* b^A_k in the child frame */
    for (i = 0; i < 6; i++) beta[i] = bk[i] - bB[6 * kb + i];
    dense_cholesky6_lower_solve(Cf, beta, tmp, 1);
    dense_cholesky6_upper_solve(Cf, tmp, Vb, 1); /* V beta */

    if (d == 6) {
        /* Free joint: S = I, so U = I, W = 0, gamma = Q, rho = T Q - beta. */
        memset(U, 0, 36 * sizeof(double));
        for (i = 0; i < 6; i++) U[7 * i] = 1.0;
        dense_matvec6(T, Q, rho);
        for (i = 0; i < 6; i++) {
            rho[i] -= beta[i];
            gamma[i] = Q[i];
        }
    } else {
        /* C^{-1} S, V S = C^{-T} C^{-1} S, and D = S^T V S formed as the Gram
         * matrix of C^{-1} S: it cannot lose definiteness to rounding. */
        dense_cholesky6_lower_solve(Cf, S, Ws, d);
        dense_cholesky6_upper_solve(Cf, Ws, VS, d);
        if (d == 1) {
            double Dv = 0.0, sb = 0.0;
            for (i = 0; i < 6; i++) Dv += Ws[i] * Ws[i];
            if (!(Dv > 0.0) || !isfinite(Dv)) return -1;
            Dinv[0] = 1.0 / Dv;
            for (i = 0; i < 6; i++) {
                U[i] = VS[i] * Dinv[0];
                sb += VS[i] * beta[i];
            }
            rho[0] = (Q[0] - sb) * Dinv[0];
            for (i = 0; i < 6; i++) gamma[i] = Vb[i] + VS[i] * rho[0];
        } else {
            dense_mul_tn(Ws, Ws, D, d, 6, d);
            dense_symmetrize(D, d);
            if (dense_spd_inverse(D, Dinv, d) != 0) return -1;
            dense_mul_nt(Dinv, VS, U, d, d, 6); /* U = D^{-1} (V S)^T */
            dense_tmatvec(VS, beta, tmp, 6, d); /* rho = D^{-1} (Q - S^T V beta) */
            for (i = 0; i < d; i++) tmp[i] = Q[i] - tmp[i];
            dense_matvec(Dinv, tmp, rho, d, d);
            /* gamma = W beta + U^T Q = V beta + V S rho, since W = V - V S U */
            dense_matvec(VS, rho, gamma, 6, d);
            for (i = 0; i < 6; i++) gamma[i] += Vb[i];
        }
    }

    /* Phi_C = blkdiag(Phi^A_oo, Phi^B_oo) - M W M^T with
     * M W M^T = (M C^{-T})(M C^{-T})^T - (M V S) D^{-1} (M V S)^T;
     * b_C = [b^A_o; b^B_o] - M gamma. A free joint has W = 0. */
    {
        double *Y = t->scratch, *Z = t->scratch + 36 * nh, *ZD = Z + 6 * nh * 6;
        if (d < 6) {
            for (ci = 0; ci < 6 * nh; ci++) lower_solve_row6(Cf, M + 6 * ci, Y + 6 * ci);
            if (d == 1) {
                for (ci = 0; ci < 6 * nh; ci++) {
                    double z = 0.0;
                    for (j = 0; j < 6; j++) z += M[6 * ci + j] * VS[j];
                    Z[ci] = z;
                    ZD[ci] = z * Dinv[0];
                }
            } else {
                dense_mul(M, VS, Z, 6 * nh, 6, d);   /* Z = M V S */
                dense_mul(Z, Dinv, ZD, 6 * nh, d, d); /* Z D^{-1} */
            }
        }
        if (hybrid_phi(L, n, S, d) != 0) return -1;
        for (ci = 0; ci < nh; ci++) {
            const double *src = ci < nAo ? bA + 6 * child_index(ci, ka) : bB + 6 * child_index(ci - nAo, kb);
            dense_matvec6(M + 36 * ci, gamma, tmp);
            for (i = 0; i < 6; i++) bC[6 * ci + i] = src[i] - tmp[i];
        }
    }
    return 0;
}

/* M W g = M V g - M V S (U g) = Y (C^{-1} g) - ZD (V S)^T g, from the
 * products dca_node_update left in the scratch: Y = M C^{-T} (6nh x 6) and
 * ZD = M V S D^{-1} (6nh x d). */
void dca_mw_apply(const aqs_linkage *L, int32_t n, const double g[6], double *out)
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const double *Y = t->scratch, *ZD = t->scratch + 72 * C->nh, *VS = t->data + C->VS;
    const int32_t rows = 6 * C->nh, d = C->d;
    double u[6], v[6];
    int32_t i, k;
    if (d == 6) {
        for (i = 0; i < rows; i++) out[i] = 0.0;
        return;
    }
    lower_solve_row6(t->data + C->W, g, u);
    for (k = 0; k < d; k++) {
        double s = 0.0;
        for (i = 0; i < 6; i++) s += VS[i * d + k] * g[i];
        v[k] = s;
    }
    if (d == 1) { /* revolute, prismatic: ZD is a column */
        for (i = 0; i < rows; i++) {
            const double *y = Y + 6 * i;
            out[i] = y[0] * u[0] + y[1] * u[1] + y[2] * u[2] + y[3] * u[3] + y[4] * u[4] + y[5] * u[5] -
                     ZD[i] * v[0];
        }
        return;
    }
    for (i = 0; i < rows; i++) {
        const double *y = Y + 6 * i, *zd = ZD + (int64_t)i * d;
        double s = y[0] * u[0] + y[1] * u[1] + y[2] * u[2] + y[3] * u[3] + y[4] * u[4] + y[5] * u[5];
        for (k = 0; k < d; k++) s -= zd[k] * v[k];
        out[i] = s;
    }
}

/* (U M^T)_{r,i} = (M V S D^{-1})_{i,r} = ZD_{i,r} (U = D^{-1} (V S)^T, D
 * symmetric); a free joint has U = I: M's column r. */
void dca_um_row(const aqs_linkage *L, int32_t n, int32_t r, double *out)
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const int32_t rows = 6 * C->nh, d = C->d;
    int32_t i;
    if (d == 6) {
        for (i = 0; i < rows; i++) out[i] = t->mscratch[6 * i + r];
        return;
    }
    for (i = 0; i < rows; i++) out[i] = t->scratch[72 * C->nh + (int64_t)i * d + r];
}

void dca_apply_W(const aqs_linkage *L, int32_t n, const double h[6], double out[6])
{
    const tree *t = &L->t;
    const node *C = &t->nodes[n];
    const double *Cf = t->data + C->W, *U = t->data + C->U, *VS = t->data + C->VS;
    double tmp[6], uh[6];
    int i;
    if (C->d == 6) {
        for (i = 0; i < 6; i++) out[i] = 0.0;
        return;
    }
    /* W h = V h - V S (U h) */
    dense_cholesky6_lower_solve(Cf, h, tmp, 1);
    dense_cholesky6_upper_solve(Cf, tmp, out, 1);
    dense_matvec(U, h, uh, C->d, 6);
    dense_matvec(VS, uh, tmp, 6, C->d);
    for (i = 0; i < 6; i++) out[i] -= tmp[i];
}

void dca_node_backsub(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *x = t->data + C->xf;
    const double *phiA = t->data + A->phi, *phiB = t->data + B->phi;
    const double *U = t->data + C->U;
    const pose *J = (t->poses + C->J);
    const double *rho = t->data + C->rho, *gamma = t->data + C->gamma;
    double *xA = t->data + A->xf, *xB = t->data + B->xf;
    double *qdd = L->qdd + jd->voff, *f = L->cforce + 6 * L->m.eff_joint[C->joint];
    int32_t nA = A->nh, nB = B->nh, i, ci, d = C->d;
    double h[6], tmp[6];

    /* h = Phi^A_ko x_A - Phi^B_ko x_B (eq. 4, 5), from the children's blocks:
     * = X sum_i (Phi^A_{i,k})^T x_i - sum_j (Phi^B_{j,k})^T x_j. */
    {
        double ha[6] = {0, 0, 0, 0, 0, 0};
        int32_t nAo = nA - 1;
        for (ci = 0; ci < nAo; ci++) {
            dense_tmatvec6(cblk(phiA, nA, child_index(ci, C->ka), C->ka), x + 6 * ci, tmp);
            for (i = 0; i < 6; i++) ha[i] += tmp[i];
        }
        spatial_xform_motion(J, ha, h);
        for (ci = nAo; ci < C->nh; ci++) {
            dense_tmatvec6(cblk(phiB, nB, child_index(ci - nAo, C->kb), C->kb), x + 6 * ci, tmp);
            for (i = 0; i < 6; i++) h[i] -= tmp[i];
        }
    }
    dense_matvec(U, h, tmp, d, 6);
    for (i = 0; i < d; i++) qdd[i] = rho[i] - tmp[i];
    dca_apply_W(L, n, h, f);
    for (i = 0; i < 6; i++) f[i] += gamma[i];

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
    P = t->poses + nd->poses;
    memcpy(f, L->m.comp_force + 6 * c, sizeof f);
    for (h = 0; h < nd->nh; h++) {
        spatial_xform_force_back(&P[h], x + 6 * h, tmp);
        for (i = 0; i < 6; i++) f[i] += tmp[i];
    }
    dense_matvec(L->m.comp_inverse + 36 * c, f, a, 6, 6);
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
        spatial_xform_force_back(&P[h], fe, fc);
        for (i = 0; i < 6; i++) acc[6 * p + i] += fc[i];
    }
    for (k = last - 1; k >= first; k--) {
        int32_t b = m->members[k], pj = m->parent_joint[b];
        const joint_def *jd = &L->joints[pj];
        double Ib[36], Ic[36], w[6];
        model_body_inertia(L, b, Ib);
        spatial_inertia_to_parent(&m->body_in_comp[b], Ib, Ic);
        dense_matvec6(Ic, ca, w);
        for (i = 0; i < 6; i++) acc[6 * b + i] += w[i];
        if (L->load_slot[b] >= 0) {
            double fb[6];
            if (!have_pose) {
                update_comp_pose_world(L, c, &Pc);
                have_pose = 1;
            }
            update_body_load_in_comp(L, b, &Pc, fb);
            for (i = 0; i < 6; i++) acc[6 * b + i] -= fb[i];
        }
        if (jd->type != AQS_JOINT_FIXED) continue;
        /* In b's frame about its origin. */
        spatial_force_from_parent(&m->body_in_comp[b], acc + 6 * b, L->cforce + 6 * pj);
        if (jd->parent >= 0)
            for (i = 0; i < 6; i++) acc[6 * jd->parent + i] += acc[6 * b + i];
    }
}
