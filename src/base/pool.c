/* pool.c -- the linkage's allocator and pooled node memory. */
#include "pool.h"

#include "invariant.h"

#include <stdlib.h>
#include <string.h>

void *lk_alloc(aqs_linkage *L, size_t bytes)
{
    if (bytes == 0) bytes = 1;
    return L->alloc(L->user, bytes);
}

void *lk_calloc(aqs_linkage *L, size_t count, size_t size)
{
    void *p;
    if (size != 0 && count > (size_t)-1 / size) return NULL;
    p = lk_alloc(L, count * size);
    if (p) memset(p, 0, count * size);
    return p;
}

void lk_free(aqs_linkage *L, void *p)
{
    if (p) L->free_fn(L->user, p);
}

int64_t pool_take(int64_t *size, int64_t n)
{
    int64_t off = *size;
    AQS_ASSERT(n >= 0 && off >= 0 && off <= INT64_MAX - n);
    *size += n;
    return off;
}
