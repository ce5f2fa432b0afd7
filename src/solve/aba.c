/* aba.c -- the exact quasi-static solve by Featherstone's articulated-body
 * algorithm (ABA) over the kinematic tree of composites, all velocities
 * zero. It gives the same accelerations and constraint forces as a full DCA
 * back-substitution (MATH.md §3, checked by tests/reference against the
 * dense solver for both), in O(N) with a small constant: one 6x6 congruence
 * per joint instead of a DCA node update with its Cholesky factor and
 * handle blocks. It neither reads nor writes the assembly tree's
 * coefficients, so the tree's stale marks simply accumulate until an
 * adaptive solve needs the tree.
 *
 * For composite c hanging from effective joint e (parent composite p, S the
 * motion subspace in c's frame, Q the active force, f_c the external load):
 *   backward:  IA_c = I_c + sum_children X^T Ia X,  pA_c = -f_c + sum X^T pa
 *              U = IA_c S,  D = S^T U,  u = Q - S^T pA_c
 *              Ia = IA_c - U D^-1 U^T,  pa = pA_c + U D^-1 u
 *   forward:   a' = X a_p,  qdd = D^-1 (u - U^T a'),  a_c = a' + S qdd
 *              f_e = IA_c a_c + pA_c  (the force of e on c, c's frame)
 * with X the motion transform from p's frame to c's, and the world moving
 * with a_0 = -g (the root trick, MATH.md §3.7). */
#include "aba.h"

#include <math.h>
#include <string.h>

#include "adaptive.h"
#include "dca.h"
#include "dense.h"
#include "update.h"

aqs_status aba_alloc(aqs_linkage *L)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    int32_t k, n = 0;
    a->order = lk_calloc(L, (size_t)m->ne + 1, sizeof(int32_t));
    a->IA = lk_calloc(L, 36 * (size_t)m->ncomp + 1, sizeof(double));
    a->pA = lk_calloc(L, 6 * (size_t)m->ncomp + 1, sizeof(double));
    a->acc = lk_calloc(L, 6 * ((size_t)m->ncomp + 1), sizeof(double));
    a->U = lk_calloc(L, 6 * (size_t)L->nv + 1, sizeof(double));
    a->u = lk_calloc(L, (size_t)L->nv + 1, sizeof(double));
    a->x = lk_calloc(L, 6 * (size_t)L->t.max_handles + 1, sizeof(double));
    if (!a->order || !a->IA || !a->pA || !a->acc || !a->U || !a->u || !a->x) return AQS_ENOMEM;
    /* Bodies come parents first; a composite's root body carries its
     * effective parent joint. */
    for (k = 0; k < L->nbodies; k++) {
        int32_t b = m->order[k], c = m->comp_of_body[b];
        if (c == m->ncomp || m->comp_root[c] != b) continue;
        a->order[n++] = m->eff_of_joint[m->parent_joint[b]];
    }
    return AQS_OK;
}

void aba_free(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    lk_free(L, a->order);
    lk_free(L, a->IA);
    lk_free(L, a->pA);
    lk_free(L, a->acc);
    lk_free(L, a->U);
    lk_free(L, a->u);
    lk_free(L, a->x);
    memset(a, 0, sizeof *a);
}

/* The pose of effective joint e's child composite in its parent's frame:
 * the joint's placement composed with J(q_e) (kept current in the tree by
 * frames_node whenever q_e changes). */
static void child_in_parent(const aqs_linkage *L, int32_t e, pose *P)
{
    const tree *t = &L->t;
    pose_compose(&L->m.eff_place[e], t->poses + t->nodes[t->node_of_eff[e]].J, P);
}

/* D = S^T U (d x d) from the rows U_k = IA S_k; its inverse into Dinv.
 * Returns 0, or -1 when D is not numerically positive definite. */
static int joint_space_inverse(const double *S, const double *U, int d, double *Dinv)
{
    double D[36];
    int i, j, r;
    for (i = 0; i < d; i++)
        for (j = 0; j < d; j++) {
            double v = 0.0;
            for (r = 0; r < 6; r++) v += S[r * d + i] * U[6 * j + r];
            D[d * i + j] = v;
        }
    if (d == 1) {
        if (!(D[0] > 0.0) || !isfinite(D[0])) return -1;
        Dinv[0] = 1.0 / D[0];
        return 0;
    }
    dense_symmetrize(D, d);
    return dense_spd_inverse(D, Dinv, d);
}

static aqs_status backward(aqs_linkage *L)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    int32_t k, c, i, j, r;
    for (c = 0; c < m->ncomp; c++) {
        memcpy(a->IA + 36 * c, m->comp_inertia + 36 * c, 36 * sizeof(double));
        for (i = 0; i < 6; i++) a->pA[6 * c + i] = -m->comp_force[6 * c + i];
    }
    for (k = m->ne - 1; k >= 0; k--) {
        int32_t e = a->order[k], p = m->eff_parent[e];
        const joint_def *jd = &L->joints[m->eff_joint[e]];
        const double *IA, *pA, *Q = L->tau + jd->voff;
        double S[36], Dinv[36], w[6], Ia[36], pa[6], tmp[36], *U = a->U + 6 * jd->voff, *u = a->u + jd->voff;
        int d = joint_nv(jd->type);
        pose P;
        c = m->eff_child[e];
        IA = a->IA + 36 * c;
        pA = a->pA + 6 * c;
        joint_subspace(jd, L->q + jd->qoff, S);
        if (d == 1) {
            double s = 0.0;
            dense_matvec6(IA, S, U); /* U = IA S, S a single column */
            for (r = 0; r < 6; r++) s += S[r] * pA[r];
            u[0] = Q[0] - s;
        } else {
            for (j = 0; j < d; j++) {
                double s = 0.0;
                for (r = 0; r < 6; r++) {
                    double v = 0.0;
                    for (i = 0; i < 6; i++) v += IA[6 * r + i] * S[i * d + j];
                    U[6 * j + r] = v;
                    s += S[r * d + j] * pA[r];
                }
                u[j] = Q[j] - s;
            }
        }
        if (joint_space_inverse(S, U, d, Dinv) != 0)
            return lk_fail(L, AQS_ENUMERIC, "articulated inertia across joint %d is numerically singular",
                           (int)m->eff_joint[e]);
        if (p == m->ncomp) continue; /* the world takes nothing back */
        /* w = D^-1 u; Ia = IA - U^T D^-1 U (U stored as d rows), pa = pA + U^T w */
        for (j = 0; j < d; j++) {
            double v = 0.0;
            for (i = 0; i < d; i++) v += Dinv[d * j + i] * u[i];
            w[j] = v;
        }
        for (r = 0; r < 6; r++) {
            double v = pA[r];
            for (j = 0; j < d; j++) v += U[6 * j + r] * w[j];
            pa[r] = v;
        }
        if (d == 1) {
            for (r = 0; r < 6; r++) {
                double ur = U[r] * Dinv[0];
                for (i = r; i < 6; i++) Ia[6 * r + i] = Ia[6 * i + r] = IA[6 * r + i] - ur * U[i];
            }
        } else {
            double DU[36]; /* D^-1 U, d x 6 */
            for (j = 0; j < d; j++)
                for (r = 0; r < 6; r++) {
                    double v = 0.0;
                    for (i = 0; i < d; i++) v += Dinv[d * j + i] * U[6 * i + r];
                    DU[6 * j + r] = v;
                }
            for (r = 0; r < 6; r++)
                for (i = r; i < 6; i++) {
                    double v = IA[6 * r + i];
                    for (j = 0; j < d; j++) v -= U[6 * j + r] * DU[6 * j + i];
                    Ia[6 * r + i] = Ia[6 * i + r] = v;
                }
        }
        child_in_parent(L, e, &P);
        spatial_inertia_to_parent(&P, Ia, tmp);
        for (i = 0; i < 36; i++) a->IA[36 * p + i] += tmp[i];
        spatial_xform_force_back(&P, pa, tmp);
        for (i = 0; i < 6; i++) a->pA[6 * p + i] += tmp[i];
    }
    return AQS_OK;
}

static void forward(aqs_linkage *L)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    double *acc = a->acc;
    int32_t k, i, j;
    for (i = 0; i < 3; i++) {
        acc[6 * m->ncomp + i] = 0.0;
        acc[6 * m->ncomp + 3 + i] = -L->gravity[i];
    }
    for (k = 0; k < m->ne; k++) {
        int32_t e = a->order[k], c = m->eff_child[e], p = m->eff_parent[e];
        const joint_def *jd = &L->joints[m->eff_joint[e]];
        const double *U = a->U + 6 * jd->voff, *u = a->u + jd->voff;
        const double *IA = a->IA + 36 * c, *pA = a->pA + 6 * c;
        double S[36], Dinv[36], rhs[6], *qdd = L->qdd + jd->voff, *ac = acc + 6 * c;
        double *f = L->cforce + 6 * (size_t)m->eff_joint[e];
        int d = joint_nv(jd->type);
        pose P;
        child_in_parent(L, e, &P);
        spatial_xform_motion(&P, acc + 6 * p, ac); /* a' = X a_p */
        joint_subspace(jd, L->q + jd->qoff, S);
        if (d == 1) {
            double D = 0.0, v = u[0];
            for (i = 0; i < 6; i++) {
                D += S[i] * U[i];
                v -= U[i] * ac[i];
            }
            qdd[0] = v / D; /* D > 0: checked in the backward pass */
            for (i = 0; i < 6; i++) ac[i] += S[i] * qdd[0];
        } else {
            (void)joint_space_inverse(S, U, d, Dinv); /* succeeded in the backward pass */
            for (j = 0; j < d; j++) {
                double v = u[j];
                for (i = 0; i < 6; i++) v -= U[6 * j + i] * ac[i];
                rhs[j] = v;
            }
            for (j = 0; j < d; j++) {
                double v = 0.0;
                for (i = 0; i < d; i++) v += Dinv[d * j + i] * rhs[i];
                qdd[j] = v;
            }
            for (i = 0; i < 6; i++) {
                double v = 0.0;
                for (j = 0; j < d; j++) v += S[i * d + j] * qdd[j];
                ac[i] += v;
            }
        }
        dense_matvec6(IA, ac, f);
        for (i = 0; i < 6; i++) f[i] += pA[i];
    }
}

/* Fixed joints: dca_welded_forces_comp takes a composite's leaf handle
 * forces, so form them (in L->aba.x, not in the tree, whose coefficients may
 * not even be allocated) from the joint forces just computed: the force on
 * the composite through handle h, in the handle's frame (its own frame for
 * its parent joint, the joint frame for a joint it holds up). */
static void welded_forces(aqs_linkage *L)
{
    const model *m = &L->m;
    const tree *t = &L->t;
    int32_t c, h, i;
    for (c = 0; c <= m->ncomp; c++) {
        const node *leaf;
        double *x;
        if (!m->comp_welded[c]) continue;
        leaf = &t->nodes[t->leaf_of_comp[c]];
        x = L->aba.x;
        for (h = 0; h < leaf->nh; h++) {
            int32_t e = t->handles[leaf->handles + h];
            const double *f = L->cforce + 6 * (size_t)m->eff_joint[e];
            if (m->eff_child[e] == c) {
                memcpy(x + 6 * h, f, 6 * sizeof(double));
            } else {
                double fj[6];
                spatial_xform_force_back(t->poses + t->nodes[t->node_of_eff[e]].J, f, fj);
                for (i = 0; i < 6; i++) x[6 * h + i] = -fj[i];
            }
        }
        dca_welded_forces_comp(L, c, x);
    }
}

aqs_status aba_solve(aqs_linkage *L)
{
    aqs_status st;
    update_loads(L); /* the composites' loads in their frames */
    if ((st = backward(L)) != AQS_OK) return st;
    forward(L);
    welded_forces(L);
    adaptive_mark_exact(L);
    L->t.nodes_updated = 0;
    L->t.factors_updated = 0;
    return AQS_OK;
}
