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
/* Each joint's Q - S^T f (f = I^A a + p^A, its force on the child, which
 * satisfies S^T f = Q in exact arithmetic) is measured against this multiple
 * of the largest joint force (where the joint forces are not below 2^-20 of
 * the largest term): above ABA_REFINE_LEVEL x ABA_PROJ_SCALE u (1,024 u) the
 * solve refines (docs/math.md §5b, "The joints' own equations"). */
#define ABA_PROJ_SCALE 64.0

/* A correction is kept when the next one, formed from the residual it
 * leaves, is at most ABA_REFINE_RATE times as large (the iteration
 * contracts). A correction of at most ABA_REFINE_SMALL u of the largest
 * acceleration is not applied and ends the joint accelerations' refinement
 * (as the first one: the solve's answer stays as it is; docs/math.md §5b,
 * "The residual in double-double"). */
#define ABA_REFINE_RATE 0.5
#define ABA_REFINE_SMALL 4.0
/* aba_polish (src/solve/aba.c) trusts the factors for the forces alone where
 * their own answer agrees with the exact DCA's to this many u of the largest
 * acceleration: 1.8e-16 .. 1.1e-15 where their forces were better (planar
 * chains of 1 and 1e9 kg out of their plane), 3e-12 .. 1e-3 where they were
 * worse (3.3 .. 10x; light planar or spherical joints holding 1e3 .. 1e9 kg). */
#define ABA_POLISH_AGREE 64.0
/* After aba_solve's forward pass (L->qdd, the nodes' accelerations and
 * L->cforce set): where the balance exceeds the level, or always on a
 * linkage with a heavy child (heavy), refine the joint accelerations (at
 * most L->refine_max corrections) and then the forces (the inverse
 * dynamics' of the bodies' accelerations, refined on their own); a heavy
 * child's balanced solve whose first correction is at the rounding level
 * keeps its answer and forces. Returns the corrections of the joint
 * accelerations kept. Out of memory: 0, the answer as it was. Where the
 * first correction is not finite, or the refinement stops short of the
 * rounding level (a correction that does not contract, or L->refine_max of
 * them used up), the factors do not hold the digits: L->aba.lost is set
 * (else cleared), the forces are left unrefined, and the caller answers by
 * the exact DCA (src/api/api.c, exact_solve). */
int32_t aba_refine(aqs_linkage *L, double balance, int heavy);
/* The double-double residual's 2-norm at the joint accelerations in L->qdd
 * (the exact DCA's refinement's measure, src/solve/refine.c); NaN when not
 * finite or out of memory. */
double aba_refine_residual(aqs_linkage *L);
/* Release the refinement's arrays (at destroy and when the model changes). */
void aba_refine_free(aqs_linkage *L);

#endif
