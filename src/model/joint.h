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

/* Pose of the child frame in the joint frame at position q. */
void joint_child_pose(const joint_def *j, const double *q, pose *P);
/* Motion subspace S (6 x nv, row-major) in the child frame at position q. */
void joint_subspace(const joint_def *j, const double *q, double *S);
/* q <- q (+) h * qdd: additive for scalar coordinates; for spherical and free
 * joints a body-frame rotation vector h * qdd[0..2] (free: the translation
 * moves by R_old * h * qdd[3..5]). */
void joint_integrate(const joint_def *j, double *q, const double *qdd, double h);

#endif
