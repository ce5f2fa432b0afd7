/* residual.h -- the joint-space residual r = Q - ID(qdd) of a quasi-static
 * solution at zero velocity, by inverse dynamics (recursive Newton-Euler)
 * over the articulated-body order (src/model/kintree.h): what iterative
 * refinement of the exact DCA solve measures (src/solve/refine.c,
 * docs/math.md §13a). */
#ifndef AQS_RESIDUAL_H
#define AQS_RESIDUAL_H

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
/* Mv (nv) = M v, the joint-space inertia matrix at the current positions
 * times v: the same pass at zero gravity, no load, no joint force (the
 * operator of refine.c's GMRES). Needs residual_poses; overwrites the forces
 * residual_forces reads. */
void residual_mass_mul(aqs_linkage *L, const double *v, double *Mv);
/* The joint forces of the last residual_eval into cforce (6 per user joint,
 * L->cforce's convention: the force of the joint on its child composite, in
 * the composite's frame); fixed joints' entries are not written. */
void residual_forces(const aqs_linkage *L, double *cforce);

#endif
