/* residual.c -- the joint-space residual of a quasi-static solution (all
 * velocities zero), r = Q - ID(qdd), by the recursive Newton-Euler algorithm
 * over the articulated-body order (parents before children), in the
 * conventions of src/solve/aba.c: with X the motion transform from the parent
 * composite's frame to c's, S the joint's motion subspace and f_ext,c the
 * composite's external load in its frame,
 *   outward:  a_c = X a_p + S qdd   (the world moves with a_0 = -g)
 *             f_c = I_c a_c - f_ext,c
 *   inward:   f_p += X^T f_c,  r_e = Q_e - S^T f_c
 * f_c is then the force of joint e on c, L->cforce's convention. Every body's
 * inertia enters once and every load once: the residual of the
 * articulated-body solve's own answer is at the rounding level (tests/
 * test_refine.c). In working precision for the DCA's refinement: a residual
 * in double-double was measured to buy nothing it could use, at 7x the cost
 * (docs/math.md §13a). The articulated-body solve's refinement takes it in
 * double-double (residual_dd_*: on a heavy body held by light links the
 * heavy weights' rounding in double is the light links' whole residual,
 * docs/math.md §5b, "The residual in double-double"), and so does the exact
 * DCA's refinement of the bodies' accelerations for its forces (refine.c,
 * state_forces). The same pass at zero
 * gravity, no load and no joint force is the product M v by the joint-space
 * inertia matrix (residual_mass_mul, the operator of the refinement's
 * GMRES). Scratch: the articulated-body
 * solver's per-solve node values (X, and v.s for a_c and f_c), which every
 * solve that reads them rewrites first. */
#include "residual.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cost.h"
#include "kintree.h"

/* The larger of a (never NaN) and b, a NaN b dropped as fmax drops it: the
 * same value as fmax(a, b) without its library call (these run per joint). */
static inline double max_of(double a, double b) { return b > a ? b : a; }

void residual_poses(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    int32_t k;
    for (k = 0; k < L->m.ne; k++) kin_joint_pose(L, &a->joint[k], &a->node[k].X);
}

/* Outward: a_c = X a_p + S qdd into the node values (v.s.acc), from the
 * world's -g (homog = 0) or rest (homog = 1). */
static void outward(aqs_linkage *L, const double *qdd, int homog)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    double g[6], S[36];
    int32_t k, i, j;
    for (i = 0; i < 3; i++) {
        g[i] = 0.0;
        g[3 + i] = homog ? 0.0 : -L->gravity[i];
    }
    for (k = 0; k < m->ne; k++) {
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        const double *ap = jt->parent < 0 ? g : a->node[jt->parent].v.s.acc, *qd = qdd + jt->voff;
        double *ac = nd->v.s.acc;
        spatial_xform_motion(&nd->X, ap, ac);
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            ac[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5] += qd[0]; /* the aligned frame: S = e_z */
        } else {
            const int d = joint_nv(jt->type);
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            for (i = 0; i < 6; i++) {
                double v = 0.0;
                for (j = 0; j < d; j++) v += S[i * d + j] * qd[j];
                ac[i] += v;
            }
        }
    }
}

/* Inward from the node values' a_c: f_c = I_c a_c (minus the loads unless
 * homog) plus the children's, into v.s.U; r = Q - S^T f (homog: S^T f). */
static double inward(aqs_linkage *L, double *r, int homog)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    double sq = 0.0, S[36];
    int32_t k, i, j;
    for (k = 0; k < m->ne; k++) kin_inertia_mul(a->joint[k].I, a->node[k].v.s.acc, a->node[k].v.s.U);
    for (i = 0; i < (homog ? 0 : m->nloaded_comps); i++) { /* minus the loads (none on the world) */
        const int32_t c = m->loaded_comps[i];
        double *f = a->node[a->pos_of_comp[c]].v.s.U;
        for (j = 0; j < 6; j++) f[j] -= m->comp_force[6 * c + j];
    }
    for (k = m->ne - 1; k >= 0; k--) { /* inward: children's forces are in */
        const aba_joint *jt = &a->joint[k];
        aba_node *nd = &a->node[k];
        const double *f = nd->v.s.U, *Q = L->tau + jt->voff;
        double *rk = r + jt->voff;
        if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
            const double s = f[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5]; /* S^T f, S = e_z */
            rk[0] = homog ? s : Q[0] - s;
            sq += rk[0] * rk[0];
        } else {
            const int d = joint_nv(jt->type);
            joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
            for (j = 0; j < d; j++) {
                double s = 0.0;
                for (i = 0; i < 6; i++) s += S[i * d + j] * f[i];
                rk[j] = homog ? s : Q[j] - s;
                sq += rk[j] * rk[j];
            }
        }
        if (jt->parent >= 0) {
            double t[6], *fp = a->node[jt->parent].v.s.U;
            spatial_xform_force_back(&nd->X, f, t);
            for (i = 0; i < 6; i++) fp[i] += t[i];
        }
    }
    return sqrt(sq);
}

/* The pass of both: homog = 0, r = Q - ID(qdd) with gravity and the loads;
 * homog = 1, r = M qdd (no gravity, no load, no joint force, sign flipped). */
static double id_pass(aqs_linkage *L, const double *qdd, double *r, int homog)
{
    outward(L, qdd, homog);
    return inward(L, r, homog);
}

void residual_accelerations(aqs_linkage *L, const double *qdd)
{
    cost_count_joints(L, 0.5 * COST_RESIDUAL);
    outward(L, qdd, 0);
}

double residual_balance(aqs_linkage *L, const double *cforce, double *work, double *scale)
{
    const model *m = &L->m;
    aba_state *a = &L->aba;
    const double il = m->length > 0.0 ? 1.0 / m->length : 1.0;
    const double gn = sqrt(L->gravity[0] * L->gravity[0] + L->gravity[1] * L->gravity[1] + L->gravity[2] * L->gravity[2]);
    double bmax = 0.0, tmax = 0.0;
    int32_t k, i, j;
    int bad = 0;
    cost_count_joints(L, COST_RESIDUAL);
    for (k = 0; k < m->ne; k++) { /* -(I a_c) into v.s.U, |I a_c| into work */
        double *g = a->node[k].v.s.U, *h = work + 6 * (size_t)k;
        kin_inertia_mul(a->joint[k].I, a->node[k].v.s.acc, g);
        for (i = 0; i < 6; i++) {
            h[i] = fabs(g[i]);
            g[i] = -g[i];
        }
    }
    for (i = 0; i < m->nloaded_comps; i++) {
        const int32_t c = m->loaded_comps[i], k2 = a->pos_of_comp[c];
        for (j = 0; j < 6; j++) {
            a->node[k2].v.s.U[j] += m->comp_force[6 * c + j];
            work[6 * (size_t)k2 + j] += fabs(m->comp_force[6 * c + j]);
        }
    }
    for (k = m->ne - 1; k >= 0; k--) { /* children's forces are in */
        const aba_joint *jt = &a->joint[k];
        const double *f = cforce + 6 * (size_t)jt->joint;
        double *g = a->node[k].v.s.U, *h = work + 6 * (size_t)k, t[6], bn = 0.0, tn = jt->I[KIN_PC] * gn;
        for (i = 0; i < 6; i++) {
            g[i] += f[i];
            h[i] += fabs(f[i]);
        }
        for (i = 0; i < 6; i++) {
            const double w = i < 3 ? il : 1.0;
            bn += fabs(g[i]) * w;
            tn += h[i] * w;
        }
        bmax = max_of(bmax, bn);
        tmax = max_of(tmax, tn);
        bad |= !(bn == bn); /* max_of drops a NaN */
        if (jt->parent >= 0) {
            double *gp = a->node[jt->parent].v.s.U, *hp = work + 6 * (size_t)jt->parent;
            spatial_xform_force_back(&a->node[k].X, f, t);
            for (i = 0; i < 6; i++) {
                gp[i] -= t[i];
                hp[i] += fabs(t[i]);
            }
        }
    }
    *scale = tmax;
    return bad ? NAN : bmax;
}

double residual_eval(aqs_linkage *L, const double *qdd, double *r)
{
    cost_count_joints(L, COST_RESIDUAL);
    return id_pass(L, qdd, r, 0);
}

void residual_mass_mul(aqs_linkage *L, const double *v, double *Mv)
{
    cost_count_joints(L, COST_RESIDUAL);
    (void)id_pass(L, v, Mv, 1);
}

void residual_forces(const aqs_linkage *L, double *cforce)
{
    const aba_state *a = &L->aba;
    int32_t k;
    for (k = 0; k < L->m.ne; k++)
        memcpy(cforce + 6 * (size_t)a->joint[k].joint, a->node[k].v.s.U, 6 * sizeof(double));
}

/* The double-double passes (residual_dd.h), twice: Dekker's product, and
 * where the compiler can target it, fma's. */
#define DD_FN(name) name##_dekker
#define DD_TARGET
#define DD_ADD_MUL dd_add_mul
#define DD_ADD_PROD dd_add_prod
#include "residual_dd.h"
#undef DD_FN
#undef DD_TARGET
#undef DD_ADD_MUL
#undef DD_ADD_PROD
#ifdef DD_FMA_TARGET
#define DD_FN(name) name##_fma
#define DD_TARGET DD_FMA_TARGET
#define DD_ADD_MUL dd_add_mul_fma
#define DD_ADD_PROD dd_add_prod_fma
#include "residual_dd.h"
#undef DD_FN
#undef DD_TARGET
#undef DD_ADD_MUL
#undef DD_ADD_PROD
#endif

void residual_dd_select(aqs_linkage *L)
{
    L->dd_fma = 0;
#ifdef DD_FMA_TARGET
    {
        const char *e = getenv("AQS_SIMD");
        L->dd_fma = !(e && strcmp(e, "sse2") == 0) && __builtin_cpu_supports("fma") != 0;
    }
#endif
}

void residual_dd_accelerations(aqs_linkage *L, const double *qdd, ddouble *acc)
{
    cost_count_joints(L, COST_DD_ACCEL);
#ifdef DD_FMA_TARGET
    if (L->dd_fma) {
        dd_accelerations_fma(L, qdd, acc);
        return;
    }
#endif
    dd_accelerations_dekker(L, qdd, acc);
}

double residual_dd_eval(aqs_linkage *L, const ddouble *acc, ddouble *fw, double *r, double *forces)
{
    cost_count_joints(L, COST_DD_RESIDUAL);
#ifdef DD_FMA_TARGET
    if (L->dd_fma) return dd_eval_fma(L, acc, fw, r, forces);
#endif
    return dd_eval_dekker(L, acc, fw, r, forces);
}

double residual_dd_norm(aqs_linkage *L, const double *qdd, ddouble *acc, ddouble *fw, double *r)
{
    double s = 0.0;
    int32_t i;
    residual_dd_accelerations(L, qdd, acc);
    if (!isfinite(residual_dd_eval(L, acc, fw, r, NULL))) return NAN;
    for (i = 0; i < L->nv; i++) s += r[i] * r[i];
    return sqrt(s);
}

void residual_dd_acc_add(aqs_linkage *L, const double *dq, ddouble *acc)
{
    const aba_state *a = &L->aba;
    int32_t k, i;
    cost_count_joints(L, COST_DD_ACCEL);
    outward(L, dq, 1);
    for (k = 0; k < L->m.ne; k++)
        for (i = 0; i < 6; i++) acc[6 * (size_t)k + i] = dd_add(acc[6 * (size_t)k + i], dd_from(a->node[k].v.s.acc[i]));
}

int residual_forces_settled(const double *fnew, const double *fold, size_t n, double contraction)
{
    double dmax = 0.0, fmx = 0.0;
    size_t i;
    for (i = 0; i < n; i++) {
        dmax = max_of(dmax, fabs(fnew[i] - fold[i]));
        fmx = max_of(fmx, fabs(fnew[i]));
    }
    return dmax * contraction <= RESIDUAL_FORCE_STOP * 1.1102230246251565e-16 * fmx;
}
