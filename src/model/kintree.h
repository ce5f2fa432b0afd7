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

/* The aligned frames (docs/math.md §13b). Position k's solver frame is its
 * composite's frame turned by C_k, a rotation with C_k e_z = the joint's axis
 * for revolute and prismatic joints (the identity for the others), so that
 * the joint's motion subspace is e_z (revolute: [e_z; 0], prismatic:
 * [0; e_z]) and J(q) a turn about z or a shift along it. aba_joint.place and
 * .I are kept in these frames: place = C_p^T place_user C_k, with its
 * out-of-plane entries set to exact zeros where the two axes are parallel to
 * the rounding (kin_align_place), and I = C_k^T I_user C_k. Parallel axes
 * then give transforms that never mix the plane of the motion with the rest,
 * bit for bit, which is what keeps a long planar chain in oblique frames
 * accurate: in the composite's own frames its O(n^3) out-of-plane inertia
 * and its O(1) in-plane inertia share every entry. */

/* C (row-major) for an axis a (unit): the smallest rotation taking e_z to a,
 * C = I + [k]x + [k]x^2 / (1 + a_z) with k = e_z x a, written out; for a_z < 0
 * the one taking e_z to -a with its x and y columns negated (a turn by pi
 * about x first), so that 1 + |a_z| >= 1 never cancels. Exact (a signed
 * permutation) when a is a coordinate axis. Returns 0 when C is the
 * identity (a = e_z), 1 otherwise. */
static inline int kin_axis_rotation(const double a[3], double C[9])
{
    const double s = a[2] < 0.0 ? -1.0 : 1.0;
    const double x = s * a[0], y = s * a[1], h = 1.0 / (1.0 + s * a[2]);
    C[0] = 1.0 - x * x * h, C[1] = -s * (x * y * h), C[2] = a[0];
    C[3] = -(x * y * h), C[4] = s * (1.0 - y * y * h), C[5] = a[1];
    C[6] = -x, C[7] = -s * y, C[8] = a[2];
    return !(a[0] == 0.0 && a[1] == 0.0 && a[2] == 1.0);
}

/* C_k of a position; 0 when it is the identity (C then unset). */
static inline int kin_align(const aba_joint *jt, double C[9])
{
    if (jt->type != AQS_JOINT_REVOLUTE && jt->type != AQS_JOINT_PRISMATIC) return 0;
    return kin_axis_rotation(jt->axis, C);
}

/* v <- C v for a spatial vector (both halves): from the aligned frame to
 * the composite's. */
static inline void kin_unalign_vec(const double C[9], double *v)
{
    int h;
    for (h = 0; h < 6; h += 3) {
        const double a = v[h], b = v[h + 1], c = v[h + 2];
        v[h] = C[0] * a + C[1] * b + C[2] * c;
        v[h + 1] = C[3] * a + C[4] * b + C[5] * c;
        v[h + 2] = C[6] * a + C[7] * b + C[8] * c;
    }
}

/* v <- C^T v (both halves): from the composite's frame to the aligned one. */
static inline void kin_align_vec(const double C[9], double *v)
{
    int h;
    for (h = 0; h < 6; h += 3) {
        const double a = v[h], b = v[h + 1], c = v[h + 2];
        v[h] = C[0] * a + C[3] * b + C[6] * c;
        v[h + 1] = C[1] * a + C[4] * b + C[7] * c;
        v[h + 2] = C[2] * a + C[5] * b + C[8] * c;
    }
}

/* X: the position's aligned frame in its parent's, the placement composed
 * with J(q): for revolute joints place R_z(q), for prismatic place T(q e_z),
 * written out; the others (C the identity) place J(q). */
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
        joint_child_pose(&L->joints[jt->joint], q, &J);
        pose_compose(&jt->place, &J, X);
    }
}

/* The placement and inertia of a position in its aligned frames, from the
 * composite-frame ones (aba_alloc): place_user in the parent composite's
 * frame, Cp the parent's C (NULL: the identity), I_user unpacked 6x6; into
 * jt->place and jt->I (packed). */
void kin_align_place(aba_joint *jt, const double *Cp, const pose *place_user, const double *I_user);

/* The world pose of a composite's frame from the exact solve's own pose
 * sweep: valid only while L->aba.world_valid (update_loads inside aba_solve). */
void kin_comp_world(const aqs_linkage *L, int32_t comp, pose *P);
/* The spatial inertia of a composite (its frame, 6x6) from the solver's
 * packed copy. */
void kin_comp_inertia(const aqs_linkage *L, int32_t comp, double I[36]);
/* The joint frame of effective joint e in its parent composite's frame
 * (from the aligned placement: the user's to the rounding). */
void kin_eff_place(const aqs_linkage *L, int32_t e, pose *P);
/* Every composite's world pose at the current positions into the solver's
 * scratch (valid until the next solve), then kin_body_world per body. */
void kin_world_poses(aqs_linkage *L);
void kin_body_world(const aqs_linkage *L, int32_t body, pose *P);
/* The world pose of a composite's frame from the positions, composing the
 * joints' poses up the kinematic tree: O(depth), no tree poses read. */
void kin_comp_world_walk(const aqs_linkage *L, int32_t comp, pose *P);

#endif
