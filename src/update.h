/* update.h -- hierarchical frames (MATH.md §9.2), world poses on request,
 * re-expression of world-frame loads, and the coefficient update (§9.1). */
#ifndef AQS_UPDATE_H
#define AQS_UPDATE_H

#include "linkage.h"

/* Handle-frame poses of a leaf in its composite's frame (constant). */
void update_leaf_poses(aqs_linkage *L, int32_t n);
/* Cross poses of an internal node from its children and q_k, and J(q_k)
 * itself (the child frame of k in its joint frame, which dca_node_update
 * reads): call whenever q_k or a position inside the node changes. */
void update_node_poses(aqs_linkage *L, int32_t n);
/* All internal nodes' cross poses, children first. O(N). */
void update_all_poses(aqs_linkage *L);
/* Cross poses of the node of effective joint e and its ancestors. O(log N).
 * Nothing while every pose is stale (update_poses recomputes them all). */
void update_poses_from_joint(aqs_linkage *L, int32_t e);
/* Every position may have moved: the internal poses follow at once when
 * collision shapes exist (their bounding spheres follow the poses), else
 * they are left stale until update_poses; the coefficients and the
 * world-frame loads are marked stale either way. */
void update_positions_moved(aqs_linkage *L);
/* The tree's poses exist (allocated on first use, O(N) memory: an exact
 * solve by the articulated-body algorithm never reads the internal ones)
 * with every leaf's set (constant); the internal ones may be stale. AQS_OK
 * or AQS_ENOMEM (message set, nothing changed). */
aqs_status update_poses_alloc(aqs_linkage *L);
/* The internal poses too, recomputed if stale: before anything reads them
 * (the DCA update, world poses through the tree, collision). O(N) when
 * stale. AQS_OK or AQS_ENOMEM (from update_poses_alloc). */
aqs_status update_poses(aqs_linkage *L);

/* World pose of a composite's frame (world: identity), O(log N) through
 * the tree's poses (recomputed first if stale: O(N) once); O(depth) up the
 * kinematic tree when the tree holds no poses, or inside an exact solve. */
void update_comp_pose_world(aqs_linkage *L, int32_t comp, pose *P);
/* World pose of a body, O(log N). */
void update_body_pose_world(aqs_linkage *L, int32_t body, pose *P);

/* The load of a body as a spatial force in its composite's frame, given the
 * composite's world pose. */
void update_body_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                              double f[6]);
/* Mark node n and its ancestors stale (MATH.md §9.1). O(log N), less when
 * an ancestor is already marked. */
void update_mark(aqs_linkage *L, int32_t n);
/* When loads changed (or positions moved, loads_dirty): re-express every
 * body load in its composite's frame, refresh those leaves (and the world
 * leaf when gravity changed) and mark their ancestors. O(N_U log N). */
void update_loads(aqs_linkage *L);
/* Recompute the stale nodes, children first: Phi, b and the DCA terms, and
 * the total-acceleration factors when enabled. Returns AQS_OK or
 * AQS_ENUMERIC (message set; the stale marks remain). */
aqs_status update_coefficients(aqs_linkage *L);

#endif
