/* update.c -- the lazy coefficient update: loads re-expressed, stale nodes
 * recomputed children first (the frames are in frames.c). */
#include "update.h"

#include <string.h>

#include "collide.h"
#include "dca.h"
#include "dense.h"
#include "frames.h"
#include "invariant.h"
#include "kintree.h"
#include "stale.h"
#include "totalacc.h"
#include "worldbound.h"

/* Refresh a leaf's b and mark its ancestors. While the whole tree is stale
 * (all_dirty: after an exact step by the articulated-body algorithm, which
 * needs only the composites' loads) b is left to the full update, which
 * recomputes every leaf's; without coefficients dca_enable marks everything
 * for that full update. */
static void refresh_leaf(aqs_linkage *L, int32_t leaf)
{
    if (L->t.data && !L->t.all_dirty) dca_leaf_b(L, leaf);
    stale_mark(L, L->t.nodes[leaf].parent);
}

void update_loads(aqs_linkage *L)
{
    model *m = &L->m;
    int32_t i, k;
    if (L->t.nnodes == 0) return;
    if (L->gravity_dirty) {
        refresh_leaf(L, L->t.leaf_of_comp[m->ncomp]);
        stale_gravity_fresh(L);
    }
    if (!L->loads_dirty) return;
    for (i = 0; i < m->nloaded_comps; i++) {
        int32_t c = m->loaded_comps[i];
        memset(m->comp_force + 6 * c, 0, 6 * sizeof(double));
        m->comp_loaded[c] = 0;
        refresh_leaf(L, L->t.leaf_of_comp[c]);
    }
    m->nloaded_comps = 0;
    for (k = 0; k < L->nloaded; k++) {
        int32_t b = L->loaded_bodies[k], c = m->comp_of_body[b];
        pose Pc;
        double f[6];
        if (c == m->ncomp) continue; /* welded to the world: moves nothing */
        if (!m->comp_loaded[c]) {
            m->comp_loaded[c] = 1;
            m->loaded_comps[m->nloaded_comps++] = c;
        }
        if (L->aba.world_valid) kin_comp_world(L, c, &Pc); /* the exact solve's own sweep */
        else frames_comp_world(L, c, &Pc);
        frames_load_in_comp(L, b, &Pc, f);
        for (i = 0; i < 6; i++) m->comp_force[6 * c + i] += f[i];
    }
    if (L->col && L->col->stiffness > 0.0) broadphase_penalty(L); /* contact forces */
    for (i = 0; i < m->nloaded_comps; i++) refresh_leaf(L, L->t.leaf_of_comp[m->loaded_comps[i]]);
    stale_loads_fresh(L);
}

/* The marks update_loads would make, without re-expressing a load: the
 * parents of the leaves of the formerly and the currently loaded composites.
 * For the automatic path's decision when the tree's poses are stale (moved
 * positions): re-expressing through the tree's poses would refresh them
 * along every loaded body's path (frames_comp_world), work an exact step
 * does not need (its sweep has the world poses). The loads stay dirty, so
 * the solve that follows re-expresses them (update_loads again: the same
 * marks, stopped at the first node already marked). Gravity changes and
 * contact forces take the full update_loads. */
void update_mark_loads(aqs_linkage *L)
{
    model *m = &L->m;
    int32_t i, k;
    if (L->t.nnodes == 0 || !L->loads_dirty || L->gravity_dirty || (L->col && L->col->stiffness > 0.0)) {
        update_loads(L);
        return;
    }
    for (i = 0; i < m->nloaded_comps; i++)
        stale_mark(L, L->t.nodes[L->t.leaf_of_comp[m->loaded_comps[i]]].parent);
    for (k = 0; k < L->nloaded; k++) {
        int32_t c = m->comp_of_body[L->loaded_bodies[k]];
        if (c != m->ncomp) stale_mark(L, L->t.nodes[L->t.leaf_of_comp[c]].parent);
    }
}

/* Sort node indices ascending (children before parents: a child's index
 * is below its parent's). Insertion sort for short lists; otherwise an LSD
 * radix sort, 8 bits a pass, as many passes as the largest node index
 * needs: O(n) for n marked nodes, never O(N). tmp holds n entries. */
static void sort_nodes(int32_t *a, int32_t n, int32_t max_index, int32_t *tmp)
{
    int32_t i, j, shift;
    if (n <= 32) {
        for (i = 1; i < n; i++) {
            int32_t v = a[i];
            for (j = i; j > 0 && a[j - 1] > v; j--) a[j] = a[j - 1];
            a[j] = v;
        }
        return;
    }
    for (shift = 0; shift < 31 && (max_index >> shift) != 0; shift += 8) {
        int32_t count[257] = {0};
        for (i = 0; i < n; i++) count[((a[i] >> shift) & 255) + 1]++;
        for (i = 0; i < 256; i++) count[i + 1] += count[i];
        for (i = 0; i < n; i++) tmp[count[(a[i] >> shift) & 255]++] = a[i];
        memcpy(a, tmp, sizeof(int32_t) * (size_t)n);
    }
}

static aqs_status update_node(aqs_linkage *L, int32_t n)
{
    const node *nd = &L->t.nodes[n];
    if (nd->joint < 0) return AQS_OK;
    /* children before parents: the update order relies on it */
    AQS_ASSERT(nd->a < n && nd->b < n && (nd->parent < 0 || nd->parent > n));
    AQS_ASSERT(L->t.nodes[nd->a].parent == n && L->t.nodes[nd->b].parent == n);
    /* the node's blocks inside the pooled coefficients */
    AQS_ASSERT(nd_lam(nd) >= 0 && nd_lam(nd) + 6 * (int64_t)nd->nh * nd->lld <= L->t.ndata);
    AQS_ASSERT(nd->rank >= 0 && nd->rank <= 6 * nd->nh && nd->lld <= 6 * nd->nh);
    AQS_ASSERT(L->t.nodes[nd->a].jw <= L->t.nodes[nd->a].rank && L->t.nodes[nd->b].jw <= L->t.nodes[nd->b].rank);
    AQS_ASSERT(nd_xf(nd) >= 0 && nd_xf(nd) + 6 * (int64_t)nd->nh <= L->t.ndata);
    AQS_ASSERT(nd->nh <= L->t.max_handles);
    switch (dca_node_update(L, n)) {
    case 0:
        break;
    case -2:
        return lk_fail(L, AQS_ENUMERIC,
                       "the loads across joint %d overflowed (its acceleration term came out non-finite "
                       "from finite inertias: gravity or forces too large)",
                       (int)L->m.eff_joint[nd->joint]);
    default:
        return lk_fail(L, AQS_ENUMERIC, "articulated inertia across joint %d is numerically singular",
                       (int)L->m.eff_joint[nd->joint]);
    }
    /* Lambda is stored at its rank, with row stride rank: the structural rank layout()
     * gave it room for (the inverse-inertia form keeps Phi, lld = 6nh) */
    AQS_ASSERT(L->dca_form == AQS_DCA_FORM_PHI ? nd->lld == 6 * nd->nh : nd->rank == nd->lld);
    if (L->wb) worldbound_node_update(L, n); /* its bodies' sphere */
    if (L->t.tdata) {
        solve_state *s = &L->s;
        if (s->pred && s->pred[n]) {
            s->tstale[n] = 1; /* processed next without its A (adaptive.c) */
        } else {
            totalacc_node_update(L, n);
            if (s->tstale) s->tstale[n] = 0;
            L->t.factors_updated++;
        }
    }
    return AQS_OK;
}

aqs_status update_coefficients(aqs_linkage *L)
{
    tree *t = &L->t;
    aqs_status st = AQS_OK;
    int32_t k;
    if (t->nnodes == 0) return AQS_OK;
    if ((st = frames_poses(L)) != AQS_OK) return st; /* left stale by moves since the last update */
    t->factors_updated = 0;
    if (t->all_dirty) {
        stale_loads_all(L);
        update_loads(L); /* the composites' loads; marks are superseded by the full pass */
        /* every leaf's b (the world leaf's from gravity): those refreshed
         * while the tree was stale were skipped (refresh_leaf) */
        for (k = 0; k < t->nnodes; k++)
            if (t->nodes[k].joint < 0 && t->data) dca_leaf_b(L, k);
        for (k = 0; k < t->nnodes && st == AQS_OK; k++) st = update_node(L, k);
        t->nodes_updated = t->nnodes;
    } else {
        update_loads(L);
        /* Children first: a child's index is below its parent's. */
        sort_nodes(t->dirty, t->ndirty, t->nnodes - 1, t->dirty_tmp);
        AQS_ASSERT(t->ndirty < 2 || t->dirty[0] < t->dirty[t->ndirty - 1]);
        for (k = 0; k < t->ndirty && st == AQS_OK; k++) st = update_node(L, t->dirty[k]);
        t->nodes_updated = t->ndirty;
    }
    if (st != AQS_OK) return st; /* the marks stay: a later update retries */
    stale_tree_fresh(L);
    t->ndirty = 0;
    if (++t->epoch == 0) { /* wrapped: clear the stamps once */
        memset(t->stamp, 0, sizeof(uint32_t) * (size_t)t->nnodes);
        t->epoch = 1;
    }
    return AQS_OK;
}
