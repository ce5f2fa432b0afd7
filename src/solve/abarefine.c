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
 *   r   = Q - S^T f,  f_c = I_c a_c - f_ext,c + sum_children X^T f_child,
 *         a_c = X a_p + S qdd (inverse dynamics from the joint
 *         accelerations, in double-double, rounded once: src/base/ddouble.h)
 *   dq  = ABA^-1(r): the articulated-body solve with r as the only load (no
 *         gravity, no external force) by the factors the solve kept (U,
 *         D^-1, the poses): bias forces backward, accelerations forward
 *   qdd += dq
 * A first correction at the rounding level ends it, the answer kept; else a
 * correction is kept when the next one is at most half as large (the
 * iteration contracts: on a heavy body held by light links the residual
 * cannot measure the error, a rounding of the heavy joints' accelerations
 * leaving a larger one than the light links' whole error), and one at the
 * rounding level ends it unapplied; at most L->refine_max of them
 * (aqs_linkage_set_exact_refinement, which also switches the balance off at
 * 0). The forces: the bodies' accelerations are refined on their own
 * against the same residual (they carry digits below the joint
 * accelerations' rounding, which the inverse dynamics' forces of a heavy
 * subtree far from its joint need), and the solve takes the inverse
 * dynamics' forces of them. A heavy child's solve (always refined) whose
 * first correction is at the rounding level and whose balance holds keeps
 * its own forces.
 * Scratch: the nodes' pA (zero between solves, left zero) and, once a solve
 * refines, the arrays of struct aba_refine (LK_MEM_EXACT, kept). */
#include "abarefine.h"

#include <math.h>
#include <string.h>

#include "cost.h"
#include "ddouble.h"
#include "dense.h"
#include "kintree.h"
#include "residual.h"
#include "rounding.h"

struct aba_refine {
    ddouble *acc; /* 6 ne: the bodies' accelerations (minus g) in double-double */
    ddouble *f;   /* 6 ne: the joint forces in double-double (children's added first) */
    double *r;    /* nv: the residual */
    double *dq;   /* nv: a correction (the loads pass's u first) */
    double *q0;   /* nv: the accelerations before the correction */
    double *r0;   /* nv: their residual */
    double *da0;  /* 6 ne: its correction's bodies' accelerations */
    ddouble *acc0; /* 6 ne: R->acc before a correction of the forces' refinement */
    double *fcur; /* 6 ne: the joint forces of R->acc's state, ABA order */
    double *ftry; /* 6 ne: those of a correction tried */
    double *da;   /* 6 ne: the correction's accelerations */
};

void aba_refine_free(aqs_linkage *L)
{
    struct aba_refine *R = L->abarf;
    if (!R) return;
    lk_free(L, R->acc);
    lk_free(L, R->f);
    lk_free(L, R->r);
    lk_free(L, R->dq);
    lk_free(L, R->q0);
    lk_free(L, R->r0);
    lk_free(L, R->da0);
    lk_free(L, R->acc0);
    lk_free(L, R->fcur);
    lk_free(L, R->ftry);
    lk_free(L, R->da);
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
    R->acc = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(ddouble));
    R->f = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(ddouble));
    R->r = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->dq = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->q0 = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->r0 = lk_calloc_in(L, LK_MEM_EXACT, nv, sizeof(double));
    R->da0 = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    R->acc0 = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(ddouble));
    R->fcur = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    R->ftry = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    R->da = lk_calloc_in(L, LK_MEM_EXACT, ne6, sizeof(double));
    if (!R->acc || !R->f || !R->r || !R->dq || !R->q0 || !R->r0 || !R->da0 || !R->acc0 || !R->fcur || !R->ftry || !R->da) {
        aba_refine_free(L);
        return NULL;
    }
    residual_dd_select(L);
    return R;
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
    cost_count_joints(L, COST_ABA_CORRECTION);
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

/* max |v_i| over nv entries (NaN when one is NaN). */
static double max_abs(const double *v, int32_t n)
{
    double e = 0.0;
    int32_t i;
    for (i = 0; i < n; i++)
        if (!(fabs(v[i]) <= e)) e = fabs(v[i]);
    return e;
}

/* The forces' refinement: the bodies' accelerations R->acc (double-double,
 * from the refined joint accelerations; with R->r their residual, rn its
 * measure, and R->da the correction's accelerations from it), refined on
 * their own against the same residual, a correction kept while it lowers the
 * residual (at most L->refine_max), the last where the next would not move
 * the forces (residual_forces_settled); then the inverse dynamics' forces of
 * them into L->cforce and the bodies' accelerations into the nodes. The
 * joint accelerations are left as they are: the bodies' accelerations carry
 * digits below the joint accelerations' rounding, which the inverse
 * dynamics' forces of a heavy subtree far from its joint need (docs/math.md
 * 5b, "The forces of a refined solve"). */
static void refine_forces(aqs_linkage *L, struct aba_refine *R, double rn)
{
    const size_t n6 = 6 * (size_t)L->m.ne;
    double next, *tmp;
    size_t i;
    int32_t it;
    int settled;
    L->aba.fkept = 0;
    for (it = 0; it < L->refine_max; it++) {
        if (it > 0) correction(L, R->r, R->dq, R->da);
        memcpy(R->acc0, R->acc, n6 * sizeof(ddouble));
        for (i = 0; i < n6; i++) R->acc[i] = dd_add(R->acc[i], dd_from(R->da[i]));
        next = residual_dd_eval(L, R->acc, R->f, R->r, R->ftry);
        if (!(next < rn)) {
            memcpy(R->acc, R->acc0, n6 * sizeof(ddouble));
            break;
        }
        L->aba.fkept++;
        settled = residual_forces_settled(R->ftry, R->fcur, n6, next / rn);
        tmp = R->fcur, R->fcur = R->ftry, R->ftry = tmp;
        rn = next;
        if (settled) break; /* the next correction would not move the forces */
    }
    for (i = 0; i < n6; i++) {
        L->aba.node[i / 6].v.s.acc[i % 6] = dd_to_double(R->acc[i]);
        L->cforce[6 * (size_t)L->aba.joint[i / 6].joint + i % 6] = R->fcur[i];
    }
}

double aba_refine_residual(aqs_linkage *L)
{
    struct aba_refine *R = refine_arrays(L);
    return R ? residual_dd_norm(L, L->qdd, R->acc, R->f, R->r) : NAN;
}

int32_t aba_refine(aqs_linkage *L, double balance, int heavy)
{
    struct aba_refine *R;
    const size_t nvb = (size_t)L->nv * sizeof(double), n6 = 6 * (size_t)L->m.ne;
    double step, next, rn;
    int32_t kept = 0, it, i;
    const int unbalanced = balance > ABA_REFINE_LEVEL * RND_U;
    L->aba.lost = 0;
    L->aba.fkept = 0; /* (also where the arrays cannot be allocated: aba_polish reads it) */
    if (L->refine_max <= 0 || !(unbalanced || heavy) || !isfinite(balance)) return 0;
    R = refine_arrays(L);
    if (!R) return 0; /* out of memory: the unrefined answer stands */
    residual_dd_accelerations(L, L->qdd, R->acc);
    rn = residual_dd_eval(L, R->acc, R->f, R->r, R->fcur);
    correction(L, R->r, R->dq, R->da);
    step = max_abs(R->dq, L->nv);
    if (!isfinite(rn)) return 0;
    if (!isfinite(step)) { /* the factors cannot correct a finite residual */
        L->aba.lost = 1;
        return 0;
    }
    /* a first correction at the rounding level: the solve had the digits
     * the problem has and keeps its joint accelerations; its forces are
     * refined where the balance says they lost digits (R->acc, R->r and
     * R->da are those of its state) */
    if (step <= ABA_REFINE_SMALL * RND_U * max_abs(L->qdd, L->nv)) {
        if (unbalanced) refine_forces(L, R, rn);
        return 0;
    }
    for (it = 0; it < L->refine_max; it++) {
        const double rn0 = rn;
        memcpy(R->q0, L->qdd, nvb); /* the state, to go back to */
        memcpy(R->acc0, R->acc, n6 * sizeof(ddouble));
        memcpy(R->r0, R->r, nvb);
        memcpy(R->da0, R->da, n6 * sizeof(double));
        memcpy(R->ftry, R->fcur, n6 * sizeof(double));
        for (i = 0; i < L->nv; i++) L->qdd[i] += R->dq[i];
        residual_dd_accelerations(L, L->qdd, R->acc);
        rn = residual_dd_eval(L, R->acc, R->f, R->r, R->fcur);
        correction(L, R->r, R->dq, R->da);
        next = max_abs(R->dq, L->nv);
        if (!(next <= ABA_REFINE_RATE * step)) { /* no contraction: the previous answer back, bit for bit */
            memcpy(L->qdd, R->q0, nvb);
            memcpy(R->acc, R->acc0, n6 * sizeof(ddouble));
            memcpy(R->r, R->r0, nvb);
            memcpy(R->da, R->da0, n6 * sizeof(double));
            memcpy(R->fcur, R->ftry, n6 * sizeof(double));
            rn = rn0;
            break;
        }
        kept++;
        step = next;
        if (step <= ABA_REFINE_SMALL * RND_U * max_abs(L->qdd, L->nv)) break; /* the next at the rounding level */
    }
    if (!(step <= ABA_REFINE_SMALL * RND_U * max_abs(L->qdd, L->nv))) {
        /* it stopped short of the rounding level (no contraction, or
         * L->refine_max corrections): the factors do not hold the digits */
        L->aba.lost = 1;
        return kept;
    }
    refine_forces(L, R, rn);
    return kept;
}
