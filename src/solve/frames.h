/* frames.h -- hierarchical frames (MATH.md §9.2): the handle poses of the
 * assembly tree's nodes, world poses on request, and a body load in its
 * composite's frame. */
#ifndef AQS_FRAMES_H
#define AQS_FRAMES_H

#include "linkage.h"

/* Handle-frame poses of a leaf in its composite's frame (constant). */
void frames_leaf(aqs_linkage *L, int32_t n);
/* Cross poses of an internal node from its children and q_k, and J(q_k)
 * itself (the child frame of k in its joint frame, which dca_node_update
 * reads): call whenever q_k or a position inside the node changes. */
void frames_node(aqs_linkage *L, int32_t n);
/* All internal nodes' cross poses, children first. O(N). */
void frames_all(aqs_linkage *L);
/* Cross poses of the node of effective joint e and its ancestors. O(log N). */
void frames_from_joint(aqs_linkage *L, int32_t e);

/* World pose of a composite's frame (world: identity), O(log N). */
void frames_comp_world(const aqs_linkage *L, int32_t comp, pose *P);
/* World pose of a body, O(log N). */
void frames_body_world(const aqs_linkage *L, int32_t body, pose *P);
/* World poses of all bodies, parents before children, O(N). */
void frames_all_bodies_world(const aqs_linkage *L, pose *out);

/* The load of a body as a spatial force in its composite's frame, given the
 * composite's world pose. */
void frames_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                         double f[6]);

#endif
