/*
 * urdf.h -- write a linkage as URDF (for aqs-bench --export-urdf and
 * bench/urdf_export.c). Read back with bindings/python/aqs/urdf.py.
 *
 * The file describes the model at q = 0 in the layout of the Python
 * save_urdf: a massless root link "world"; link "link_<i>" per body i with
 * its inertial (origin at the centre of mass, rpy 0, the body-frame inertia
 * about the centre of mass); joint "joint_<j>" per joint j with origin xyz
 * (the joint frame in the parent frame) and rpy (R = Rz(yaw) Ry(pitch)
 * Rx(roll), from the joint quaternion), parent, child and axis. aqs revolute
 * joints are written as "continuous", prismatic ones with limits +-1e300,
 * free joints as "floating", planar as "planar", fixed as "fixed"; spherical,
 * universal and cylindrical joints have no URDF equivalent. Every number is
 * printed with %.17g, so the values read back are the doubles written (the
 * rpy angles round-trip the joint rotation to a few ulp).
 */
#ifndef BENCH_URDF_H
#define BENCH_URDF_H

#include <stddef.h>

#include "aqs.h"

/** Write linkage (any phase) to path as URDF, robot name robot_name (NULL:
 *  "aqs"; written as is, so without XML special characters). On failure returns AQS_EINVAL (NULL argument, a joint type URDF
 *  cannot express, a file that cannot be written) or the status of a failed
 *  read-back, and writes a message to message (message_size bytes; message
 *  may be NULL). A partly written file is removed. */
aqs_status bench_export_urdf(const aqs_linkage *linkage, const char *path,
                             const char *robot_name, char *message, size_t message_size);

/** (roll, pitch, yaw) with R(quat) = Rz(yaw) Ry(pitch) Rx(roll), pitch in
 *  [-pi/2, pi/2], roll and yaw in [-pi, pi], from the quaternion's
 *  half-angle sums (as the Python quat_to_rpy). quat: (w, x, y, z), unit. */
void bench_quat_to_rpy(const double quat[4], double rpy[3]);

#endif /* BENCH_URDF_H */
