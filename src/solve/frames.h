/* frames.h -- hierarchical frames (MATH.md §9.2): the handle poses of the
 * assembly tree's nodes, world poses on request, and a body load in its
 * composite's frame. */
#ifndef AQS_FRAMES_H
#define AQS_FRAMES_H

#include "linkage.h"

/* Cross poses of an internal node from its children and q_k, and J(q_k)
 * itself (the child frame of k in its joint frame, which dca_node_update
 * reads): call whenever q_k or a position inside the node changes. */
void frames_node(aqs_linkage *L, int32_t n);
/* Cross poses of the node of effective joint e and its ancestors. O(log N).
 * Nothing while every pose is stale (frames_poses recomputes them all). */
void frames_from_joint(aqs_linkage *L, int32_t e);
/* Every position may have moved: the internal poses follow at once when
 * collision shapes exist (their bounding spheres follow the poses), else
 * they are left stale until frames_poses; the coefficients and the
 * world-frame loads are marked stale either way. */
void frames_positions_moved(aqs_linkage *L);
/* The tree's poses exist (allocated on first use, O(N) memory: an exact
 * solve by the articulated-body algorithm never reads the internal ones)
 * with every leaf's set (constant); the internal ones may be stale. AQS_OK
 * or AQS_ENOMEM (message set, nothing changed). */
aqs_status frames_poses_alloc(aqs_linkage *L);
/* The internal poses too, recomputed if stale: before anything reads them
 * (the DCA update, world poses through the tree, collision). O(N) when
 * stale. AQS_OK or AQS_ENOMEM (from frames_poses_alloc). */
aqs_status frames_poses(aqs_linkage *L);

/* The world leaf's frame in the world (tree.world_frame): the world's origin
 * turned as the joint frame of the first joint its leaf holds (in the aligned
 * frames), constant. The
 * grounded nodes' poses are in this frame, not the world's; the world's
 * acceleration -g, world poses and world-fixed shapes are turned into it
 * and out of it where they meet the tree. */
void frames_world_frame(const aqs_linkage *L, pose *W);
/* The pose of a leaf's handle h in its composite's frame (the world's for
 * the world leaf, whose stored poses are in world_frame). */
void frames_leaf_handle(const aqs_linkage *L, int32_t leaf, int32_t h, pose *P);

/* World pose of a composite's frame (world: identity), O(log N) through
 * the tree's poses (recomputed first if stale: O(N) once); O(depth) up the
 * kinematic tree when the tree holds no poses, or inside an exact solve. */
void frames_comp_world(aqs_linkage *L, int32_t comp, pose *P);
/* World pose of a body, O(log N). */
void frames_body_world(aqs_linkage *L, int32_t body, pose *P);

/* The load of a body as a spatial force in its composite's frame, given the
 * composite's world pose. */
void frames_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                         double f[6]);

#endif
