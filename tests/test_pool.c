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

/* An allocator handing out one buffer it filled with garbage, at an offset
 * that is not a multiple of a page: the large blocks lk_calloc asks to be
 * backed by huge pages (pool.c, hint_huge) come from any allocator, and the
 * hint must neither touch memory outside the block nor change what the
 * block holds or how it is counted. */
typedef struct {
    unsigned char *buf;
    size_t size, used;
    int calls;
} arena;

/* Blocks 16-aligned, as malloc's are (the size rounded up): what a caller's
 * allocator must give (aqs.h); the linkage's own size is no multiple of 16. */
static size_t round16(size_t n) { return (n + 15) & ~(size_t)15; }

static void *arena_alloc(void *user, size_t size)
{
    arena *a = (arena *)user;
    size = round16(size);
    if (a->used + size > a->size) return NULL;
    a->used += size;
    a->calls++;
    return a->buf + a->used - size;
}

static void arena_free(void *user, void *ptr)
{
    (void)user;
    (void)ptr;
}

static void test_large_blocks(void **state)
{
    /* below, at and above the 4 MiB where the hint starts, and a size that
     * ends inside a 2 MiB page */
    const size_t sizes[] = {((size_t)4 << 20) - 8, (size_t)4 << 20, ((size_t)9 << 20) + 24, (size_t)5 << 20};
    const size_t guard = 4096, total = ((size_t)32 << 20) + 2 * guard;
    arena ar;
    aqs_linkage *L = NULL;
    size_t k, i;
    (void)state;
    memset(&ar, 0, sizeof ar);
    ar.buf = (unsigned char *)malloc(total);
    ar.size = total;
    assert_non_null(ar.buf);
    memset(ar.buf, 0xa5, total);
    ar.used = guard + 48; /* the linkage's first block starts 48 bytes into a page (16-aligned) */
    assert_int_equal(aqs_linkage_create_with_allocator(arena_alloc, arena_free, &ar, &L), AQS_OK);
    for (k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        const size_t before = L->mem_now, start = ar.used;
        unsigned char *z = (unsigned char *)lk_calloc_in(L, LK_MEM_EXACT, sizes[k], 1);
        size_t nonzero = 0;
        assert_non_null(z);
        for (i = 0; i < sizes[k]; i++) nonzero += z[i] != 0;
        assert_int_equal(nonzero, 0);
        assert_int_equal(L->mem_now - before, lk_block_bytes(sizes[k])); /* counted as any block */
        assert_int_equal(ar.used - start, round16(lk_block_bytes(sizes[k])));
        lk_free(L, z);
        assert_int_equal(L->mem_now, before);
        ar.used = start; /* the next block in the same place, shifted by 16 bytes */
        ar.used += 16;
    }
    for (i = 0; i < guard; i++) assert_int_equal(ar.buf[i], 0xa5); /* nothing before the blocks */
    for (i = ar.used + ((size_t)10 << 20); i < total; i++) assert_int_equal(ar.buf[i], 0xa5); /* nor after */
    aqs_linkage_destroy(L);
    free(ar.buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pool_take),
        cmocka_unit_test(test_allocator_paths),
        cmocka_unit_test(test_large_blocks),
    };
    return cmocka_run_group_tests_name("pool", tests, NULL, NULL);
}
