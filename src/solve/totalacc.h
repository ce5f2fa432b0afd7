/* totalacc.h -- total-acceleration coefficients in square-root form
 * (MATH.md §4-5): A_C(x) = || T_C [x; 1] ||^2, T_C built by Householder
 * reflections (docs/math.md §9). */
#ifndef AQS_TOTALACC_H
#define AQS_TOTALACC_H

#include "linkage.h"

/* Allocate the factors of every node (first use of adaptive solving).
 * Returns AQS_OK or AQS_ENOMEM (nothing changed). */
aqs_status totalacc_enable(aqs_linkage *L, const char *fn);
void totalacc_free(aqs_linkage *L);
/* T_C of an internal node from its children's factors and the node's DCA
 * coefficients. Call right after dca_node_update on the same node: it reads
 * the node's M = [Phi^A_ok X^T; -Phi^B_ok] from the tree's scratch. */
void totalacc_node_update(aqs_linkage *L, int32_t n);
/* A(n) at the handle forces stored in the node (its x). */
double totalacc_eval(const aqs_linkage *L, int32_t n);

#endif
