/* test_pool.c -- memory through the linkage's allocator and the pooled
 * offsets of the node arrays. */
#include "testutil.h"

#include <stdlib.h>
#include <string.h>

#include "linkage.h"
#include "pool.h"

static void test_pool_take(void **state)
{
    int64_t size = 0;
    (void)state;
    assert_true(pool_take(&size, 36) == 0);
    assert_true(pool_take(&size, 0) == 36);
    assert_true(pool_take(&size, 12) == 36);
    assert_true(size == 48);
}

static void test_allocator_paths(void **state)
{
    counting_state cs;
    aqs_linkage *L = NULL;
    double *p;
    unsigned char *z;
    size_t i;
    (void)state;
    memset(&cs, 0, sizeof cs);
    assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
    p = lk_alloc(L, 0); /* zero bytes still gives a block (one byte) */
    assert_non_null(p);
    lk_free(L, p);
    z = lk_calloc(L, 100, 3);
    assert_non_null(z);
    for (i = 0; i < 300; i++) assert_int_equal(z[i], 0);
    lk_free(L, z);
    /* count * size overflowing size_t is refused before calling the allocator */
    {
        long before = cs.count;
        assert_null(lk_calloc(L, (size_t)-1 / 2, 3));
        assert_int_equal(cs.count, before);
    }
    lk_free(L, NULL); /* no call for NULL */
    aqs_linkage_destroy(L);
    assert_int_equal(cs.live, 0);
    assert_int_equal(cs.allocs, cs.frees);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pool_take),
        cmocka_unit_test(test_allocator_paths),
    };
    return cmocka_run_group_tests_name("pool", tests, NULL, NULL);
}
