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
/* The poses and inertias read from the solver's order: kintree.h. */

#endif
