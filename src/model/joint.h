/* joint.h -- joint types: sizes, the child frame as a function of q, the
 * motion subspace S (in the child frame), integration on the manifold. */
#ifndef AQS_JOINT_H
#define AQS_JOINT_H

#include <stdint.h>

#include "spatial.h"

#define JOINT_TYPE_COUNT 8

/* One joint as added by the user (axis normalized; u, v complete it). */
typedef struct {
    int32_t type, parent, child;
    double pos[3], quat[4], axis[3], u[3], v[3];
    int32_t qoff, voff; /* offsets in the bulk position / acceleration arrays */
    double limits[4];   /* lower, upper, effort, velocity (aqs_joint_set_limits); kept, not enforced */
} joint_def;

int joint_nq(int32_t type);
int joint_nv(int32_t type);
const char *joint_type_name(int32_t type);
/* Whether the type uses its axis (revolute, prismatic, universal, cylindrical, planar). */
int joint_uses_axis(int32_t type);

/* The completing directions of the header: e = coordinate axis of the
 * smallest |a_i|, u = normalize(e - (e.a) a), v = a x u. */
void joint_directions(const double a[3], double u[3], double v[3]);

/* The zero position (identity quaternions). */
void joint_zero_position(int32_t type, double *q);
/* Validate a position given by the user: finite, quaternions unit within
 * UNIT_QUAT_TOLERANCE (check.h). Writes the normalized position to out.
 * Returns 0, or the index of the first bad value (>= 1, one-based) as a
 * positive number, or -1 for a quaternion of wrong norm. */
int joint_check_position(int32_t type, const double *q, double *out);

/* The aligned frames (docs/math.md §13b). A joint that uses an axis
 * (joint_uses_axis) is solved in its frames turned by C = [u v axis] (the
 * columns; a rotation): its joint frame becomes joint frame C and its child
 * composite's frame child frame C, where its axis is e_z and u, v are e_x,
 * e_y. C into C (row-major); returns 0 (C unset) when the joint uses no axis
 * or C is the identity. */
int joint_align_rotation(const joint_def *j, double C[9]);
/* The joint as the solvers see it in its aligned frames: j with axis, u, v
 * replaced by e_z, e_x, e_y when it uses an axis. */
void joint_aligned(const joint_def *j, joint_def *out);
/* joint_child_pose and joint_subspace of joint_aligned(j): J(q) and S in the
 * aligned frames, what every solver uses. */
void joint_child_pose_aligned(const joint_def *j, const double *q, pose *P);
void joint_subspace_aligned(const joint_def *j, const double *q, double *S);

/* Pose of the child frame in the joint frame at position q. */
void joint_child_pose(const joint_def *j, const double *q, pose *P);
/* Motion subspace S (6 x nv, row-major) in the child frame at position q. */
void joint_subspace(const joint_def *j, const double *q, double *S);
/* q <- q (+) h * qdd: additive for scalar coordinates; for spherical and free
 * joints a body-frame rotation vector h * qdd[0..2] (free: the translation
 * moves by R_old * h * qdd[3..5]). */
void joint_integrate(const joint_def *j, double *q, const double *qdd, double h);

#endif
