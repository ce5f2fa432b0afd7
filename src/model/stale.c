/* stale.c -- the one owner of "what is stale" (src/model/stale.h). */
#include "stale.h"

#include "invariant.h"

void stale_mark(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    /* The dirty set is top-closed: stop at the first node already in it. */
    for (; n >= 0 && t->stamp[n] != t->epoch; n = t->nodes[n].parent) {
        t->stamp[n] = t->epoch;
        t->dirty[t->ndirty++] = n;
    }
    AQS_ASSERT(t->ndirty <= t->nnodes); /* each node once per epoch */
}

void stale_positions(aqs_linkage *L, int32_t n)
{
    if (n < 0) L->t.all_dirty = 1;
    else stale_mark(L, n);
    L->loads_dirty = 1; /* world-frame loads are re-expressed (MATH.md §9.1) */
    L->s.valid = 0;
}

void stale_loads(aqs_linkage *L)
{
    L->loads_dirty = 1;
    L->s.valid = 0;
}

void stale_gravity(aqs_linkage *L)
{
    L->gravity_dirty = 1;
    L->s.valid = 0;
}

void stale_joint_force(aqs_linkage *L, int32_t n)
{
    if (n >= 0) stale_mark(L, n);
    L->s.valid = 0;
}

void stale_settings(aqs_linkage *L) { L->s.valid = 0; }

void stale_loads_all(aqs_linkage *L) { L->loads_dirty = L->gravity_dirty = 1; }

void stale_tree(aqs_linkage *L)
{
    L->t.all_dirty = 1;
    stale_loads_all(L);
    L->s.valid = 0;
}

void stale_solve_failed(aqs_linkage *L)
{
    L->solved = 0;
    L->s.valid = 0;
}

void stale_solve_done(aqs_linkage *L) { L->solved = 1; }

void stale_set_refinable(aqs_linkage *L, int refinable) { L->s.valid = refinable; }

void stale_gravity_fresh(aqs_linkage *L) { L->gravity_dirty = 0; }

void stale_loads_fresh(aqs_linkage *L) { L->loads_dirty = 0; }

void stale_tree_fresh(aqs_linkage *L) { L->t.all_dirty = 0; }
