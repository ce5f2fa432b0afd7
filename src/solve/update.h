/* update.h -- re-expression of world-frame loads and the lazy coefficient
 * update (MATH.md §9.1); the frames are in frames.h. */
#ifndef AQS_UPDATE_H
#define AQS_UPDATE_H

#include "linkage.h"

/* When loads changed (or positions moved, loads_dirty): re-express every
 * body load in its composite's frame, refresh those leaves (and the world
 * leaf when gravity changed) and mark their ancestors. O(N_U log N). */
void update_loads(aqs_linkage *L);
/* The stale marks update_loads would make, the loads left to re-express
 * (the automatic path's decision on a moved tree; update.c). */
void update_mark_loads(aqs_linkage *L);
/* Recompute the stale nodes, children first: Phi, b and the DCA terms, and
 * the total-acceleration factors when enabled. Returns AQS_OK or
 * AQS_ENUMERIC (message set; the stale marks remain). */
aqs_status update_coefficients(aqs_linkage *L);

#endif
