/* abarefine.c -- iterative refinement of the articulated-body solve where
 * it lost digits (docs/math.md §5b).
 *
 * The articulated-body algorithm forms each joint's projected inertia
 * Ia = IA - U D^-1 U^T and moves it into the parent's frame; where that
 * cancels or mixes scales (spherical and planar joints between bodies of
 * very different masses on a floating base, a long planar chain whose
 * articulated inertia is moved into the oblique frame of the arm holding it)
 * the accelerations lose digits the problem does not lose (the DCA keeps
 * them on the same models: up to 4e-9 against 2e-16). The forward pass
 * measures the bodies' balance of forces (aba.c, forward); above
 * ABA_REFINE_LEVEL u this file refines the answer:
 *   r   = Q - S^T f,  f_c = I_c a_c - f_ext,c + sum_children X^T f_child
 *         (inverse dynamics inward from the solve's accelerations a_c)
 *   dq  = ABA^-1(r): the articulated-body solve with r as the only load (no
 *         gravity, no external force) by the factors the solve kept (U,
 *         D^-1, the poses): bias forces backward, accelerations forward
 *   qdd += dq, a_c += da_c
 * A correction is kept when it lowers the residual; at most L->refine_max
 * of them (aqs_linkage_set_exact_refinement, which also switches the
 * balance off at 0). A solve that kept one takes the inverse dynamics'
 * forces f_c of its final accelerations (its own, f = IA a + pA, are what
 * the balance found unbalanced).
 * Scratch: the nodes' pA (zero between solves, left zero) and, once a solve
 * refines, the arrays of struct aba_refine (LK_MEM_EXACT, kept). */
#include "abarefine.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "kintree.h"
#include "rounding.h"

struct aba_refine {
    double *r;    /* nv: the residual */
    double *dq;   /* nv: a correction (the loads pass's u first) */
    double *q0;   /* nv: the accelerations before the correction */
    double *da;   /* 6 ne: the correction's accelerations */
    double *a0;   /* 6 ne: the nodes' accelerations before it */
};

void aba_refine_free(aqs_linkage *L)
{
    struct aba_refine *R = L->abarf;
    if (!R) return;
    lk_free(L, R->r);
    lk_free(L, R->dq);
    lk_free(L, R->q0);
    lk_free(L, R->da);
    lk_free(L, R->a0);
    lk_free(L, R);
    L->abarf = NULL;
}

static struct aba_refine *refine_arrays(aqs_linkage *L)
{
    const size_t nv = (size_t)L->nv + 1, ne6 = 6 * (size_t)L->m.ne + 1;
    struct aba_refine *R = L->abarf;
    if (R) return R;
    R = lk_calloc_in(L, LK_MEM_EXACT, 1, sizeof *R);
    if (!R) return NULL;
    L->abarf = R;
    R->r = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->dq = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->q0 = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->da = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    R->a0 = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    if (!R->r || !R->dq || !R->q0 || !R->da || !R->a0) {
        aba_refine_free(L);
        return NULL;
    }
    return R;
}

/* The residual of the nodes' accelerations (L->qdd their joint parts):
 * into r when r is not NULL, the forces into L->cforce when forces is set.
 * Returns max |r| over the larger of the largest joint force and the sum
 * of the bodies' terms |I_c a_c| + m_c |g| (torques weighed by 1/l as in
 * rounding.c; 0 when both are 0; NaN when a value is not finite). pA is
 * the inward pass's accumulator: zero before (the forward pass leaves it
 * so) and after. */
static double residual(aqs_linkage *L, double *r, int forces)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    const double il = m->length > 0.0 ? 1.0 / m->length : 1.0;
    const double gn = sqrt(L->gravity[0] * L->gravity[0] + L->gravity[1] * L->gravity[1] + L->gravity[2] * L->gravity[2]);
    double rmax = 0.0, smax = 0.0, tsum = 0.0, f[6];
    int32_t k, i, j, bad = 0;
    for (i = 0; i < m->nloaded_comps; i++) {
        const int32_t c = m->loaded_comps[i];
        double *pA = a->node[a->pos_of_comp[c]].pA;
        for (j = 0; j < 6; j++) pA[j] -= m->comp_force[6 * c + j];
    }
    for (k = m->ne - 1; k >= 0; k--) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        kin_inertia_mul(jt->I, nd->v.s.acc, f);
        /* the bodies' terms, their norms summed: I (a - g) and the weight m |g| (in
         * a free fall both are 0 and m |g|, and so are the joint forces) */
        tsum += (fabs(f[0]) + fabs(f[1]) + fabs(f[2])) * il + fabs(f[3]) + fabs(f[4]) + fabs(f[5]) +
                jt->I[KIN_PC] * gn;
        for (i = 0; i < 6; i++) f[i] += nd->pA[i];
        {
            const double e = kin_joint_residual(L, jt, f, il, r ? r + jt->voff : NULL); /* torques by 1/l */
            rmax = fmax(rmax, e);
            bad |= !(e == e); /* fmax drops a NaN */
        }
        smax = fmax(smax, (fabs(f[0]) + fabs(f[1]) + fabs(f[2])) * il + fabs(f[3]) + fabs(f[4]) + fabs(f[5]));
        if (forces) memcpy(L->cforce + 6 * (size_t)jt->joint, f, sizeof f);
        if (jt->parent >= 0) {
            double t[6], *fp = a->node[jt->parent].pA;
            spatial_xform_force_back(&nd->X, f, t);
            for (i = 0; i < 6; i++) fp[i] += t[i];
        }
        memset(nd->pA, 0, sizeof nd->pA);
    }
    smax = fmax(smax, tsum);
    if (bad || !isfinite(smax)) return NAN;
    return smax > 0.0 ? rmax / smax : (rmax > 0.0 ? INFINITY : 0.0);
}

/* dq = ABA^-1(r) by the solve's factors, its accelerations into da:
 * backward, the bias forces of r alone (u = r - S^T pA, pa = pA + U D^-1 u);
 * forward from rest, dq = D^-1 (u - U^T X da_p). */
static void correction(aqs_linkage *L, const double *r, double *dq, double *da)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    double S[36], Dinv[36], w[6];
    int32_t k, i, j;
    for (k = m->ne - 1; k >= 0; k--) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        double pa[6], *u = dq + jt->voff;
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            const double *U = nd->v.s.U;
            u[0] = r[jt->voff] - nd->pA[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5];
            w[0] = u[0] * nd->Dinv;
            for (i = 0; i < 6; i++) pa[i] = nd->pA[i] + U[i] * w[0];
        } else if (jt->type != AQS_JOINT_FIXED) {
            const int d = joint_nv(jt->type);
            const double *U = a->Um + 6 * a->moff[k];
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            (void)dense_joint_space_inverse(S, U, d, Dinv); /* succeeded in the solve */
            for (j = 0; j < d; j++) {
                double s = 0.0;
                for (i = 0; i < 6; i++) s += S[i * d + j] * nd->pA[i];
                u[j] = r[jt->voff + j] - s;
            }
            for (j = 0; j < d; j++) {
                double v = 0.0;
                for (i = 0; i < d; i++) v += Dinv[d * j + i] * u[i];
                w[j] = v;
            }
            for (i = 0; i < 6; i++) {
                double v = nd->pA[i];
                for (j = 0; j < d; j++) v += U[6 * j + i] * w[j];
                pa[i] = v;
            }
        } else {
            memcpy(pa, nd->pA, sizeof pa);
        }
        if (jt->parent >= 0) {
            double t[6], *fp = a->node[jt->parent].pA;
            spatial_xform_force_back(&nd->X, pa, t);
            for (i = 0; i < 6; i++) fp[i] += t[i];
        }
        memset(nd->pA, 0, sizeof nd->pA);
    }
    for (k = 0; k < m->ne; k++) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        double *ac = da + 6 * (size_t)k, *q = dq + jt->voff;
        if (jt->parent < 0) memset(ac, 0, 6 * sizeof(double));
        else spatial_xform_motion(&nd->X, da + 6 * (size_t)jt->parent, ac);
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            const double *U = nd->v.s.U;
            q[0] = (q[0] - (U[0] * ac[0] + U[1] * ac[1] + U[2] * ac[2] + U[3] * ac[3] + U[4] * ac[4] + U[5] * ac[5])) *
                   nd->Dinv;
            ac[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5] += q[0];
        } else if (jt->type != AQS_JOINT_FIXED) {
            const int d = joint_nv(jt->type);
            const double *U = a->Um + 6 * a->moff[k];
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            (void)dense_joint_space_inverse(S, U, d, Dinv);
            if (jt->type == AQS_JOINT_FREE) dense_free_accel(Dinv, q, ac, q); /* q holds u */
            else dense_joint_accel(S, U, Dinv, d, q, ac, q); /* q holds u from the backward pass */
        }
    }
}

int32_t aba_refine(aqs_linkage *L, double balance)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    struct aba_refine *R;
    const size_t nvb = (size_t)L->nv * sizeof(double);
    double res, next;
    int32_t kept = 0, it, k, i;
    if (L->refine_max <= 0 || !(balance > ABA_REFINE_LEVEL * RND_U) || !isfinite(balance)) return 0;
    R = refine_arrays(L);
    if (!R) return 0; /* out of memory: the unrefined answer stands */
    res = residual(L, R->r, 0);
    for (it = 0; it < L->refine_max; it++) {
        correction(L, R->r, R->dq, R->da);
        memcpy(R->q0, L->qdd, nvb);
        for (k = 0; k < m->ne; k++) {
            double *ac = a->node[k].v.s.acc;
            memcpy(R->a0 + 6 * (size_t)k, ac, 6 * sizeof(double));
            for (i = 0; i < 6; i++) ac[i] += R->da[6 * (size_t)k + i];
        }
        for (i = 0; i < L->nv; i++) L->qdd[i] += R->dq[i];
        next = residual(L, R->r, 0);
        if (!(next < res)) { /* not better: the previous answer back, bit for bit */
            memcpy(L->qdd, R->q0, nvb);
            for (k = 0; k < m->ne; k++) memcpy(a->node[k].v.s.acc, R->a0 + 6 * (size_t)k, 6 * sizeof(double));
            break;
        }
        kept++;
        res = next;
    }
    /* The forces: the inverse dynamics' of the refined accelerations (the
     * solve's own, f = IA a + pA, are what the balance found unbalanced) */
    if (kept) (void)residual(L, NULL, 1);
    return kept;
}
