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

/* ---- Added for the per-concept unit tests. ----
 * Reference geometry written independently of src/base/spatial.c (other
 * formulas), so that a test comparing against it can catch a library bug. */

/* Largest absolute difference of two vectors. */
double test_max_abs_diff(const double *a, const double *b, size_t n);
/* Rotation of angle about axis (any non-zero length) by Rodrigues' formula
 * R = I + sin(t) K + (1 - cos(t)) K^2, K = skew(axis / |axis|). */
void test_rodrigues(const double axis[3], double angle, double R[9]);
/* Rotation matrix of a unit quaternion (w, x, y, z) as
 * R = (w^2 - v.v) I + 2 v v^T + 2 w skew(v). */
void test_quat_matrix(const double q[4], double R[9]);
/* C = A B for 3x3 row-major matrices (C may not alias A or B). */
void test_mat3_mul(const double A[9], const double B[9], double C[9]);
/* A uniformly distributed unit quaternion with w >= 0 (Shoemake). */
void test_random_quat(uint64_t *state, double q[4]);
/* Fails the test, printing both strings, unless needle occurs in text. */
void test_assert_contains(const char *text, const char *needle);
/* Create a linkage with malloc/free; asserts success. */
aqs_linkage *test_new_linkage(void);
/* Create a linkage whose allocator is the counting one, cs (malloc/free
 * when cs is NULL); asserts success. */
aqs_linkage *test_new_linkage_in(counting_state *cs);

#endif
