/* kintree.h -- the kinematic tree of composites in depth-first order (the
 * articulated-body solver's order, L->aba; built by aba_alloc): the
 * per-joint constants it keeps (joint placements, packed inertias) and the
 * poses computed from them and the positions, without the assembly tree.
 * Below the solvers: the model's inertia readers and the frames use it. */
#ifndef AQS_KINTREE_H
#define AQS_KINTREE_H

#include <math.h>
#include <string.h>

#include "joint.h"
#include "linkage.h"

/* Packed symmetric 6x6 [A B; B^T C]: offsets of A, B, C. */
enum { KIN_PA = 0, KIN_PB = 6, KIN_PC = 15 };

static inline void kin_unpack_inertia(const double *P, double *F)
{
    int i, j, n = 0;
    for (i = 0; i < 3; i++)
        for (j = i; j < 3; j++) {
            F[6 * i + j] = F[6 * j + i] = P[KIN_PA + n];
            F[6 * (3 + i) + 3 + j] = F[6 * (3 + j) + 3 + i] = P[KIN_PC + n];
            n++;
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) F[6 * i + 3 + j] = F[6 * (3 + j) + i] = P[KIN_PB + 3 * i + j];
}

static inline void kin_pack_inertia(const double *F, double *P)
{
    int i, j, n = 0;
    for (i = 0; i < 3; i++)
        for (j = i; j < 3; j++) {
            P[KIN_PA + n] = F[6 * i + j];
            P[KIN_PC + n] = F[6 * (3 + i) + 3 + j];
            n++;
        }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++) P[KIN_PB + 3 * i + j] = F[6 * i + 3 + j];
}

/* o = I v for a packed spatial inertia I. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void kin_inertia_mul(const double *I, const double *v, double *o)
{
    const double *A = I + KIN_PA, *B = I + KIN_PB, *C = I + KIN_PC;
    o[0] = A[0] * v[0] + A[1] * v[1] + A[2] * v[2] + B[0] * v[3] + B[1] * v[4] + B[2] * v[5];
    o[1] = A[1] * v[0] + A[3] * v[1] + A[4] * v[2] + B[3] * v[3] + B[4] * v[4] + B[5] * v[5];
    o[2] = A[2] * v[0] + A[4] * v[1] + A[5] * v[2] + B[6] * v[3] + B[7] * v[4] + B[8] * v[5];
    o[3] = B[0] * v[0] + B[3] * v[1] + B[6] * v[2] + C[0] * v[3] + C[1] * v[4] + C[2] * v[5];
    o[4] = B[1] * v[0] + B[4] * v[1] + B[7] * v[2] + C[1] * v[3] + C[3] * v[4] + C[4] * v[5];
    o[5] = B[2] * v[0] + B[5] * v[1] + B[8] * v[2] + C[2] * v[3] + C[4] * v[4] + C[5] * v[5];
}

/* X: the composite's frame in its parent's, the placement composed with
 * J(q). The frames are the aligned ones (joint.h, docs/math.md §13b): a
 * revolute joint's J(q) is a turn about z, a prismatic one's a shift along
 * z, written out; the others take joint_child_pose of the aligned joint. */
static inline void kin_joint_pose(const aqs_linkage *L, const aba_joint *jt, pose *X)
{
    const double *R = jt->place.R, *q = L->q + jt->qoff;
    int i;
    if (jt->type == AQS_JOINT_REVOLUTE) {
        const double c = cos(q[0]), s = sin(q[0]);
        for (i = 0; i < 3; i++) {
            X->R[3 * i] = R[3 * i] * c + R[3 * i + 1] * s;
            X->R[3 * i + 1] = R[3 * i + 1] * c - R[3 * i] * s;
            X->R[3 * i + 2] = R[3 * i + 2];
        }
        memcpy(X->p, jt->place.p, sizeof X->p);
    } else if (jt->type == AQS_JOINT_PRISMATIC) {
        memcpy(X->R, R, sizeof X->R);
        for (i = 0; i < 3; i++) X->p[i] = jt->place.p[i] + R[3 * i + 2] * q[0];
    } else {
        pose J;
        joint_child_pose_aligned(&L->joints[jt->joint], q, &J);
        pose_compose(&jt->place, &J, X);
    }
}

/* Position jt's joint equation Q - S^T f (f: the joint's force on its
 * child, in its aligned frame; S likewise), slot by slot into r when not
 * NULL. Returns the largest |Q_j - S_j^T f|, a torque slot (an angular
 * column of S) weighed by il; NaN when one is NaN. A revolute or prismatic
 * joint inline (S = e_z), the others through kin_joint_residual_general. */
double kin_joint_residual_general(const aqs_linkage *L, const aba_joint *jt, const double *f, double il, double *r);
static inline double kin_joint_residual(const aqs_linkage *L, const aba_joint *jt, const double *f, double il,
                                        double *r)
{
    if (jt->type == AQS_JOINT_REVOLUTE || jt->type == AQS_JOINT_PRISMATIC) {
        const double e = L->tau[jt->voff] - f[jt->type == AQS_JOINT_REVOLUTE ? 2 : 5];
        if (r) r[0] = e;
        return fabs(e) * (jt->type == AQS_JOINT_REVOLUTE ? il : 1.0);
    }
    return kin_joint_residual_general(L, jt, f, il, r);
}

/* (C, 0) for joint j (transpose 0) or (C^T, 0) (transpose 1): the pose of its
 * aligned frames in its own frames, or the inverse; the identity when C is
 * (joint_align_rotation). */
void kin_joint_turn(const joint_def *j, int transpose, pose *P);
/* A body's frame in its composite's frame. A composite's frame is its root
 * body's frame turned by the C of the root's joint (the aligned frames,
 * joint.h and docs/math.md §13b), so a root body's pose in it is (C^T, 0):
 * from model.body_in_comp when that is held (welded bodies), else from the
 * joint's axis. */
void kin_body_in_comp(const aqs_linkage *L, int32_t body, pose *P);

/* The world pose of a composite's frame from the exact solve's own pose
 * sweep: valid only while L->aba.world_valid (update_loads inside aba_solve). */
void kin_comp_world(const aqs_linkage *L, int32_t comp, pose *P);
/* The spatial inertia of a composite (its frame, 6x6) from the solver's
 * packed copy. */
void kin_comp_inertia(const aqs_linkage *L, int32_t comp, double I[36]);
/* The (aligned) joint frame of effective joint e in its parent composite's frame. */
const pose *kin_eff_place(const aqs_linkage *L, int32_t e);
/* Every composite's world pose at the current positions into the solver's
 * scratch (valid until the next solve), then kin_body_world per body. */
void kin_world_poses(aqs_linkage *L);
void kin_body_world(const aqs_linkage *L, int32_t body, pose *P);
/* The world pose of a composite's frame from the positions, composing the
 * joints' poses up the kinematic tree: O(depth), no tree poses read. */
void kin_comp_world_walk(const aqs_linkage *L, int32_t comp, pose *P);

#endif
