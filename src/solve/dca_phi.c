/* dca_phi.c -- the inverse-inertia ("Phi") form of the DCA node update: each
 * node keeps its handles' articulated inverse inertia Phi as an explicit
 * matrix, and a join forms Phi_C = blkdiag(Phi^A_oo, Phi^B_oo) - M W M^T
 * (MATH.md §3). It is the form of aqs 0.1 up to 2026-12-01, kept as
 * AQS_DCA_FORM_PHI: about half the square-root form's cost per node,
 * but the subtraction loses digits as subassemblies grow (a straight chain
 * of 13,000 links is "numerically singular"), and with near point masses,
 * light parts and large mass ratios (docs/math.md, "Accurate Phi"). It
 * writes the same outputs as the square-root form (src/solve/dca.c): rho, gamma,
 * b, FX = W M^T and QX = U M^T. */
#include "dca.h"

#include <math.h>
#include <string.h>

#include "dense.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#define PHI_SSE2 1
#endif

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

void dca_phi_leaf(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *nd = &t->nodes[n];
    double *phi = t->data + nd_lam(nd); /* Phi takes Lambda's place */
    const pose *P = t->poses + nd->poses;
    int32_t i, j;
    if (nd->comp == L->m.ncomp) {
        memset(phi, 0, sizeof(double) * 36 * nd->nh * nd->nh); /* the world does not move */
        return;
    }
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

#ifdef PHI_SSE2
/* lower_solve_row6 for two rows m0, m1 (into y0, y1), each lane its operations */
static void lower_solve_row6_x2(const double *Cf, const double *m0, const double *m1, double *y0, double *y1)
{
    __m128d y[6];
    int i, k;
    for (i = 0; i < 6; i++) {
        __m128d v = _mm_loadh_pd(_mm_load_sd(m0 + i), m1 + i);
        for (k = 0; k < i; k++) v = _mm_sub_pd(v, _mm_mul_pd(_mm_set1_pd(Cf[6 * i + k]), y[k]));
        y[i] = _mm_div_pd(v, _mm_set1_pd(Cf[7 * i]));
        _mm_storel_pd(y0 + i, y[i]);
        _mm_storeh_pd(y1 + i, y[i]);
    }
}
#endif

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

int dca_phi_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *q = L->q + jd->qoff, *Q = L->tau + jd->voff;
    const pose *J = t->poses + nd_J(C);
    double Cf[36], U[36], VS[36], *FX = t->data + nd_W(C), *QX = t->data + nd_U(C);
    double *rho = t->data + nd_rho(C), *gamma = t->data + nd_gamma(C), *S = t->data + nd_S(C);
    double *M = t->mscratch, *phi = t->data + nd_lam(C), *bC = t->data + C->bv;
    const double *phiA = t->data + nd_lam(A), *phiB = t->data + nd_lam(B);
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    int32_t nA = A->nh, nB = B->nh, ka = C->ka, kb = C->kb, nh = C->nh, d = C->d;
    int32_t nAo = nA - 1, i, j, ci, cj;
    double T[36], Ws[36], D[36], Dinv[36], beta[6], bk[6], tmp[6], Vb[6];

    /* J = J(q_k), refreshed by frames_node; X = spatial_from_parent(J)
     * maps k's joint frame to its child frame. */
    joint_subspace_aligned(jd, q, S); /* the aligned frames (joint.h) */

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
            ci = 0;
#ifdef PHI_SSE2
            for (; ci + 1 < 6 * nh; ci += 2)
                lower_solve_row6_x2(Cf, M + 6 * ci, M + 6 * ci + 6, Y + 6 * ci, Y + 6 * ci + 6);
#endif
            for (; ci < 6 * nh; ci++) lower_solve_row6(Cf, M + 6 * ci, Y + 6 * ci);
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
        for (ci = 0; ci < nh; ci++)
            for (cj = ci; cj < nh; cj++) {
                double *out = blk(phi, nh, ci, cj);
                int same = (ci < nAo) == (cj < nAo);
                const double *base =
                    !same ? NULL
                    : ci < nAo ? cblk(phiA, nA, child_index(ci, ka), child_index(cj, ka))
                               : cblk(phiB, nB, child_index(ci - nAo, kb), child_index(cj - nAo, kb));
                if (d == 1 && ci == cj) {
                    /* a diagonal block is symmetric: its upper triangle only */
                    const double *zd = ZD + 6 * ci, *z = Z + 6 * cj, *y = Y + 36 * ci;
                    int r, c, k;
                    for (r = 0; r < 6; r++)
                        for (c = r; c < 6; c++) {
                            double sum = 0.0;
                            for (k = 0; k < 6; k++) sum += y[6 * r + k] * y[6 * c + k];
                            out[6 * r + c] = out[6 * c + r] = zd[r] * z[c] - sum + base[6 * r + c];
                        }
                } else if (d == 1) {
                    const double *zd = ZD + 6 * ci, *z = Z + 6 * cj;
                    int r, c;
                    dense_mul66_nt(Y + 36 * ci, Y + 36 * cj, out);
                    for (r = 0; r < 6; r++)
                        for (c = 0; c < 6; c++) out[6 * r + c] = zd[r] * z[c] - out[6 * r + c];
                    if (base)
                        for (i = 0; i < 36; i++) out[i] += base[i];
                } else if (d < 6) {
                    int r, c, k;
                    dense_mul66_nt(Y + 36 * ci, Y + 36 * cj, out);
                    for (r = 0; r < 6; r++)
                        for (c = 0; c < 6; c++) {
                            double sum = 0.0;
                            for (k = 0; k < d; k++) sum += ZD[(6 * ci + r) * d + k] * Z[(6 * cj + c) * d + k];
                            out[6 * r + c] = (base ? base[6 * r + c] : 0.0) - out[6 * r + c] + sum;
                        }
                    if (ci == cj) dense_symmetrize(out, 6);
                } else {
                    for (i = 0; i < 36; i++) out[i] = base ? base[i] : 0.0;
                }
            }
        symmetrize_blocks(phi, nh, 0); /* diagonal blocks were formed symmetric */
        for (ci = 0; ci < nh; ci++) {
            const double *src = ci < nAo ? bA + 6 * child_index(ci, ka) : bB + 6 * child_index(ci - nAo, kb);
            dense_matvec6(M + 36 * ci, gamma, tmp);
            for (i = 0; i < 6; i++) bC[6 * ci + i] = src[i] - tmp[i];
        }
    }
    /* FX = W M^T and QX = U M^T for the back-substitution and the total
     * accelerations (src/solve/dca.c), W = V - V S U (zero for a free joint). */
    {
        double V[36], Wm[36];
        const int32_t rows = 6 * nh;
        if (d == 6) {
            memset(Wm, 0, sizeof Wm);
        } else {
            dense_cholesky6_inverse(Cf, V);
            for (i = 0; i < 6; i++)
                for (j = 0; j < 6; j++) {
                    double x = V[6 * i + j];
                    int32_t k;
                    for (k = 0; k < d; k++) x -= VS[d * i + k] * U[6 * k + j];
                    Wm[6 * i + j] = x;
                }
        }
        ci = 0;
#ifdef PHI_SSE2
        for (; ci + 1 < rows; ci += 2) { /* two rows of M at a time, each lane the sums below */
            const double *m0 = M + 6 * ci, *m1 = m0 + 6;
            __m128d mj[6];
            for (j = 0; j < 6; j++) mj[j] = _mm_loadh_pd(_mm_load_sd(m0 + j), m1 + j);
            for (i = 0; i < 6; i++) {
                const double *w = Wm + 6 * i;
                __m128d x = _mm_mul_pd(_mm_set1_pd(w[0]), mj[0]);
                for (j = 1; j < 6; j++) x = _mm_add_pd(x, _mm_mul_pd(_mm_set1_pd(w[j]), mj[j]));
                _mm_storeu_pd(FX + (int64_t)i * rows + ci, x);
            }
            for (i = 0; i < d; i++) {
                const double *u = U + 6 * i;
                __m128d x = _mm_mul_pd(_mm_set1_pd(u[0]), mj[0]);
                for (j = 1; j < 6; j++) x = _mm_add_pd(x, _mm_mul_pd(_mm_set1_pd(u[j]), mj[j]));
                _mm_storeu_pd(QX + (int64_t)i * rows + ci, x);
            }
        }
#endif
        for (; ci < rows; ci++) {
            const double *m = M + 6 * ci;
            for (i = 0; i < 6; i++) {
                const double *w = Wm + 6 * i;
                FX[(int64_t)i * rows + ci] = w[0] * m[0] + w[1] * m[1] + w[2] * m[2] + w[3] * m[3] + w[4] * m[4] + w[5] * m[5];
            }
            for (i = 0; i < d; i++) {
                const double *u = U + 6 * i;
                QX[(int64_t)i * rows + ci] = u[0] * m[0] + u[1] * m[1] + u[2] * m[2] + u[3] * m[3] + u[4] * m[4] + u[5] * m[5];
            }
        }
    }
    return 0;
}

