/* cost.h -- per-node costs of the two solve paths, in instructions, for the
 * automatic choice between them (src/solve/autopath.c, docs/api.md "Automatic
 * path"). The one place these numbers live: when a kernel gets cheaper,
 * re-run tools/calibrate_cost.py (callgrind on the 5,000-joint molecule; it
 * prints these lines, each the inclusive instruction count per call of the
 * kernel named below) and paste its output here.
 *
 * Counted, not timed: the choice then depends on counts only, so a run is
 * reproducible (the same positions and loads take the same path on every
 * machine and at any load). Calibrated 2026-12-03 by tools/calibrate_cost.py
 * --joints 5000 --steps 12 (docs/bench.md, "The automatic path", recalibrated after the
 * AVX and bit-for-bit node work: the square-root node 28.8 k -> 14.7 k), gcc 12,
 * -O2 -funroll-loops, on a processor with AVX (the SSE2 path's node costs ~1.2x). */
#ifndef AQS_COST_H
#define AQS_COST_H

#include "linkage.h"

/* An internal node's DCA coefficients (dca_node_update), by DCA form
 * (AQS_DCA_FORM_SQRT, the default, and AQS_DCA_FORM_PHI; the square-root
 * node 14,710 before its empty row copies were skipped, 2026-12-06). */
#define COST_DCA_NODE_SQRT 14340.0
#define COST_DCA_NODE_PHI 8010.0
/* An internal node's total-acceleration factor (totalacc_node_update;
 * 5,070 before dca_mw_apply's SSE2 lanes, 2026-12-06). */
#define COST_FACTOR 4850.0
/* A node processed by the adaptive solve: its back-substitution
 * (dca_node_backsub_sums in the square-root form), one totalacc_eval, one
 * heap_push and heap_pop (tools/calibrate_cost.py: 1,280, 2026-12-06). */
#define COST_PROCESS 1260.0
/* A node moved by an adaptive step: joint_integrate, frames_node. */
#define COST_MOVE 490.0
/* The refinement of an adaptive solve's computed joints (arefine_solve), per
 * processed node, and what a node update adds once the linkage keeps its load
 * factors (docs/math.md §13c). Not from tools/calibrate_cost.py: callgrind on
 * `autocount_main adaptive 5000 N_f 20` with every solve refined, 2026-12-04
 * (arefine_solve 4.4 k per processed node at N_f = 1, 5.8 k at N_f = 10; the
 * node updates +36 M over 31,296, E^T E and the copies). */
#define COST_AREFINE 5500.0
#define COST_KEEP_FACTORS 1150.0
/* The exact step by the articulated-body algorithm, per effective joint:
 * its solve (solve_body: the loads' update, aba_solve's pass and checks;
 * counted by the work meter in aba_solve) and the rest of the step (the
 * move: joint_integrate, the positions' update). tools/calibrate_cost.py on
 * an exact run of the molecule, 2026-12-06 (1,532 and 110; before, 1,700
 * and 40: the pass from aqs-bench's run plus the later additions, and the
 * move without the positions' update, together 6 % above the step's 1,642). */
#define COST_ABA_JOINT 1530.0
#define COST_ABA_MOVE 110.0

/* The work meter: an exact solve's passes add their cost to L->ap.work as
 * they run (cost_count), and src/api/api.c's exact_solve keeps the count of
 * the last exact solve as the exact path's cost (autopath.c), so that the
 * model prices what that solve did: the articulated-body pass alone
 * (COST_ABA_JOINT a joint, counted in aba_solve), or refined (a linkage with
 * a heavy child refines every solve: 2.6 .. 5.7x the pass alone on the
 * molecule with heavy atoms), or handed over to the exact DCA (the stale
 * nodes' update as autopath_update_cost prices it, COST_PROCESS a processed
 * node, COST_AREFINE a node of the adaptive refinement, and the refinement's
 * passes below). Counted against callgrind (docs/bench.md, "The automatic
 * path on heavy linkages"): the refined articulated-body solve within 1 %,
 * the exact DCA's refined solve 10 % low (its Krylov vectors are not
 * counted). Per call, inclusive, from tools/calibrate_cost.py's runs of
 * bench/autocount_main (fma double-double; without fma the double-double
 * passes cost ~1.6x, docs/math.md 5b):
 *   per effective joint: the articulated-body refinement's correction
 *   (abarefine.c, with the refinement's copies of its state), a
 *   double-double residual (residual_dd_eval), the bodies' double-double
 *   accelerations (residual_dd_accelerations, residual_dd_acc_add), a
 *   residual pass in double (residual_eval, residual_mass_mul,
 *   residual_balance; residual_accelerations alone counts half);
 *   per node: the exact DCA refinement's correction (refine.c: each internal
 *   node's update, COST_DCA_NODE_*, or its loads, COST_NODE_LOADS, and its
 *   back-substitution, COST_BACKSUB: dca_node_backsub per call in the exact
 *   DCA's refinement, 630 since 2026-12-06; 730 before, measured on the
 *   adaptive steps, whose back-substitution is now dca_node_backsub_sums). */
#define COST_ABA_CORRECTION 510.0
#define COST_DD_RESIDUAL 1390.0
#define COST_DD_ACCEL 450.0
#define COST_RESIDUAL 300.0
#define COST_BACKSUB 630.0
#define COST_NODE_LOADS 900.0

static inline void cost_count(aqs_linkage *L, double instructions) { L->ap.work += instructions; }
/* per_joint times the effective joints */
static inline void cost_count_joints(aqs_linkage *L, double per_joint)
{
    L->ap.work += per_joint * (double)L->m.ne;
}
/* An internal node's DCA coefficients in the linkage's form (and its load
 * factors kept, once it keeps them). */
static inline double cost_node(const aqs_linkage *L)
{
    if (L->dca_form == AQS_DCA_FORM_PHI) return COST_DCA_NODE_PHI;
    return COST_DCA_NODE_SQRT + (L->t.lf ? COST_KEEP_FACTORS : 0.0);
}

#endif
