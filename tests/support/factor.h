/* factor.h -- reading the packed total-acceleration factors (src/solve/totalacc.c)
 * in the tests. */
#ifndef AQS_TEST_FACTOR_H
#define AQS_TEST_FACTOR_H

#include <stdint.h>

#include "linkage.h"

/* Node n's factor as trows full rows of 6nh + 1 columns (row-major, in the
 * factor's column order: handle blocks tree.tperm, then the constant): row r
 * is stored from its first column trowpos[tpos + r] on, zeros left of it. */
void test_unpack_factor(const aqs_linkage *L, int32_t n, double *full);

#endif
