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
/* The exact DCA's answer (start, nv values) corrected by the articulated-body
 * factors (src/solve/refine.c, on a linkage with a heavy child; docs/math.md
 * 13a, "Corrections by the articulated-body factors"): the pass at the
 * current positions and loads, then its refinement (aba_refine) started
 * from start. Kept, in L->qdd and L->cforce: corrected accelerations where
 * the corrections contracted to the rounding level and left the
 * double-double residual at most level, with the forces refined at them; or
 * start with the refined forces where no correction of the accelerations
 * was needed, the forces' corrections lowered the bodies' residual and the
 * pass's own answer agrees with start to ABA_POLISH_AGREE u of its largest
 * entry. Returns the corrections of the accelerations kept (0: start), or
 * -1 where nothing is kept (a singular articulated inertia, corrections
 * that do not contract, factors that disagree, out of memory): L->qdd and
 * L->cforce are then not the answer (the caller keeps a copy).
 * aqs_linkage_last_error is left as it was. */
int32_t aba_polish(aqs_linkage *L, const double *start, double level);
/* The poses and inertias read from the solver's order: kintree.h. */

#endif
