/* kintree.c -- poses and inertias read from the kinematic tree in
 * depth-first order (kintree.h), kept in the aligned frames and turned back
 * to the composites' frames for everyone else. */
#include "kintree.h"

#include <float.h>

/* P <- P C^T: a pose of an aligned frame made the pose of its composite's
 * frame. */
static void unalign_pose(const aba_joint *jt, pose *P)
{
    double C[9], R[9];
    int i;
    if (!kin_align(jt, C)) return;
    for (i = 0; i < 3; i++) {
        const double r0 = P->R[3 * i], r1 = P->R[3 * i + 1], r2 = P->R[3 * i + 2];
        R[3 * i] = r0 * C[0] + r1 * C[1] + r2 * C[2];
        R[3 * i + 1] = r0 * C[3] + r1 * C[4] + r2 * C[5];
        R[3 * i + 2] = r0 * C[6] + r1 * C[7] + r2 * C[8];
    }
    memcpy(P->R, R, sizeof R);
}

/* Entries within 4 u of the exact zeros and ones of a frame sharing its
 * parent's z axis (or its negative) are set to them: R's third row and
 * column, and p's z when it is within 4 u |p|. The rounding of C_p^T R C
 * is of that size; leaving it would couple the plane of a planar chain to
 * its O(n^3) out-of-plane inertia at every joint. */
static void snap_planar(pose *P)
{
    double *R = P->R, *p = P->p;
    const double tol = 4.0 * DBL_EPSILON;
    if (fabs(R[2]) > tol || fabs(R[5]) > tol || fabs(R[6]) > tol || fabs(R[7]) > tol || fabs(fabs(R[8]) - 1.0) > tol)
        return;
    R[2] = R[5] = R[6] = R[7] = 0.0;
    R[8] = R[8] > 0.0 ? 1.0 : -1.0;
    if (fabs(p[2]) <= tol * sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])) p[2] = 0.0;
}

void kin_align_place(aba_joint *jt, const double *Cp, const pose *place_user, const double *I_user)
{
    double C[9], T[9];
    pose P;
    int i;
    P = *place_user;
    if (Cp) { /* P.R <- Cp^T R, P.p <- Cp^T p */
        mat3_tvec(Cp, place_user->p, P.p);
        for (i = 0; i < 3; i++) {
            double col[3] = {place_user->R[i], place_user->R[3 + i], place_user->R[6 + i]}, o[3];
            mat3_tvec(Cp, col, o);
            P.R[i] = o[0], P.R[3 + i] = o[1], P.R[6 + i] = o[2];
        }
    }
    if (kin_align(jt, C)) {
        double I[36];
        pose Ct; /* the composite's frame in the aligned one: (C^T, 0) */
        mat3_mul(P.R, C, T);
        memcpy(P.R, T, sizeof T);
        for (i = 0; i < 9; i++) Ct.R[i] = C[3 * (i % 3) + i / 3];
        Ct.p[0] = Ct.p[1] = Ct.p[2] = 0.0;
        spatial_inertia_to_parent(&Ct, I_user, I);
        kin_pack_inertia(I, jt->I);
    } else {
        kin_pack_inertia(I_user, jt->I);
    }
    snap_planar(&P);
    jt->place = P;
}

void kin_comp_world(const aqs_linkage *L, int32_t comp, pose *P)
{
    const int32_t k = L->aba.pos_of_comp[comp];
    *P = L->aba.node[k].v.world;
    unalign_pose(&L->aba.joint[k], P);
}

void kin_comp_inertia(const aqs_linkage *L, int32_t comp, double I[36])
{
    const aba_joint *jt = &L->aba.joint[L->aba.pos_of_comp[comp]];
    double C[9];
    if (kin_align(jt, C)) {
        double F[36];
        pose Cp = {{0}, {0, 0, 0}}; /* the aligned frame in the composite's: (C, 0) */
        memcpy(Cp.R, C, sizeof C);
        kin_unpack_inertia(jt->I, F);
        spatial_inertia_to_parent(&Cp, F, I);
    } else {
        kin_unpack_inertia(jt->I, I);
    }
}

void kin_eff_place(const aqs_linkage *L, int32_t e, pose *P)
{
    const aba_state *a = &L->aba;
    const aba_joint *jt = &a->joint[a->pos_of_comp[L->m.eff_child[e]]];
    double C[9];
    *P = jt->place;
    unalign_pose(jt, P); /* place_user = C_p place C^T */
    if (jt->parent >= 0 && kin_align(&a->joint[jt->parent], C)) {
        pose t = *P;
        mat3_vec(C, t.p, P->p);
        mat3_mul(C, t.R, P->R);
    }
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
    pose W;
    if (c == m->ncomp) {
        *P = *model_body_in_comp(m, body); /* welded to the world: its pose there */
        return;
    }
    kin_comp_world(L, c, &W);
    pose_compose(&W, model_body_in_comp(m, body), P);
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
    unalign_pose(&a->joint[a->pos_of_comp[comp]], P);
}
