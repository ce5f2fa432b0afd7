/* residual.h -- the joint-space residual r = Q - ID(qdd) of a quasi-static
 * solution at zero velocity, by inverse dynamics (recursive Newton-Euler)
 * over the articulated-body order (src/model/kintree.h): what iterative
 * refinement of the exact DCA solve measures (src/solve/refine.c,
 * docs/math.md §13a). */
#ifndef AQS_RESIDUAL_H
#define AQS_RESIDUAL_H

#include "ddouble.h"
#include "linkage.h"

/* Each composite's frame in its parent's at the current positions, into
 * the articulated-body solver's per-solve node values (node[k].X, which
 * every articulated-body solve rewrites first): once before residual_eval
 * calls at the same positions. */
void residual_poses(aqs_linkage *L);
/* r (nv) = L->tau - ID(qdd) with the current gravity and the composites'
 * loads (L->m.comp_force, current after update_loads). Returns ||r||_2 (NaN
 * or inf when a value is not finite). The joint forces f it formed stay in
 * the node values (v.s.U) until residual_forces or the next solve. */
double residual_eval(aqs_linkage *L, const double *qdd, double *r);
/* The bodies' accelerations a_c of qdd (relative to free fall) into the
 * node values (v.s.acc): residual_eval's outward pass alone. */
void residual_accelerations(aqs_linkage *L, const double *qdd);
/* The bodies' balance of forces with the joint forces cforce at the node
 * values' accelerations a_c: max over bodies of |f_c - sum_children X^T
 * f_child - (I_c a_c - f_ext,c)|_1 (torques weighed by 1/l), NaN if one is
 * not; *scale the largest such sum of the terms' magnitudes with the
 * body's weight m_c |g| (a_c is relative to free fall). work: 6 ne
 * scratch; overwrites the forces residual_forces reads. */
double residual_balance(aqs_linkage *L, const double *cforce, double *work, double *scale);
/* Mv (nv) = M v, the joint-space inertia matrix at the current positions
 * times v: the same pass at zero gravity, no load, no joint force (the
 * operator of refine.c's GMRES). Needs residual_poses; overwrites the forces
 * residual_forces reads. */
void residual_mass_mul(aqs_linkage *L, const double *v, double *Mv);
/* The joint forces of the last residual_eval into cforce (6 per user joint,
 * L->cforce's convention: the force of the joint on its child composite, in
 * the composite's frame); fixed joints' entries are not written. */
void residual_forces(const aqs_linkage *L, double *cforce);

/* The same in double-double (src/base/ddouble.h; docs/math.md §5b, "The
 * residual in double-double"), for the articulated-body solve's refinement
 * (src/solve/abarefine.c), with its own storage (the node values are not
 * touched; residual_poses or an articulated-body solve sets the poses).
 * residual_dd_accelerations: the bodies' accelerations a_c (6 per joint, the
 * ABA order, relative to free fall) of qdd, outward from a_0 = -g. */
void residual_dd_accelerations(aqs_linkage *L, const double *qdd, ddouble *acc);
/* Which product the double-double passes take (L->dd_fma): fma's where the
 * processor has it and AQS_SIMD is not "sse2", else Dekker's (the same
 * results). Once, before the first pass (with the arrays of a refinement). */
void residual_dd_select(aqs_linkage *L);
/* r = Q - S^T f with f_c = I_c a_c - f_ext,c + sum_children X^T f_child
 * formed from acc inward, rounded once: into r (nv) when not NULL; the
 * joint forces rounded into forces (6 per joint, the ABA order) when not
 * NULL; fw: 6 ne scratch. Returns max |r| over the larger of the largest
 * joint force and the sum of the bodies' terms |I_c a_c| + m_c |g| (torques
 * weighed by 1/l as in rounding.c; 0 when both are 0; NaN when a value is
 * not finite). */
double residual_dd_eval(aqs_linkage *L, const ddouble *acc, ddouble *fw, double *r, double *forces);
/* The 2-norm of the double-double residual r = Q - S^T f of qdd (nv
 * values into r; acc: 6 ne ddouble scratch, fw: 6 ne): the two passes above
 * in turn. NaN where a value is not finite. */
double residual_dd_norm(aqs_linkage *L, const double *qdd, ddouble *acc, ddouble *fw, double *r);
/* acc += the bodies' accelerations of dq from rest (6 per joint, the ABA
 * order), formed in double (a correction's) and added in double-double;
 * overwrites the node values' accelerations (v.s.acc). */
void residual_dd_acc_add(aqs_linkage *L, const double *dq, ddouble *acc);
/* Whether a refinement of the forces can stop: the next correction would
 * move them by less than RESIDUAL_FORCE_STOP u of the largest, predicted as
 * the last correction's move (fnew - fold, n entries) times the residual's
 * contraction (its measure after over before the last correction). */
#define RESIDUAL_FORCE_STOP 0.125
int residual_forces_settled(const double *fnew, const double *fold, size_t n, double contraction);

#endif
