/* heap.h -- a binary max-heap of (key, node) pairs in caller-provided
 * (pooled) memory: the priority queue of the adaptive back-substitution. */
#ifndef AQS_HEAP_H
#define AQS_HEAP_H

#include <stdint.h>

typedef struct {
    double *key;
    int32_t *item;
    int32_t size, capacity;
} heap;

/* Use the arrays key and item, each of capacity entries. */
void heap_init(heap *h, double *key, int32_t *item, int32_t capacity);
/* Insert; returns 0, or -1 when full. */
int heap_push(heap *h, double key, int32_t item);
/* Remove the entry with the largest key; returns 0, or -1 when empty. */
int heap_pop(heap *h, double *key, int32_t *item);
/* The largest key (0 if empty). */
double heap_top(const heap *h);

#endif
