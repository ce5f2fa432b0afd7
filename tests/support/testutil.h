/* testutil.h -- shared helpers of the C unit tests (CMocka). */
#ifndef AQS_TESTUTIL_H
#define AQS_TESTUTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "aqs.h"

/* A counting allocator: live blocks and bytes; optionally fails the
 * fail_at-th allocation (1-based; 0 = never). */
typedef struct {
    long allocs, frees, live;
    long fail_at;
    long count;
} counting_state;

void *counting_alloc(void *user, size_t size);
void counting_free(void *user, void *ptr);

/* A uniform pseudo-random number in [lo, hi), deterministic per state. */
double test_uniform(uint64_t *state, double lo, double hi);

/* Add a body with mass m, com c, diagonal inertia (d, d, d). Asserts success. */
int32_t test_add_body(aqs_linkage *L, double m, double cx, double cy, double cz, double d);
/* Add a joint of type with placement pos and axis (identity orientation). */
int32_t test_add_joint(aqs_linkage *L, int32_t type, int32_t parent, int32_t child, double px,
                       double py, double pz, double ax, double ay, double az);

/* Relative 2-norm difference of two vectors (absolute if b is zero). */
double test_rel_diff(const double *a, const double *b, size_t n);

#endif
