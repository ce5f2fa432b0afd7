/* refinetest.h -- out of memory in a refinement's arrays, the check the
 * tests of the three refinements share (test_refine.c, test_arefine.c,
 * test_abarefine.c: src/solve/refine.c, arefine.c, abarefine.c): a solve
 * whose refinement cannot have its arrays still succeeds, unrefined, bit for
 * bit the answer of a twin with the refinement off; the next solve with
 * memory refines. The refinement's count is read through a pointer into the
 * linkage's stats (&L->s.refined, &L->s.arefined), so that this file needs
 * the public header alone. */
#ifndef AQS_TEST_REFINETEST_H
#define AQS_TEST_REFINETEST_H

#include "testutil.h"

typedef struct {
    aqs_linkage *L;         /* its allocator the counting one, cs */
    counting_state *cs;
    const int32_t *refined; /* the refinement's count among L's stats */
    const double *q0;       /* the accelerations of L's twin with the refinement off */
    size_t nv;              /* their number */
    int keeps;              /* a failed solve may keep what it allocated before the failure (the
                               adaptive refinement's load factors): its live blocks are not compared */
} test_oom;

/* A solve of o->L whose fail-th allocation from now fails: it succeeds, the
 * failing allocation reached, nothing refined, nothing held (the allocator's
 * live blocks as before, unless o->keeps), its accelerations o->q0, bit for
 * bit. Returns the live blocks before the solve. */
long test_oom_unrefined(const test_oom *o, long fail);

/* The next solve, with memory: refined, holding more than the live blocks
 * before the last failed solve (its arrays), its accelerations not o->q0. */
void test_oom_refined(const test_oom *o, long live);

/* Each of the refinement's first nalloc allocations failed in turn
 * (test_oom_unrefined), then test_oom_refined. */
void test_oom_each(const test_oom *o, long nalloc);

#endif
