/* dca.c -- Featherstone's divide-and-conquer articulated-body algorithm for
 * quasi-statics, in the symbols of MATH.md §3. Every handle carries its own
 * frame: the child body frame for the joint a cluster hangs from, the joint
 * frame (fixed in the parent body) for the joints it holds up (§3.6). */
#include "dca.h"

#include <string.h>

#include "dense.h"
#include "model.h"
#include "update.h"

/* Block (i, j) of an n-handle Phi: 6x6 at rows 6i, columns 6j. */
static double *phi_block(double *phi, int32_t nh, int32_t i, int32_t j)
{
    return phi + (int64_t)36 * nh * i + 6 * j;
}

static void get_block(const double *phi, int32_t nh, int32_t i, int32_t j, double out[36])
{
    int r;
    const double *src = phi + (int64_t)36 * nh * i + 6 * j;
    for (r = 0; r < 6; r++) memcpy(out + 6 * r, src + (int64_t)6 * nh * r, 6 * sizeof(double));
}

static void put_block(double *phi, int32_t nh, int32_t i, int32_t j, const double in[36])
{
    int r;
    double *dst = phi_block(phi, nh, i, j);
    for (r = 0; r < 6; r++) memcpy(dst + (int64_t)6 * nh * r, in + 6 * r, 6 * sizeof(double));
}

void dca_leaf_phi(aqs_linkage *L, int32_t n)
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
        double blk[36];
        for (i = 0; i < nd->nh; i++) {
            spatial_from_parent(&P[i], X);
            dense_mul(X, Iinv, Y + 36 * i, 6, 6, 6);
        }
        /* Phi_{hh'} = X_h I^{-1} X_h'^T */
        for (j = 0; j < nd->nh; j++) {
            spatial_from_parent(&P[j], X);
            for (i = 0; i < nd->nh; i++) {
                dense_mul_nt(Y + 36 * i, X, blk, 6, 6, 6);
                put_block(phi, nd->nh, i, j, blk);
            }
        }
        dense_symmetrize(phi, 6 * nd->nh);
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

/* X^T f for a motion transform X (6x6): the force transform back. */
static void xform_force_back(const double X[36], const double f[6], double out[6])
{
    dense_tmatvec(X, f, out, 6, 6);
}

int dca_node_update(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *q = L->q + jd->qoff, *Q = L->tau + jd->voff;
    double *X = t->data + C->X, *W = t->data + C->W, *U = t->data + C->U;
    double *rho = t->data + C->rho, *gamma = t->data + C->gamma, *S = t->data + C->S;
    double *M = t->data + C->M, *phi = t->data + C->phi, *bC = t->data + C->bv;
    const double *phiA = t->data + A->phi, *phiB = t->data + B->phi;
    const double *bA = t->data + A->bv, *bB = t->data + B->bv;
    int32_t nA = A->nh, nB = B->nh, ka = C->ka, kb = C->kb, nh = C->nh, d = C->d;
    int32_t i, j, ci, cj;
    double Akk[36], Bkk[36], T[36], V[36], VS[36], D[36], Dinv[36], beta[6], bk[6], tmp[6];
    double blk[36];
    pose J;

    joint_child_pose(jd, q, &J);
    spatial_from_parent(&J, X);
    joint_subspace(jd, q, S);

    /* A's k blocks into the child frame of k (§3.6). */
    get_block(phiA, nA, ka, ka, Akk);
    dense_mul(X, Akk, T, 6, 6, 6);
    dense_mul_nt(T, X, Akk, 6, 6, 6);
    get_block(phiB, nB, kb, kb, Bkk);
    for (i = 0; i < 36; i++) T[i] = Akk[i] + Bkk[i];
    dense_symmetrize(T, 6);
    if (dense_spd_inverse(T, V, 6) != 0) return -1;

    /* M = [Phi^A_ok X^T ; -Phi^B_ok], one 6x6 block per outer handle. */
    for (i = 0, ci = 0; i < nA; i++) {
        if (i == ka) continue;
        get_block(phiA, nA, i, ka, blk);
        dense_mul_nt(blk, X, M + 36 * ci, 6, 6, 6);
        ci++;
    }
    for (i = 0; i < nB; i++) {
        if (i == kb) continue;
        get_block(phiB, nB, i, kb, blk);
        for (j = 0; j < 36; j++) M[36 * ci + j] = -blk[j];
        ci++;
    }

    dense_matvec(X, bA + 6 * ka, bk, 6, 6); /* b^A_k in the child frame */
    for (i = 0; i < 6; i++) beta[i] = bk[i] - bB[6 * kb + i];

    if (d == 6) {
        /* Free joint: S = I, so U = I, W = 0, gamma = Q, rho = V^{-1} Q - beta. */
        memset(W, 0, 36 * sizeof(double));
        memset(U, 0, 36 * sizeof(double));
        for (i = 0; i < 6; i++) U[7 * i] = 1.0;
        dense_matvec(T, Q, rho, 6, 6);
        for (i = 0; i < 6; i++) {
            rho[i] -= beta[i];
            gamma[i] = Q[i];
        }
    } else {
        dense_mul(V, S, VS, 6, 6, d);       /* V S (6 x d) */
        dense_mul_tn(S, VS, D, d, 6, d);    /* D = S^T V S */
        dense_symmetrize(D, d);
        if (dense_spd_inverse(D, Dinv, d) != 0) return -1;
        dense_mul_nt(Dinv, VS, U, d, d, 6); /* U = D^{-1} (V S)^T */
        dense_mul(VS, U, T, 6, d, 6);       /* W = V - V S U */
        for (i = 0; i < 36; i++) W[i] = V[i] - T[i];
        dense_symmetrize(W, 6);
        dense_tmatvec(VS, beta, tmp, 6, d); /* rho = D^{-1} (Q - S^T V beta) */
        for (i = 0; i < d; i++) tmp[i] = Q[i] - tmp[i];
        dense_matvec(Dinv, tmp, rho, d, d);
        dense_matvec(W, beta, gamma, 6, 6); /* gamma = W beta + U^T Q */
        dense_tmatvec(U, Q, tmp, d, 6);
        for (i = 0; i < 6; i++) gamma[i] += tmp[i];
    }

    /* Phi_C = blkdiag(Phi^A_oo, Phi^B_oo) - M W M^T; b_C = [b^A_o; b^B_o] - M gamma. */
    {
        double *MW = t->scratch;
        dense_mul(M, W, MW, 6 * nh, 6, 6);
        for (ci = 0; ci < nh; ci++)
            for (cj = ci; cj < nh; cj++) {
                int fromA_i = ci < nA - 1, fromA_j = cj < nA - 1;
                dense_mul_nt(MW + 36 * ci, M + 36 * cj, blk, 6, 6, 6);
                if (fromA_i == fromA_j) {
                    int32_t ai = fromA_i ? (ci < ka ? ci : ci + 1) : (ci - (nA - 1) < kb ? ci - (nA - 1) : ci - (nA - 1) + 1);
                    int32_t aj = fromA_j ? (cj < ka ? cj : cj + 1) : (cj - (nA - 1) < kb ? cj - (nA - 1) : cj - (nA - 1) + 1);
                    double base[36];
                    get_block(fromA_i ? phiA : phiB, fromA_i ? nA : nB, ai, aj, base);
                    for (i = 0; i < 36; i++) blk[i] = base[i] - blk[i];
                } else {
                    for (i = 0; i < 36; i++) blk[i] = -blk[i];
                }
                put_block(phi, nh, ci, cj, blk);
                if (cj != ci) {
                    double tr[36];
                    for (i = 0; i < 6; i++)
                        for (j = 0; j < 6; j++) tr[6 * j + i] = blk[6 * i + j];
                    put_block(phi, nh, cj, ci, tr);
                }
            }
        dense_symmetrize(phi, 6 * nh);
        dense_matvec(M, gamma, bC, 6 * nh, 6);
        for (ci = 0; ci < nh; ci++) {
            const double *src;
            if (ci < nA - 1) src = bA + 6 * (ci < ka ? ci : ci + 1);
            else {
                int32_t bj = ci - (nA - 1);
                src = bB + 6 * (bj < kb ? bj : bj + 1);
            }
            for (i = 0; i < 6; i++) bC[6 * ci + i] = src[i] - bC[6 * ci + i];
        }
    }
    return 0;
}

void dca_node_backsub(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n];
    const node *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    const double *x = t->data + C->xf, *M = t->data + C->M;
    const double *W = t->data + C->W, *U = t->data + C->U, *X = t->data + C->X;
    const double *rho = t->data + C->rho, *gamma = t->data + C->gamma;
    double *xA = t->data + A->xf, *xB = t->data + B->xf;
    double *qdd = L->qdd + jd->voff, *f = L->cforce + 6 * L->m.eff_joint[C->joint];
    int32_t nA = A->nh, nB = B->nh, i, ci, d = C->d;
    double h[6], tmp[6];

    /* h = Phi^A_ko x_A - Phi^B_ko x_B = M^T x (eq. 4, 5) */
    dense_tmatvec(M, x, h, 6 * C->nh, 6);
    dense_matvec(U, h, tmp, d, 6);
    for (i = 0; i < d; i++) qdd[i] = rho[i] - tmp[i];
    dense_matvec(W, h, f, 6, 6);
    for (i = 0; i < 6; i++) f[i] += gamma[i];

    for (i = 0, ci = 0; i < nA; i++) {
        if (i == C->ka) continue;
        memcpy(xA + 6 * i, x + 6 * ci, 6 * sizeof(double));
        ci++;
    }
    xform_force_back(X, f, tmp);
    for (i = 0; i < 6; i++) xA[6 * C->ka + i] = -tmp[i];
    for (i = 0; i < nB; i++) {
        if (i == C->kb) continue;
        memcpy(xB + 6 * i, x + 6 * ci, 6 * sizeof(double));
        ci++;
    }
    memcpy(xB + 6 * C->kb, f, 6 * sizeof(double));
}

/* Acceleration minus g (root trick) of a composite, in its frame, from its
 * leaf's handle forces: a' = I^{-1} (f + sum_h X_h^T x_h). The world's is -g. */
static void comp_acceleration(const aqs_linkage *L, int32_t c, double a[6])
{
    const tree *t = &L->t;
    const node *nd;
    const pose *P;
    const double *x;
    double f[6], X[36], tmp[6];
    int32_t h, i;
    if (c == L->m.ncomp) {
        a[0] = a[1] = a[2] = 0.0;
        for (i = 0; i < 3; i++) a[3 + i] = -L->gravity[i];
        return;
    }
    nd = &t->nodes[t->leaf_of_comp[c]];
    P = t->poses + nd->poses;
    x = t->data + nd->xf;
    memcpy(f, L->m.comp_force + 6 * c, sizeof f);
    for (h = 0; h < nd->nh; h++) {
        spatial_from_parent(&P[h], X);
        xform_force_back(X, x + 6 * h, tmp);
        for (i = 0; i < 6; i++) f[i] += tmp[i];
    }
    dense_matvec(L->m.comp_inverse + 36 * c, f, a, 6, 6);
}

/* Newton's law on each welded subtree S hanging from fixed joint j:
 * f_j = sum_{i in S} (I_i a'_i - f_i) + sum_{joints e leaving S} f_e,
 * accumulated children first in the composite's frame (MATH.md §2). */
void dca_welded_forces(aqs_linkage *L)
{
    const model *m = &L->m;
    double *acc = L->welded_acc, *ca = L->welded_acc + 6 * L->nbodies;
    unsigned char *has = (unsigned char *)(ca + 6 * (m->ncomp + 1));
    int32_t k, c, e, i;
    if (m->nwelded == 0) return;
    memset(has, 0, (size_t)m->ncomp + 1);
    for (k = 0; k < L->nbodies; k++) {
        int32_t b = m->order[k];
        if (L->joints[m->parent_joint[b]].type == AQS_JOINT_FIXED) has[m->comp_of_body[b]] = 1;
    }
    for (c = 0; c <= m->ncomp; c++)
        if (has[c]) comp_acceleration(L, c, ca + 6 * c);
    for (k = 0; k < L->nbodies; k++) memset(acc + 6 * k, 0, 6 * sizeof(double));
    /* Forces of the moving joints held by welded composites. */
    for (e = 0; e < m->ne; e++) {
        int32_t j = m->eff_joint[e], p = L->joints[j].parent;
        pose J, Pc;
        double Xi[36], fc[6];
        if (p < 0 || !has[m->eff_parent[e]]) continue;
        joint_child_pose(&L->joints[j], L->q + L->joints[j].qoff, &J);
        pose_compose(&m->eff_place[e], &J, &Pc);
        spatial_from_parent(&Pc, Xi);
        dense_tmatvec(Xi, L->cforce + 6 * j, fc, 6, 6);
        for (i = 0; i < 6; i++) acc[6 * p + i] += fc[i];
    }
    for (k = L->nbodies - 1; k >= 0; k--) {
        int32_t b = m->order[k], pj = m->parent_joint[b];
        const joint_def *jd = &L->joints[pj];
        double Ib[36], Ic[36], w[6], Xm[36];
        c = m->comp_of_body[b];
        if (!has[c]) continue;
        model_body_inertia(L, b, Ib);
        spatial_inertia_to_parent(&m->body_in_comp[b], Ib, Ic);
        dense_matvec(Ic, ca + 6 * c, w, 6, 6);
        for (i = 0; i < 6; i++) acc[6 * b + i] += w[i];
        if (L->load_slot[b] >= 0) {
            pose Pc;
            double fb[6];
            update_comp_pose_world(L, c, &Pc);
            update_body_load_in_comp(L, b, &Pc, fb);
            for (i = 0; i < 6; i++) acc[6 * b + i] -= fb[i];
        }
        if (jd->type != AQS_JOINT_FIXED) continue;
        /* In b's frame about its origin: X^T with X the motion transform b -> composite. */
        spatial_to_parent(&m->body_in_comp[b], Xm);
        dense_tmatvec(Xm, acc + 6 * b, L->cforce + 6 * pj, 6, 6);
        if (jd->parent >= 0)
            for (i = 0; i < 6; i++) acc[6 * jd->parent + i] += acc[6 * b + i];
    }
}
