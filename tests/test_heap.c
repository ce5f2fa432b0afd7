/* test_heap.c -- the binary max-heap: pops come out in non-increasing key
 * order and match a sorted reference; full and empty are refused. */
#include "testutil.h"

#include <stdlib.h>

#include "heap.h"

static int by_key_desc(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x < y) - (x > y);
}

static void test_order_matches_sort(void **state)
{
    uint64_t rng = 7;
    enum { N = 2000 };
    double keys[N], ref[N], k;
    int32_t items[N], item, i, seen[N] = {0};
    heap h;
    (void)state;
    heap_init(&h, keys, items, N);
    for (i = 0; i < N; i++) {
        /* duplicates and zeros on purpose (A(node) is often exactly 0) */
        ref[i] = i % 7 == 0 ? 0.0 : (double)(int)test_uniform(&rng, 0, 500);
        assert_int_equal(heap_push(&h, ref[i], i), 0);
    }
    assert_int_equal(h.size, N);
    assert_int_equal(heap_push(&h, 1.0, -1), -1); /* full */
    qsort(ref, N, sizeof(double), by_key_desc);
    assert_true(heap_top(&h) == ref[0]);
    for (i = 0; i < N; i++) {
        assert_int_equal(heap_pop(&h, &k, &item), 0);
        assert_true(k == ref[i]);
        assert_true(item >= 0 && item < N && !seen[item]);
        seen[item] = 1;
    }
    assert_int_equal(heap_pop(&h, &k, &item), -1); /* empty */
    assert_true(heap_top(&h) == 0.0);
}

/* Interleaved pushes and pops, as in the adaptive loop, against a brute-force
 * maximum over a plain array. */
static void test_interleaved(void **state)
{
    uint64_t rng = 11;
    enum { N = 500 };
    double keys[N], live[N], k;
    int32_t items[N], item, nlive = 0, step;
    heap h;
    (void)state;
    heap_init(&h, keys, items, N);
    for (step = 0; step < 5000; step++) {
        if (nlive < N && (nlive == 0 || test_uniform(&rng, 0, 1) < 0.55)) {
            double v = test_uniform(&rng, 0, 1);
            assert_int_equal(heap_push(&h, v, nlive), 0);
            live[nlive++] = v;
        } else {
            int32_t j, best = 0;
            for (j = 1; j < nlive; j++)
                if (live[j] > live[best]) best = j;
            assert_int_equal(heap_pop(&h, &k, &item), 0);
            assert_true(k == live[best]);
            live[best] = live[--nlive];
        }
        assert_int_equal(h.size, nlive);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_order_matches_sort),
        cmocka_unit_test(test_interleaved),
    };
    return cmocka_run_group_tests_name("heap", tests, NULL, NULL);
}
