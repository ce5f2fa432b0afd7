/* check.h -- error messages and the argument checks shared by the entry
 * points (api.c, collide_api.c): each check returns AQS_OK or records a message
 * naming the function, the argument and the value, and returns the status. */
#ifndef AQS_CHECK_H
#define AQS_CHECK_H

#include "linkage.h"

/* A user's quaternion counts as unit when its norm is within this of 1
 * (aqs_joint_add, positions of spherical and free joints, shape placements). */
#define UNIT_QUAT_TOLERANCE 1e-6

/* 1 if q's norm (into *norm) is within UNIT_QUAT_TOLERANCE of 1 (NaN: 0). */
int check_quat_is_unit(const double q[4], double *norm);

/* v non-NULL and its n values finite. */
aqs_status check_vec(aqs_linkage *L, const char *fn, const char *name, const double *v, int n);
/* q (finite) unit within UNIT_QUAT_TOLERANCE; its norm into *norm. */
aqs_status check_unit_quat(aqs_linkage *L, const char *fn, const char *name, const double q[4],
                           double *norm);
/* The linkage is finalized (AQS_ESTATE otherwise). */
aqs_status check_finalized(aqs_linkage *L, const char *fn);
/* A size-versioned struct of a getter (aqs_solve_stats, aqs_collision_stats,
 * aqs_memory_stats): stats non-NULL, its first member (uint32_t size, into *size)
 * at least 8. */
aqs_status check_stats_size(aqs_linkage *L, const char *fn, const void *stats, uint32_t *size);

#endif
