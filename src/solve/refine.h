/* refine.h -- iterative refinement of the exact DCA solve (docs/math.md
 * §13a): corrections by the DCA itself, with the joint-space residual of
 * src/solve/residual.c as its only load. */
#ifndef AQS_REFINE_H
#define AQS_REFINE_H

#include "linkage.h"

/* After an exact DCA solve (adaptive_solve with eps = 0 and no cap, the
 * coefficients current): the joint forces and accelerations refined by the
 * DCA's own residual first (arefine_solve over every node, which from then on
 * has the node updates keep their load factors), then up to L->refine_max
 * GMRES cycles on L->qdd, each kept only when it is finite and lowers the
 * residual's 2-norm; L->cforce holds the first refinement's forces (when it
 * converged; else the unrefined ones), or the inverse dynamics' forces of the
 * refined accelerations where their estimated error is at the rounding level
 * or below the unrefined forces' (fixed joints' included; see FORCES in
 * refine.c). The DCA's stored b, rho, gamma and rounding levels
 * are those of the unrefined solve again on return, its handle forces the
 * first refinement's; the solve's stats are not changed. Its arrays are
 * allocated at the first call that refines; if that allocation fails the
 * answer is left unrefined (L->s.refined 0, no error: a solve or step never
 * fails for the refinement's memory), and the next call tries again. */
void refine_exact(aqs_linkage *L);
void refine_free(aqs_linkage *L);

#endif
