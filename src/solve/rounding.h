/* rounding.h -- a running estimate of the DCA's rounding error in the joint
 * accelerations, with a safety factor (docs/math.md, "The rounding term"):
 * per node from the conditioning its update sees, per solve along the
 * back-substitution, and for the queued (uncomputed) subtrees. */
#ifndef AQS_ROUNDING_H
#define AQS_ROUNDING_H

#include "linkage.h"

/* Unit roundoff of double (2^-53) and the safety factor on every local
 * rounding term. */
#define RND_U 1.1102230246251565e-16
#define RND_SAFETY 8.0
/* doubles per tree node in tree.rnd_node (rounding.c) */
#define RND_NODE_LEVELS 7
/* Past this relative error level (kappa u) the first-order estimate itself is
 * not trusted: the solve is not certified. */
#define RND_KAPPA_MAX 1e-3

/* Node n (square-root form), at the end of its coefficients: U (d x 6), G2 =
 * Sd^T K2 K2^T Sd (d x d), E = Lc^-1 Tc^T (c x 6), beta, the joint force Q,
 * the constraint rows' factor Lc (its c pivots, row stride ncol), the
 * constraint directions Tc (6 x c, row stride 6: column i is row i of Lc's)
 * and the outer handles' b. Reads the node's FX, b and mass properties and its
 * children's levels; sets n's rk, rkb, rerho, regam, resub.
 * The rigid join in inertia form (src/solve/dca.c, rigid_join) has no E or
 * Lc: it passes E = Lc = Tc = NULL, W = E^T E itself (6 x 6), and in gpiv the
 * level of its reduction (for the others, the pivot ratio of Lc). */
void rounding_node(aqs_linkage *L, int32_t n, const double *U, const double *G2, const double *E,
                   const double *W, const double *beta, const double *Q, const double *Lc, const double *Tc,
                   int32_t ncol, double gpiv, const double *bo);
/* Before a solve's back-substitution: the root's handle forces are exact,
 * the per-solve sums zero. */
void rounding_solve_start(aqs_linkage *L);
/* The back-substitution's products for node n and handle forces x (6 nh):
 * qdd = rho - QX x and, when f is not NULL, f = gamma + FX x, summed as
 * dca_node_backsub sums them, and the same products summed by handle h (each
 * from its first product, in column order) for joint_error, in the scratch
 * after tree.rnd_x's handles: sum_h sum_{k in h} |QX_ik x_k| (i < d),
 * sum_i (sum_{k in h} QX_ik x_k)^2 and, with f, sum_{k in h} FX_ik x_k. */
void rounding_backsub_products(aqs_linkage *L, int32_t n, const double *x, double *qdd, double *f);
/* After dca_node_backsub_sums(L, n) (its sums by handle; the inverse-inertia
 * form's dca_node_backsub: nothing estimated): the estimated absolute error
 * (2-norm) of the joint's acceleration, and the children's handle-force
 * errors. Adds it to the solve's sums unless the joint is free. */
void rounding_backsub(aqs_linkage *L, int32_t n, int counted);
/* After a solve or refine: the queued nodes' uncomputed joints, then
 * L->s.rounding and L->s.certified for the measure in force. */
void rounding_finish(aqs_linkage *L);
/* The relative level of node n's coefficients (the larger of its reduced
 * factors' and its b's): they carry about RND_SAFETY u times it of error;
 * 0 where no levels are kept. */
double rounding_coeff_level(const aqs_linkage *L, int32_t n);
/* A solve whose rounding is not estimated (the articulated-body algorithm):
 * rounding = +inf, certified = 0. */
void rounding_none(aqs_linkage *L);

#endif
