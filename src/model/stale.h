/* stale.h -- the one owner of "what is stale". Every change to a finalized
 * linkage (positions, loads, gravity, tolerance and solver settings, shapes
 * and contacts, a solve that failed) is reported here, and this module alone
 * decides what it invalidates:
 *   - the readable results of the last solve (L->solved),
 *   - whether the last solve can still be refined (L->s.valid),
 *   - the composites' loads and the world leaf's gravity term
 *     (L->loads_dirty, L->gravity_dirty), recomputed by update_loads,
 *   - the assembly tree's coefficients (the marks of stale_mark and
 *     L->t.all_dirty), recomputed by update_coefficients.
 * The recomputations report back (stale_loads_fresh, stale_tree_fresh) so
 * that no other file writes those flags. */
#ifndef AQS_STALE_H
#define AQS_STALE_H

#include "linkage.h"

/* Positions moved: node n's coefficients and its ancestors' (n < 0: every
 * node), the world-frame loads (re-expressed in the moved frames). */
void stale_positions(aqs_linkage *L, int32_t n);
/* Body loads, contact settings or shapes changed (the composites' loads). */
void stale_loads(aqs_linkage *L);
/* Gravity changed (the world leaf). */
void stale_gravity(aqs_linkage *L);
/* A joint force changed: the node of its joint (n < 0: none, not finalized). */
void stale_joint_force(aqs_linkage *L, int32_t n);
/* Tolerance, cap, bound kind or exact solver changed: the last solve stays
 * readable but is no longer the one a refine would continue. */
void stale_settings(aqs_linkage *L);
/* Every coefficient, load and the gravity term (coefficients allocated or
 * recomputed from scratch: finalize, dca_enable, totalacc_enable, an exact
 * step by the articulated-body algorithm). */
void stale_tree(aqs_linkage *L);
/* A solve, refine or step failed numerically (AQS_ENUMERIC): its results
 * are not readable until the next successful solve (aqs.h). */
void stale_solve_failed(aqs_linkage *L);
/* A solve or refine succeeded: its results are readable. */
void stale_solve_done(aqs_linkage *L);
/* The adaptive solver's own view: a solve left a heap a refine can continue
 * (refinable = 1), or it started and has not finished (0). */
void stale_set_refinable(aqs_linkage *L, int refinable);

/* Mark node n and its ancestors stale (MATH.md §9.1): the dirty set that
 * update_coefficients recomputes. O(log N), less when an ancestor is already
 * marked (the set is top-closed). */
void stale_mark(aqs_linkage *L, int32_t n);

/* A full update recomputes every load and the gravity term as well. */
void stale_loads_all(aqs_linkage *L);

/* Reports of the recomputations (src/solve/update.c). */
void stale_gravity_fresh(aqs_linkage *L); /* update_loads: the world leaf's gravity term */
void stale_loads_fresh(aqs_linkage *L);   /* update_loads: the composites' loads */
void stale_tree_fresh(aqs_linkage *L);    /* update_coefficients: every marked node done */

#endif
