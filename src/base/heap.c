/* heap.c -- binary max-heap on parallel arrays (sift up / sift down). */
#include "heap.h"

#include "invariant.h"

void heap_init(heap *h, double *key, int32_t *item, int32_t capacity)
{
    h->key = key;
    h->item = item;
    h->size = 0;
    h->capacity = capacity;
}

int heap_push(heap *h, double key, int32_t item)
{
    int32_t i;
    if (h->size >= h->capacity) return -1;
    i = h->size++;
    while (i > 0) {
        int32_t parent = (i - 1) / 2;
        if (!(h->key[parent] < key)) break;
        h->key[i] = h->key[parent];
        h->item[i] = h->item[parent];
        i = parent;
    }
    h->key[i] = key;
    h->item[i] = item;
    AQS_ASSERT(h->size <= h->capacity && (i == 0 || !(h->key[(i - 1) / 2] < key)));
    return 0;
}

int heap_pop(heap *h, double *key, int32_t *item)
{
    int32_t i = 0, n;
    double k;
    int32_t it;
    if (h->size == 0) return -1;
    *key = h->key[0];
    *item = h->item[0];
    n = --h->size;
    if (n == 0) return 0;
    k = h->key[n];
    it = h->item[n];
    for (;;) {
        int32_t c = 2 * i + 1;
        if (c >= n) break;
        if (c + 1 < n && h->key[c + 1] > h->key[c]) c++;
        if (!(h->key[c] > k)) break;
        h->key[i] = h->key[c];
        h->item[i] = h->item[c];
        i = c;
    }
    h->key[i] = k;
    h->item[i] = it;
    /* the new top is no smaller than its children (NaN keys compare false) */
    AQS_ASSERT(n < 2 || !(h->key[0] < h->key[1]));
    AQS_ASSERT(n < 3 || !(h->key[0] < h->key[2]));
    return 0;
}

double heap_top(const heap *h) { return h->size > 0 ? h->key[0] : 0.0; }
