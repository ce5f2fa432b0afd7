/* arefine.h -- iterative refinement of an adaptive solve's computed joints
 * (docs/math.md §13c): corrections by the DCA on the processed nodes, with the
 * residual of the reduced system (the queued subtrees and leaves held by their
 * coefficients) as their only load. */
#ifndef AQS_AREFINE_H
#define AQS_AREFINE_H

#include "linkage.h"

/* After an adaptive solve (square-root form, the coefficients current; also
 * one that processed every node, for the exact refinement's joint forces,
 * src/solve/refine.c): up
 * to L->refine_max corrections of the computed joints' accelerations,
 * constraint forces and the handle forces of the processed nodes and their
 * children (the queued nodes' included), each kept only when it lowers the
 * reduced system's residual; the joint forces have converged (*converged
 * set to 1, when converged is not NULL) when the last correction, kept or
 * not, moved none by more than 64 u of the largest, or the residual reached
 * 0, or each correction after the first moved them by at most 1/16 of what
 * the first did. The stored b,
 * rho, gamma and rounding levels are the solve's again on return. Returns the
 * corrections kept (0: nothing changed; also when out of memory, and the next
 * call tries again). */
int32_t arefine_solve(aqs_linkage *L, int *converged);
/* The refinement's arrays (and the nodes' load factors), if not held yet.
 * Returns 0, or -1 when out of memory (nothing kept). */
int arefine_alloc(aqs_linkage *L);
void arefine_free(aqs_linkage *L);

#endif
