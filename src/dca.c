/* dca.c -- Featherstone's divide-and-conquer articulated-body algorithm for
 * quasi-statics, in the symbols of MATH.md §3. Every handle carries its own
 * frame: the child body frame for the joint a cluster hangs from, the joint
 * frame (fixed in the parent body) for the joints it holds up (§3.6). */
#include "dca.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "model.h"
#include "stale.h"
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

static void dca_leaf_phi(aqs_linkage *L, int32_t n);

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
    stale_tree(L);
    return AQS_OK;
}

/* Leaf Phi (constant after finalize; the world leaf's is zero). */
static void dca_leaf_phi(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *nd = &t->nodes[n];
    double *phi = t->data + nd->phi;
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
    double *M = t->mscratch, *phi = t->data + C->phi, *bC = t->data + C->bv;
    const double *phiA = t->data + A->phi, *phiB = t->data + B->phi;
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    int32_t nA = A->nh, nB = B->nh, ka = C->ka, kb = C->kb, nh = C->nh, d = C->d;
    int32_t nAo = nA - 1, i, j, ci, cj;
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

/* out = W h for internal node n (W = V - V S U, applied through the stored
 * Cholesky factor of T; zero for a free joint). */
static void dca_apply_W(const aqs_linkage *L, int32_t n, const double h[6], double out[6])
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
