/* refinetest.c -- out of memory in a refinement's arrays (refinetest.h). */
#include "refinetest.h"

#include <stdlib.h>
#include <string.h>

/* o->L's accelerations, in a new array. */
static double *accelerations(const test_oom *o)
{
    double *q = malloc(sizeof(double) * o->nv);
    assert_non_null(q);
    assert_int_equal(aqs_linkage_get_accelerations(o->L, q, o->nv), AQS_OK);
    return q;
}

long test_oom_unrefined(const test_oom *o, long fail)
{
    const long live = o->cs->live;
    double *q1;
    o->cs->fail_at = o->cs->count + fail;
    assert_int_equal(aqs_linkage_solve(o->L), AQS_OK);
    assert_true(o->cs->count >= o->cs->fail_at); /* the failing allocation was reached */
    assert_int_equal(*o->refined, 0);
    if (!o->keeps) assert_int_equal(o->cs->live, live);
    q1 = accelerations(o);
    assert_memory_equal(o->q0, q1, sizeof(double) * o->nv);
    free(q1);
    return live;
}

void test_oom_refined(const test_oom *o, long live)
{
    double *q1;
    o->cs->fail_at = 0;
    assert_int_equal(aqs_linkage_solve(o->L), AQS_OK);
    assert_true(*o->refined >= 1);
    assert_true(o->cs->live > live);
    q1 = accelerations(o);
    assert_true(memcmp(o->q0, q1, sizeof(double) * o->nv) != 0);
    free(q1);
}

void test_oom_each(const test_oom *o, long nalloc)
{
    long k, live = 0;
    for (k = 1; k <= nalloc; k++) live = test_oom_unrefined(o, k);
    test_oom_refined(o, live);
}
