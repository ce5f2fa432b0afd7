/* abarefine.h -- iterative refinement of the articulated-body solve where
 * its residual says it lost digits (src/solve/abarefine.c; docs/math.md
 * §5b). */
#ifndef AQS_ABAREFINE_H
#define AQS_ABAREFINE_H

#include "linkage.h"

/* The bodies' force balance (aba.c's forward pass), in units of u, above
 * which a solve is refined. */
#define ABA_REFINE_LEVEL 16.0
/* The balance is also measured against this multiple of the largest joint
 * force (linear rows), where that is smaller than the largest term and not
 * below 2^-10 of it: a balance above ABA_REFINE_LEVEL x ABA_FORCE_SCALE u
 * (256 u) of the joint forces refines (docs/math.md §5b, "Against the joint
 * forces"). */
#define ABA_FORCE_SCALE 16.0

/* After aba_solve's forward pass (L->qdd, the nodes' accelerations and
 * L->cforce set): measure the residual and refine where it exceeds the
 * level, at most L->refine_max corrections. Returns the corrections kept
 * (their forces then in L->cforce). Out of memory: 0, the answer as it was. */
int32_t aba_refine(aqs_linkage *L, double balance);
/* Release the refinement's arrays (at destroy and when the model changes). */
void aba_refine_free(aqs_linkage *L);

#endif
