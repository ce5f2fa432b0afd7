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
/* The spatial inertia of a composite (its frame, 6x6) from the solver's
 * packed copy. */
void aba_comp_inertia(const aqs_linkage *L, int32_t comp, double I[36]);
/* The joint frame of effective joint e in its parent composite's frame. */
const pose *aba_eff_place(const aqs_linkage *L, int32_t e);
/* Every composite's world pose at the current positions into the solver's
 * scratch (valid until the next solve), then aba_body_world per body. */
void aba_world_poses(aqs_linkage *L);
void aba_body_world(const aqs_linkage *L, int32_t body, pose *P);
/* The world pose of a composite's frame from the positions, composing the
 * joints' poses up the kinematic tree: O(depth), no tree poses read. */
void aba_comp_world_walk(const aqs_linkage *L, int32_t comp, pose *P);

#endif
