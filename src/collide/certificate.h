/* certificate.h -- what the lazy self-collision query may keep from one query
 * to the next (src/collide/broadphase.c): per-node lists of shape pairs in two
 * compacting pools (the cached contacts; the certificates' near lists), and
 * the motion bounds that say how long a certificate of separation stays
 * valid (docs/collision.md, "Certificates"). */
#ifndef AQS_CERTIFICATE_H
#define AQS_CERTIFICATE_H

#include <stdint.h>

#include "spatial.h"

/* Pairs of shape indices. A node's list is buf[cur][2 off .. 2 (off + cnt)). */
typedef struct {
    int32_t *buf[2];
    int32_t cap, used, cur;
} pair_pool;

/* Append (i, j): 0 if the pool is full (nothing written). */
int pair_pool_push(pair_pool *p, int32_t i, int32_t j);
/* Move the lists of the nodes with live[n] into the other buffer, updating
 * off, within half of it. When they do not fit: with partial, the lists
 * that do not fit are dropped (live[n] cleared); without, nothing changes
 * and 0 is returned (the caller forgets every list). Else 1. */
int pair_pool_compact(pair_pool *p, int32_t nnodes, unsigned char *live, int32_t *off,
                      const int32_t *cnt, int partial);

/* x rounded up: the next double above (accumulated bounds stay upper bounds). */
double bound_up(double x);
/* Upper bound on |Pk_new(x) - Pk_old(x)| over the points x of a sphere (centre
 * s[0..2], radius s[3] + grow) in the child's frame: |(R_new - R_old) c +
 * p_new - p_old| + |R_new - R_old|_F (r + grow), conservative for rounding;
 * 0 when the poses are bitwise equal or the sphere is empty (s[3] < 0). */
double placement_motion(const pose *old_pk, const pose *new_pk, const double s[4], double grow);

#endif
