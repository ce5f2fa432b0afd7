/* cost.h -- per-node costs of the two solve paths, in instructions, for the
 * automatic choice between them (src/autopath.c, docs/api.md "Automatic
 * path"). The one place these numbers live: when a kernel gets cheaper,
 * re-run tools/calibrate_cost.sh (callgrind on the 5,000-joint molecule; it
 * prints these lines) and paste its output here.
 *
 * Counted, not timed: the choice then depends on counts only, so a run is
 * reproducible (the same positions and loads take the same path on every
 * machine and at any load). Calibrated 2026-12-02 on branch auto (commit
 * in docs/bench.md, "Automatic path"), gcc 12 -O2. */
#ifndef AQS_COST_H
#define AQS_COST_H

/* An internal node's DCA coefficients (dca_node_update), by DCA form. */
#define COST_DCA_NODE_SQRT 23200.0
#define COST_DCA_NODE_PHI 5600.0
/* An internal node's total-acceleration factor (totalacc_node_update). */
#define COST_FACTOR 8000.0
/* A node processed by the adaptive solve: back-substitution, the A of its
 * children, the heap. */
#define COST_PROCESS 2300.0
/* A node moved by an adaptive step: its joint integrated, its frames. */
#define COST_MOVE 600.0
/* The exact solve by the articulated-body algorithm, per effective joint. */
#define COST_ABA_JOINT 2800.0
/* An exact step's move, per effective joint: every joint integrated, every
 * node's frames (update_all_poses). */
#define COST_ABA_MOVE 530.0

#endif
