/* kintree.c -- poses and inertias read from the kinematic tree in
 * depth-first order (kintree.h). */
#include "kintree.h"

double kin_joint_residual_general(const aqs_linkage *L, const aba_joint *jt, const double *f, double il, double *r)
{
    double S[36], e = 0.0;
    const int d = joint_nv(jt->type);
    int i, j;
    if (d == 0) return 0.0;
    joint_subspace_aligned(&L->joints[jt->joint], L->q + jt->qoff, S);
    for (j = 0; j < d; j++) {
        double s = 0.0, v;
        for (i = 0; i < 6; i++) s += S[i * d + j] * f[i];
        v = L->tau[jt->voff + j] - s;
        if (r) r[j] = v;
        v = fabs(v);
        if (S[0 * d + j] != 0.0 || S[1 * d + j] != 0.0 || S[2 * d + j] != 0.0) v *= il;
        if (!(v <= e)) e = v; /* NaN too */
    }
    return e;
}

void kin_joint_turn(const joint_def *j, int transpose, pose *P)
{
    double C[9];
    int i;
    pose_identity(P);
    if (!joint_align_rotation(j, C)) return;
    for (i = 0; i < 9; i++) P->R[i] = transpose ? C[3 * (i % 3) + i / 3] : C[i];
}

void kin_body_in_comp(const aqs_linkage *L, int32_t body, pose *P)
{
    const model *m = &L->m;
    if (m->body_in_comp) *P = m->body_in_comp[body];
    else kin_joint_turn(&L->joints[m->parent_joint[body]], 1, P); /* no welded body: every body a root */
}

void kin_comp_world(const aqs_linkage *L, int32_t comp, pose *P)
{
    *P = L->aba.node[L->aba.pos_of_comp[comp]].v.world;
}

void kin_comp_inertia(const aqs_linkage *L, int32_t comp, double I[36])
{
    kin_unpack_inertia(L->aba.joint[L->aba.pos_of_comp[comp]].I, I);
}

const pose *kin_eff_place(const aqs_linkage *L, int32_t e)
{
    return &L->aba.joint[L->aba.pos_of_comp[L->m.eff_child[e]]].place;
}

void kin_world_poses(aqs_linkage *L)
{
    aba_state *a = &L->aba;
    int32_t k;
    for (k = 0; k < L->m.ne; k++) {
        const aba_joint *jt = &a->joint[k];
        pose X;
        kin_joint_pose(L, jt, &X);
        if (jt->parent < 0) a->node[k].v.world = X;
        else pose_compose(&a->node[jt->parent].v.world, &X, &a->node[k].v.world);
    }
}

void kin_body_world(const aqs_linkage *L, int32_t body, pose *P)
{
    const model *m = &L->m;
    int32_t c = m->comp_of_body[body];
    pose B;
    kin_body_in_comp(L, body, &B);
    if (c == m->ncomp) *P = B; /* welded to the world: its pose there */
    else pose_compose(&L->aba.node[L->aba.pos_of_comp[c]].v.world, &B, P);
}

void kin_comp_world_walk(const aqs_linkage *L, int32_t comp, pose *P)
{
    const aba_state *a = &L->aba;
    int32_t k;
    pose_identity(P);
    if (comp == L->m.ncomp) return;
    for (k = a->pos_of_comp[comp]; k >= 0; k = a->joint[k].parent) {
        pose X, t;
        kin_joint_pose(L, &a->joint[k], &X);
        pose_compose(&X, P, &t);
        *P = t;
    }
}
