/* dca.h -- articulated-body coefficients of the assembly tree's nodes and the
 * exact back-substitution (MATH.md §3). */
#ifndef AQS_DCA_H
#define AQS_DCA_H

#include "linkage.h"

/* Allocate the tree's DCA coefficients (Phi, b, handle forces, W, U, ...)
 * and compute the leaves' Phi, once: a linkage solved only exactly by the
 * articulated-body algorithm never needs them. Marks every node stale.
 * AQS_OK or AQS_ENOMEM (message naming fn). */
aqs_status dca_enable(aqs_linkage *L, const char *fn);
/* Leaf b from the composite's external load (world leaf: from gravity). */
void dca_leaf_b(aqs_linkage *L, int32_t n);
/* Internal node: X, W, U, rho, gamma, S, M, Phi, b from its children and
 * the principal joint's position and force. Returns 0, or -1 when the
 * articulated inertia is numerically singular. */
int dca_node_update(aqs_linkage *L, int32_t n);
/* Right after dca_node_update(L, n), from the products it left in the
 * scratch (valid until the next node update): out (6 nh) = M W g for a
 * 6-vector g, i.e. the handle part of g^T [W M^T], without forming W. */
void dca_mw_apply(const aqs_linkage *L, int32_t n, const double g[6], double *out);
/* Right after dca_node_update(L, n): out (6 nh) = row r < d of U M^T. */
void dca_um_row(const aqs_linkage *L, int32_t n, int32_t r, double *out);
/* Internal node: from its handle forces x, the principal joint's
 * acceleration and constraint force (written to L->qdd / L->cforce) and
 * the children's handle forces. */
void dca_node_backsub(aqs_linkage *L, int32_t n);
/* Constraint forces of the fixed joints inside composite c, from its leaf's
 * handle forces x (6 per handle, in the handles' frames: the DCA's are set
 * when the leaf's parent node was back-substituted). */
void dca_welded_forces_comp(aqs_linkage *L, int32_t c, const double *x);

#endif
