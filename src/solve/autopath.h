/* autopath.h -- the automatic choice, solve by solve, between the adaptive
 * solver and the exact articulated-body solve, from a cost model counted in
 * instructions (src/solve/cost.h) and the counts of the last solves
 * (docs/api.md, "aqs_linkage_set_auto"). */
#ifndef AQS_AUTOPATH_H
#define AQS_AUTOPATH_H

#include "linkage.h"

/* Defaults at creation: on, nothing known. */
void autopath_init(aqs_linkage *L);
/* Forget the counts (a tolerance, a cap, the prediction or the mode
 * changed): the next solve is adaptive and teaches the model again. */
void autopath_reset(aqs_linkage *L);
/* Whether the model chooses the path of the next solve: on, eps > 0, no
 * cap, something that can move, and counts known. */
int autopath_applies(const aqs_linkage *L);
/* At the end of a step, before the update after its move: whether the
 * next step would be exact once that update is done (the stale nodes are
 * then the moved ones, none after it); if so the update is skipped (an
 * exact step does not need it). Changes nothing. */
int autopath_prefers_exact(const aqs_linkage *L, int stepping);
/* What the next update_coefficients would cost (instructions): the stale
 * internal nodes' coefficients and factors (a predicted node's factor is
 * skipped). Read by the model and by the exact solve's work meter (cost.h)
 * when the exact path hands over to the DCA. */
double autopath_update_cost(const aqs_linkage *L);
/* Decide the next solve's path (1: exact) and keep the regret of the
 * exact choices current. Call only when autopath_applies. */
int autopath_decide(aqs_linkage *L, int stepping);
/* Who made the whole tree stale: an exact step's move (own = 1: the cost
 * of switching back, paid once) or the caller, e.g. set_positions (own = 0:
 * an adaptive solve would pay it too, so it is no reason to stay exact). */
void autopath_tree_moved(aqs_linkage *L, int own);
/* After a successful solve: learn its counts (an adaptive solve's, or, for
 * an exact one while a tolerance is set, an estimate from its
 * accelerations) and record its path (AQS_PATH_*) and whether the model
 * chose it. */
void autopath_after_solve(aqs_linkage *L, int32_t path, int chose);

#endif
