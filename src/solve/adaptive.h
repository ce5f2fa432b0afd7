/* adaptive.h -- the heap-ordered partial back-substitution with certified
 * error bounds (MATH.md §6), and the exact full back-substitution. */
#ifndef AQS_ADAPTIVE_H
#define AQS_ADAPTIVE_H

#include "linkage.h"

/* The per-solve arrays (heap, processed list), sized at finalize. */
aqs_status adaptive_alloc(aqs_linkage *L);
void adaptive_free(aqs_linkage *L);
/* Back-substitute with the current tolerance (exact when eps = 0 and no
 * cap), after the coefficients are up to date. Sets L->s. */
void adaptive_solve(aqs_linkage *L);
/* Set L->s as after a solve that computed every joint outside this file
 * (the articulated-body solver): no bound, no processed or queued node. */
void adaptive_mark_exact(aqs_linkage *L);
/* Continue the last adaptive solve down to a smaller eps. */
void adaptive_refine(aqs_linkage *L, double eps);
/* Whether the next solve may use the predicted set (margin > 0, eps > 0,
 * no cap). */
int adaptive_predict_usable(const aqs_linkage *L);
/* Empty the predicted set; its members' skipped factors are marked for the
 * next update. */
void adaptive_predict_clear(aqs_linkage *L);
/* q <- q (+) h qdd for the computed joints; refresh the moved nodes' frames
 * and mark them stale. */
void adaptive_integrate(aqs_linkage *L, double h);

#endif
