/* abarefine.h -- iterative refinement of the articulated-body solve where
 * its residual says it lost digits (src/solve/abarefine.c; docs/math.md
 * §5b). */
#ifndef AQS_ABAREFINE_H
#define AQS_ABAREFINE_H

#include "linkage.h"

/* The bodies' force balance (aba.c's forward pass), in units of u, above
 * which a solve is refined. */
#define ABA_REFINE_LEVEL 16.0

/* After aba_solve's forward pass (L->qdd, the nodes' accelerations and
 * L->cforce set): measure the residual and refine where it exceeds the
 * level, at most L->refine_max corrections. Returns the corrections kept
 * (their forces then in L->cforce). Out of memory: 0, the answer as it was. */
int32_t aba_refine(aqs_linkage *L, double balance);
/* Release the refinement's arrays (at destroy and when the model changes). */
void aba_refine_free(aqs_linkage *L);

#endif
