/* pool.c -- the linkage's allocator and pooled node memory. */
#if defined(__linux__) && !defined(_DEFAULT_SOURCE)
#define _DEFAULT_SOURCE /* madvise and MADV_HUGEPAGE under -std=c99 */
#endif
#include "pool.h"

#include "invariant.h"

#include <stdlib.h>
#include <string.h>

#ifdef __linux__
#include <sys/mman.h>
#endif

/* Large blocks: ask for transparent huge pages (2 MiB) on the 2 MiB-aligned
 * part of the block, before anything touches it, so that the pages are
 * faulted in huge where the system allows it (/sys/kernel/mm/
 * transparent_hugepage/enabled "madvise" or "always"). The articulated-body
 * pass streams ~0.75 KB per joint, 0.75 GB at 10^6 joints: with 4 KiB pages
 * that is a TLB miss every few joints (docs/bench.md, "Time per joint flat in
 * N"). A hint only: its failure (another allocator's memory, no THP) changes
 * nothing, and the memory, its contents and the counts are the same. */
enum { HUGE_PAGE = 2 * 1024 * 1024, HUGE_MIN = 2 * HUGE_PAGE };

static void hint_huge(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (bytes >= HUGE_MIN) {
        const uintptr_t a = ((uintptr_t)p + HUGE_PAGE - 1) & ~(uintptr_t)(HUGE_PAGE - 1);
        const uintptr_t e = ((uintptr_t)p + bytes) & ~(uintptr_t)(HUGE_PAGE - 1);
        if (e > a) (void)madvise((void *)a, (size_t)(e - a), MADV_HUGEPAGE);
    }
#else
    (void)p;
    (void)bytes;
#endif
}

/* The header in front of every block: its size as requested from the
 * allocator and its category. The union keeps what follows aligned as the
 * allocator's blocks are (any C type: its size is a multiple of the
 * strictest alignment among its members, which are there for that); 16 bytes
 * where no type needs more (aqs.h, aqs_memory_stats). */
typedef union {
    struct {
        size_t bytes;
        int category;
    } h;
    long double ld;
    double d;
    void *p;
    int64_t i;
    unsigned char size16[16];
} block_header;

size_t lk_block_bytes(size_t bytes)
{
    return (bytes == 0 ? 1 : bytes) + sizeof(block_header);
}

void *lk_alloc_in(aqs_linkage *L, int category, size_t bytes)
{
    block_header *b;
    AQS_ASSERT(category >= 0 && category < LK_MEM_COUNT);
    if (bytes == 0) bytes = 1;
    if (bytes > (size_t)-1 - sizeof(block_header)) return NULL;
    bytes += sizeof(block_header);
    b = (block_header *)L->alloc(L->user, bytes);
    if (!b) return NULL;
    b->h.bytes = bytes;
    b->h.category = category;
    L->mem[category] += bytes;
    L->mem_now += bytes;
    L->mem_blocks++;
    if (L->mem_now > L->mem_peak) L->mem_peak = L->mem_now;
    return b + 1;
}

void *lk_alloc(aqs_linkage *L, size_t bytes)
{
    return lk_alloc_in(L, LK_MEM_MODEL, bytes);
}

void *lk_calloc_in(aqs_linkage *L, int category, size_t count, size_t size)
{
    void *p;
    if (size != 0 && count > (size_t)-1 / size) return NULL;
    p = lk_alloc_in(L, category, count * size);
    if (p) {
        hint_huge(p, count * size);
        memset(p, 0, count * size);
    }
    return p;
}

void *lk_calloc(aqs_linkage *L, size_t count, size_t size)
{
    return lk_calloc_in(L, LK_MEM_MODEL, count, size);
}

void lk_free(aqs_linkage *L, void *p)
{
    block_header *b;
    if (!p) return;
    b = (block_header *)p - 1;
    AQS_ASSERT(b->h.category >= 0 && b->h.category < LK_MEM_COUNT && L->mem[b->h.category] >= b->h.bytes);
    L->mem[b->h.category] -= b->h.bytes;
    L->mem_now -= b->h.bytes;
    L->mem_blocks--;
    L->free_fn(L->user, b);
}

int64_t pool_take(int64_t *size, int64_t n)
{
    int64_t off = *size;
    AQS_ASSERT(n >= 0 && off >= 0 && off <= INT64_MAX - n);
    *size += n;
    return off;
}
