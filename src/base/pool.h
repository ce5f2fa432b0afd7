/* pool.h -- all memory of a linkage goes through its allocator; the node
 * memory of the assembly tree is a few pooled arrays sized at finalize. */
#ifndef AQS_POOL_H
#define AQS_POOL_H

#include <stdint.h>

#include "linkage.h"

/* Reserve n items of a pooled array: returns the offset and advances *size. */
int64_t pool_take(int64_t *size, int64_t n);

#endif
