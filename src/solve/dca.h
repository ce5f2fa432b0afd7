/* dca.h -- articulated-body coefficients of the assembly tree's nodes and the
 * exact back-substitution (MATH.md §3; docs/math.md, "Accurate Phi"). Two
 * forms of the node update share the outputs below: the square-root form
 * (src/solve/dca.c, AQS_DCA_FORM_SQRT, the default) and the inverse-inertia form
 * (src/solve/dca_phi.c, AQS_DCA_FORM_PHI). */
#ifndef AQS_DCA_H
#define AQS_DCA_H

#include "linkage.h"

/* Allocate the tree's DCA coefficients (mass properties, Lambda or Phi, b,
 * handle forces, FX, QX, ...) and set up the leaves, once: a linkage solved
 * only exactly by the articulated-body algorithm never needs them. Marks
 * every node stale. AQS_OK, AQS_EINVAL (a body's mass outside [DCA_MASS_MIN,
 * DCA_MASS_MAX]) or AQS_ENOMEM (message naming fn). */
aqs_status dca_enable(aqs_linkage *L, const char *fn);
/* The masses the DCA computes with besides 0 (dca_enable refuses others,
 * AQS_EINVAL): products of two stay normal numbers. */
#define DCA_MASS_MIN 1e-150
#define DCA_MASS_MAX 1e150
/* Leaf Phi of the inverse-inertia form, in the node's Lambda storage. */
void dca_phi_leaf(aqs_linkage *L, int32_t n);
/* Leaf b from the composite's external load (world leaf: from gravity). */
void dca_leaf_b(aqs_linkage *L, int32_t n);
/* Internal node: its coefficients (rho, gamma, S, b, FX = W M^T, QX =
 * U M^T, and Lambda or Phi) from its children and the principal joint's
 * position and force, in the linkage's DCA form. Returns 0, -1 when
 * the articulated inertia is numerically singular, -2 (square-root form)
 * when the joint's acceleration term rho came out non-finite from finite
 * factors: the loads overflowed. */
int dca_node_update(aqs_linkage *L, int32_t n);
/* Keep each node's load factors from its next update on (what rho, gamma and
 * b take from beta and Q; square-root form): 36 + 6 d + d^2 doubles per internal
 * node, for dca_node_loads. AQS_OK or AQS_ENOMEM. */
aqs_status dca_loads_enable(aqs_linkage *L);
void dca_loads_free(aqs_linkage *L);
/* Internal node n's rho, gamma and b from its children's b and its joint force
 * alone, by the factors its last update kept (the positions unchanged since):
 * the same values as dca_node_update in exact arithmetic. 0, or -1 when no
 * factors are kept for it (then dca_node_update). */
int dca_node_loads(aqs_linkage *L, int32_t n);
/* The inverse-inertia form of dca_node_update (src/solve/dca_phi.c). */
int dca_phi_node_update(aqs_linkage *L, int32_t n);
/* out (6 nh) = M W g for a 6-vector g (the handle part of g^T [W M^T]):
 * FX^T g. */
void dca_mw_apply(const aqs_linkage *L, int32_t n, const double g[6], double *out);
/* out (6 nh) = row r < d of U M^T (= QX). */
void dca_um_row(const aqs_linkage *L, int32_t n, int32_t r, double *out);
/* a (6 nh) = Phi x + b: the accelerations of node n's handles from its stored
 * handle forces, each in its handle's frame (square-root form). 0, or -1 if
 * I^-1 does not exist. */
int dca_handle_accels(const aqs_linkage *L, int32_t n, double *a);
/* The same, with in mag (6 nh, when not NULL) the magnitude of each entry's
 * terms: |b| + |the rigid part| + sum_c |lam_c| sum_i |lam_ic x_i| (an
 * entry's rounding is about u times it). */
int dca_handle_accels_mag(const aqs_linkage *L, int32_t n, double *a, double *mag);
/* Internal node: from its handle forces x, the principal joint's
 * acceleration and constraint force (written to L->qdd / L->cforce) and
 * the children's handle forces: qdd = rho - QX x, f = gamma + FX x. */
void dca_node_backsub(aqs_linkage *L, int32_t n);
/* dca_node_backsub for the square-root form's adaptive solve: the same
 * results, each product formed once for them and for the rounding estimate's
 * sums by handle (rounding_backsub_products, read by rounding_backsub). */
void dca_node_backsub_sums(aqs_linkage *L, int32_t n);
/* Constraint forces of the fixed joints inside composite c, from its leaf's
 * handle forces x (6 per handle, in the handles' frames: the DCA's are set
 * when the leaf's parent node was back-substituted). */
void dca_welded_forces_comp(aqs_linkage *L, int32_t c, const double *x);

#endif
