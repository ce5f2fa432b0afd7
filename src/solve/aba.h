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
/* The fixed joints' forces from the moving joints' forces in L->cforce (the
 * composites with welded bodies, through dca_welded_forces_comp): after
 * aba_solve, and after a refined exact DCA solve (src/solve/refine.c). */
void aba_welded_forces(aqs_linkage *L);
/* The exact DCA's answer in L->qdd, of double-double residual norm rn,
 * refined by the articulated-body factors (src/solve/refine.c, on a linkage
 * with a heavy child; docs/math.md 13a, "Corrections by the articulated-body
 * factors"): the pass made at the current positions and loads, then, where
 * accel, its corrections from that answer (aba_refine), kept only where they
 * contracted to the rounding level and lowered the residual; the forces
 * (L->cforce) refined as the articulated-body solve refines them, at the
 * accelerations kept. Returns the corrections kept (0: the DCA's
 * accelerations, refined forces), or -1 where the factors cannot (a
 * singular articulated inertia, a correction that does not contract, out of
 * memory): L->qdd and L->cforce are then not the answer (the caller keeps a
 * copy). The solve's stats (nodes and factors updated) are left as they
 * were. */
int32_t aba_polish(aqs_linkage *L, const double *start, double level);
/* The poses and inertias read from the solver's order: kintree.h. */

#endif
