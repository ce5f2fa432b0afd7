/* aba.h -- the exact quasi-static solve by Featherstone's articulated-body
 * algorithm over the kinematic tree of composites (docs/math.md, "Exact
 * solve by the articulated-body algorithm"). */
#ifndef AQS_ABA_H
#define AQS_ABA_H

#include "linkage.h"

/* The scratch arrays and the joint order, at finalize. AQS_OK or AQS_ENOMEM. */
aqs_status aba_alloc(aqs_linkage *L);
void aba_free(aqs_linkage *L);
/* Every joint's acceleration and constraint force (L->qdd, L->cforce) from
 * the current positions and loads, O(N), without the assembly tree's
 * coefficients (which stay as they are: stale marks are kept). Sets L->s
 * as an exact solve. Returns AQS_OK, or AQS_ENUMERIC (message set) when an
 * articulated inertia is numerically singular. */
aqs_status aba_solve(aqs_linkage *L);
/* The world pose of a composite's frame from the solve's own pose sweep:
 * valid only while L->aba.world_valid (update_loads inside aba_solve). */
void aba_comp_world(const aqs_linkage *L, int32_t comp, pose *P);
/* The same by composing the solve's poses up the kinematic tree, O(depth):
 * valid only while L->aba.x_valid (the welded bodies' loads in aba_solve). */
void aba_comp_world_walk(const aqs_linkage *L, int32_t comp, pose *P);

#endif
