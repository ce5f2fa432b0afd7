/* assembly.c -- building the assembly tree by tree contraction.
 *
 * Vertices are the composites and the world (index ncomp); edges are the
 * effective joints. Every vertex starts as a leaf cluster whose handles are
 * its incident joints (for a composite: its parent joint first). Rounds of
 * merges follow until one cluster is left: a cluster with one handle is
 * raked into its neighbour, and two adjacent clusters with two handles each
 * are compressed; a cluster takes part in at most one merge per round. A
 * constant fraction of the clusters disappears per round, so the height is
 * O(log N), and a merged cluster never has more handles than the larger
 * part, so handles stay bounded by the largest body degree. */
#include "assembly.h"

#include <string.h>

#include "pool.h"

typedef struct {
    aqs_linkage *L;
    int32_t *hv; /* handle lists of all nodes */
    int64_t nhv, cap;
    int32_t *uf, *uf_node; /* union-find over vertices; cluster node of each root */
    int32_t nnodes;
} builder;

static int32_t find(builder *B, int32_t v)
{
    int32_t r = v;
    while (B->uf[r] != r) r = B->uf[r];
    while (B->uf[v] != r) {
        int32_t nx = B->uf[v];
        B->uf[v] = r;
        v = nx;
    }
    return r;
}

static int reserve_handles(builder *B, int64_t extra)
{
    int32_t *nh;
    int64_t cap = B->cap;
    if (B->nhv + extra <= B->cap) return 0;
    while (cap < B->nhv + extra) cap = cap * 2 + 16;
    nh = lk_alloc_in(B->L, LK_MEM_TREE, (size_t)cap * sizeof(int32_t));
    if (!nh) return -1;
    if (B->nhv) memcpy(nh, B->hv, (size_t)B->nhv * sizeof(int32_t));
    lk_free(B->L, B->hv);
    B->hv = nh;
    B->cap = cap;
    return 0;
}

/* The cluster on the other side of effective joint e from cluster c. */
static int32_t across(builder *B, int32_t c, int32_t e)
{
    const model *m = &B->L->m;
    int32_t np = B->uf_node[find(B, m->eff_parent[e])];
    int32_t nc = B->uf_node[find(B, m->eff_child[e])];
    return np == c ? nc : np;
}

/* Merge clusters n1 and n2 across joint e into a new node. */
static int merge(builder *B, int32_t n1, int32_t n2, int32_t e, int32_t *stamp, int32_t round)
{
    aqs_linkage *L = B->L;
    const model *m = &L->m;
    node *nodes = L->t.nodes;
    int32_t rp = find(B, m->eff_parent[e]), rc = find(B, m->eff_child[e]);
    int32_t a = B->uf_node[rp] == n1 ? n1 : n2, b = a == n1 ? n2 : n1;
    int32_t id = B->nnodes, i, nh = nodes[a].nh + nodes[b].nh - 2;
    node *C = &nodes[id];
    if (reserve_handles(B, nh) != 0) return -1;
    memset(C, 0, sizeof *C);
    C->a = a;
    C->b = b;
    C->parent = -1;
    C->joint = e;
    C->comp = -1;
    C->nh = nh;
    C->d = joint_nv(L->joints[m->eff_joint[e]].type);
    C->handles = B->nhv;
    C->height = 1 + (nodes[a].height > nodes[b].height ? nodes[a].height : nodes[b].height);
    for (i = 0; i < nodes[a].nh; i++) {
        int32_t h = B->hv[nodes[a].handles + i];
        if (h == e) C->ka = i;
        else B->hv[B->nhv++] = h;
    }
    for (i = 0; i < nodes[b].nh; i++) {
        int32_t h = B->hv[nodes[b].handles + i];
        if (h == e) C->kb = i;
        else B->hv[B->nhv++] = h;
    }
    nodes[a].parent = id;
    nodes[b].parent = id;
    B->uf[rc] = rp;
    B->uf_node[rp] = id;
    B->nnodes++;
    stamp[a] = stamp[b] = stamp[id] = round; /* one merge per cluster and round */
    return 0;
}

static aqs_status contract(builder *B, int32_t nvert)
{
    aqs_linkage *L = B->L;
    node *nodes = L->t.nodes;
    int32_t *live = NULL, *next = NULL, *stamp = NULL;
    int32_t nlive = nvert, round = 0, i, k;
    aqs_status st = AQS_OK;
    live = lk_alloc_in(L, LK_MEM_TREE, (size_t)nvert * sizeof(int32_t));
    next = lk_alloc_in(L, LK_MEM_TREE, (size_t)nvert * sizeof(int32_t));
    stamp = lk_calloc_in(L, LK_MEM_TREE, (size_t)B->L->t.nnodes, sizeof(int32_t));
    if (!live || !next || !stamp) {
        st = AQS_ENOMEM;
        goto done;
    }
    for (i = 0; i < nvert; i++) live[i] = i;
    while (nlive > 1) {
        int32_t nnext = 0, first_new = B->nnodes;
        round++;
        /* rake */
        for (k = 0; k < nlive; k++) {
            int32_t c = live[k], n, e;
            if (stamp[c] == round || nodes[c].nh != 1) continue;
            e = B->hv[nodes[c].handles];
            /* The world holding only a free joint is joined last: the root
             * node then solves the floating base's joint against the whole
             * system's mobility, not against the base's alone (a base of tiny
             * rotational inertia k would give the joint's acceleration as a
             * difference of 1/k-sized terms; docs/math.md 4a). */
            if (c == B->L->m.ncomp && nlive > 2 && B->L->joints[B->L->m.eff_joint[e]].type == AQS_JOINT_FREE)
                continue;
            n = across(B, c, e);
            if (stamp[n] == round) continue;
            if (merge(B, c, n, e, stamp, round) != 0) {
                st = AQS_ENOMEM;
                goto done;
            }
        }
        /* compress */
        for (k = 0; k < nlive; k++) {
            int32_t c = live[k], h;
            if (stamp[c] == round || nodes[c].nh != 2) continue;
            for (h = 0; h < 2; h++) {
                int32_t e = B->hv[nodes[c].handles + h], n = across(B, c, e);
                if (stamp[n] == round || nodes[n].nh != 2) continue;
                if (merge(B, c, n, e, stamp, round) != 0) {
                    st = AQS_ENOMEM;
                    goto done;
                }
                break;
            }
        }
        for (k = 0; k < nlive; k++)
            if (stamp[live[k]] != round) next[nnext++] = live[k];
        for (i = first_new; i < B->nnodes; i++) next[nnext++] = i;
        memcpy(live, next, (size_t)nnext * sizeof(int32_t));
        nlive = nnext;
    }
    L->t.root = live[0];
done:
    lk_free(L, live);
    lk_free(L, next);
    lk_free(L, stamp);
    return st;
}

/* The other builder (MATH.md §10): recursive bisection. A cluster is split
 * at the joint that best balances its two sides, recursively; simple and
 * balanced for chains, but boundary joints accumulate on the nodes of
 * branched trees (more handles per node). Kept to compare tree shapes. */
typedef struct {
    int32_t start, len, stage, edge, split, res[2], up, slot;
} bisect_frame;

static aqs_status bisect(builder *B, int32_t nvert)
{
    aqs_linkage *L = B->L;
    const model *m = &L->m;
    const node *nodes = L->t.nodes;
    int32_t *verts = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)nvert);
    int32_t *tag = lk_calloc_in(L, LK_MEM_TREE, (size_t)nvert, sizeof(int32_t));
    int32_t *par = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)nvert);
    int32_t *pedge = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)nvert);
    int32_t *size = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)nvert);
    int32_t *order = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)nvert);
    int32_t *stamp = lk_calloc_in(L, LK_MEM_TREE, (size_t)L->t.nnodes, sizeof(int32_t));
    bisect_frame *stack = lk_alloc_in(L, LK_MEM_TREE, sizeof(bisect_frame) * (size_t)(nvert + 1));
    int32_t top = 0, ntag = 0, i, result = -1;
    aqs_status st = AQS_OK;
    if (!verts || !tag || !par || !pedge || !size || !order || !stamp || !stack) {
        st = AQS_ENOMEM;
        goto done;
    }
    for (i = 0; i < nvert; i++) verts[i] = i;
    stack[0].start = 0;
    stack[0].len = nvert;
    stack[0].stage = 0;
    stack[0].up = -1;
    top = 1;
    while (top > 0) {
        bisect_frame *f = &stack[top - 1];
        int32_t res = -1;
        if (f->len == 1) {
            res = verts[f->start]; /* the leaf node of that vertex */
        } else if (f->stage == 0) {
            /* BFS over the cluster from its first vertex: parents and sizes */
            int32_t head = 0, tail = 0, best = -1, bestgap = INT32_MAX, k;
            ntag++;
            for (k = f->start; k < f->start + f->len; k++) tag[verts[k]] = ntag;
            order[tail++] = verts[f->start];
            par[verts[f->start]] = -1;
            while (head < tail) {
                int32_t v = order[head++], h;
                for (h = 0; h < nodes[v].nh; h++) {
                    int32_t e = B->hv[nodes[v].handles + h];
                    int32_t w = m->eff_parent[e] == v ? m->eff_child[e] : m->eff_parent[e];
                    if (tag[w] != ntag || w == par[v]) continue;
                    par[w] = v;
                    pedge[w] = e;
                    order[tail++] = w;
                }
            }
            for (k = tail - 1; k >= 0; k--) size[order[k]] = 1;
            for (k = tail - 1; k > 0; k--) size[par[order[k]]] += size[order[k]];
            for (k = 1; k < tail; k++) {
                int32_t gap = f->len - 2 * size[order[k]];
                if (gap < 0) gap = -gap;
                if (gap < bestgap) {
                    bestgap = gap;
                    best = order[k];
                }
            }
            /* the subtree of best first, then the rest (tag the subtree) */
            ntag++;
            tag[best] = ntag;
            for (k = 1; k < tail; k++) {
                int32_t v = order[k];
                if (v != best && tag[par[v]] == ntag) tag[v] = ntag;
            }
            head = f->start;
            for (k = 0; k < tail; k++)
                if (tag[order[k]] == ntag) verts[head++] = order[k];
            for (k = 0; k < tail; k++)
                if (tag[order[k]] != ntag) verts[head++] = order[k];
            f->edge = pedge[best];
            f->split = size[best];
            f->stage = 1;
            stack[top].start = f->start;
            stack[top].len = f->split;
            stack[top].stage = 0;
            stack[top].up = top - 1;
            stack[top].slot = 0;
            top++;
            continue;
        } else if (f->stage == 1) {
            f->stage = 2;
            stack[top].start = f->start + f->split;
            stack[top].len = f->len - f->split;
            stack[top].stage = 0;
            stack[top].up = top - 1;
            stack[top].slot = 1;
            top++;
            continue;
        } else {
            if (merge(B, f->res[0], f->res[1], f->edge, stamp, 1) != 0) {
                st = AQS_ENOMEM;
                goto done;
            }
            res = B->nnodes - 1;
        }
        /* deliver the finished cluster's node to its parent frame */
        if (f->up < 0) result = res;
        else stack[f->up].res[f->slot] = res;
        top--;
    }
    L->t.root = result;
done:
    lk_free(L, verts);
    lk_free(L, tag);
    lk_free(L, par);
    lk_free(L, pedge);
    lk_free(L, size);
    lk_free(L, order);
    lk_free(L, stamp);
    lk_free(L, stack);
    return st;
}

void assembly_free(aqs_linkage *L)
{
    tree *t = &L->t;
    lk_free(L, t->nodes);
    lk_free(L, t->handles);
    lk_free(L, t->poses);
    lk_free(L, t->data);
    lk_free(L, t->rnd_x);
    lk_free(L, t->rnd_node);
    lk_free(L, t->lf);
    lk_free(L, t->lfoff);
    lk_free(L, t->lfok);
    lk_free(L, t->node_of_eff);
    lk_free(L, t->leaf_of_comp);
    lk_free(L, t->scratch);
    lk_free(L, t->mscratch);
    lk_free(L, t->hscratch);
    lk_free(L, t->stamp);
    lk_free(L, t->dirty);
    lk_free(L, t->dirty_tmp);
    memset(t, 0, sizeof *t);
    t->root = -1;
}

/* Renumber the nodes in depth-first post-order (A's subtree, B's subtree,
 * then the node): children still come before parents, and each subtree's
 * nodes -- hence, after layout(), its pooled memory -- are contiguous, so
 * the children-first update and the back-substitution stream through
 * memory instead of jumping between contraction rounds. */
static int renumber_postorder(aqs_linkage *L)
{
    tree *t = &L->t;
    int32_t n = t->nnodes, top = 0, next = 0, i;
    int32_t *stack = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)(n + 1));
    int32_t *newid = lk_alloc_in(L, LK_MEM_TREE, sizeof(int32_t) * (size_t)(n + 1));
    unsigned char *expanded = lk_calloc_in(L, LK_MEM_TREE, (size_t)n + 1, 1);
    node *copy = lk_alloc_in(L, LK_MEM_TREE, sizeof(node) * (size_t)(n + 1));
    if (!stack || !newid || !expanded || !copy) {
        lk_free(L, stack);
        lk_free(L, newid);
        lk_free(L, expanded);
        lk_free(L, copy);
        return -1;
    }
    stack[top++] = t->root;
    while (top > 0) {
        int32_t v = stack[top - 1];
        if (t->nodes[v].joint >= 0 && !expanded[v]) {
            expanded[v] = 1;
            stack[top++] = t->nodes[v].b; /* popped after A's subtree */
            stack[top++] = t->nodes[v].a;
        } else {
            top--;
            newid[v] = next++;
        }
    }
    memcpy(copy, t->nodes, sizeof(node) * (size_t)n);
    for (i = 0; i < n; i++) {
        node nd = copy[i];
        if (nd.a >= 0) nd.a = newid[nd.a];
        if (nd.b >= 0) nd.b = newid[nd.b];
        if (nd.parent >= 0) nd.parent = newid[nd.parent];
        t->nodes[newid[i]] = nd;
    }
    for (i = 0; i <= L->m.ncomp; i++) t->leaf_of_comp[i] = newid[t->leaf_of_comp[i]];
    t->root = newid[t->root];
    lk_free(L, stack);
    lk_free(L, newid);
    lk_free(L, expanded);
    lk_free(L, copy);
    return 0;
}

/* Offsets of every node's pooled arrays. Lambda's columns (lld): the
 * square-root form's node update gives C the rank d + rank_A + rank_B, at
 * most 6nh (src/solve/dca.c), leaves 0: known here, children first; the
 * inverse-inertia form keeps Phi (6nh x 6nh) in its place. */
static void layout(tree *t, int32_t form)
{
    int32_t i;
    t->ndata = 0;
    t->nposes = 0;
    for (i = 0; i < t->nnodes; i++) {
        node *n = &t->nodes[i];
        int64_t h = n->nh;
        if (form == AQS_DCA_FORM_PHI) n->lld = 6 * n->nh;
        else if (n->joint < 0) n->lld = 0;
        else {
            int32_t r = n->d + t->nodes[n->a].lld + t->nodes[n->b].lld;
            n->lld = r < 6 * n->nh ? r : 6 * n->nh;
        }
        n->poses = pool_take(&t->nposes, h + (n->joint >= 0 ? 1 : 0)); /* and nd_J */
        /* b, then nd_xf, nd_ic, nd_lam and (internal) nd_W, nd_U, nd_rho, nd_gamma, nd_S */
        n->bv = pool_take(&t->ndata, 12 * h + 13 + 6 * h * n->lld +
                                         (n->joint >= 0 ? 36 * h + 6 * n->d * h + n->d + 6 + 6 * n->d : 0));
    }
}

aqs_status assembly_build(aqs_linkage *L)
{
    const model *m = &L->m;
    tree *t = &L->t;
    builder B;
    int32_t nvert = m->ncomp + 1, i, e;
    int32_t *cursor = NULL;
    int64_t total_h = 0;
    aqs_status st = AQS_ENOMEM;
    memset(t, 0, sizeof *t);
    memset(&B, 0, sizeof B);
    B.L = L;
    t->root = -1;
    t->nnodes = nvert + m->ne;
    t->nodes = lk_calloc_in(L, LK_MEM_TREE, (size_t)t->nnodes, sizeof(node));
    t->node_of_eff = lk_calloc_in(L, LK_MEM_TREE, (size_t)m->ne + 1, sizeof(int32_t));
    t->leaf_of_comp = lk_calloc_in(L, LK_MEM_TREE, (size_t)nvert, sizeof(int32_t));
    B.uf = lk_alloc_in(L, LK_MEM_TREE, (size_t)nvert * sizeof(int32_t));
    B.uf_node = lk_alloc_in(L, LK_MEM_TREE, (size_t)nvert * sizeof(int32_t));
    cursor = lk_calloc_in(L, LK_MEM_TREE, (size_t)nvert, sizeof(int32_t));
    if (!t->nodes || !t->node_of_eff || !t->leaf_of_comp || !B.uf || !B.uf_node || !cursor ||
        reserve_handles(&B, 2 * (int64_t)m->ne) != 0)
        goto fail;
    /* Leaves: handle counts, then lists (a composite's parent joint first). */
    for (e = 0; e < m->ne; e++) {
        t->nodes[m->eff_parent[e]].nh++;
        t->nodes[m->eff_child[e]].nh++;
    }
    for (i = 0; i < nvert; i++) {
        node *n = &t->nodes[i];
        n->a = n->b = n->parent = n->joint = -1;
        n->comp = i;
        n->handles = B.nhv;
        B.nhv += n->nh;
        cursor[i] = (int32_t)(n->handles + (i < m->ncomp ? 1 : 0));
        B.uf[i] = i;
        B.uf_node[i] = i;
        t->leaf_of_comp[i] = i;
    }
    for (e = 0; e < m->ne; e++) {
        B.hv[t->nodes[m->eff_child[e]].handles] = e;
        B.hv[cursor[m->eff_parent[e]]++] = e;
    }
    B.nnodes = nvert;
    if (m->ne > 0) {
        st = L->tree_builder == AQS_TREE_BISECTION ? bisect(&B, nvert) : contract(&B, nvert);
        if (st != AQS_OK) goto fail;
    } else {
        t->nnodes = 0; /* everything is welded to the world: nothing moves */
    }
    t->handles = B.hv;
    t->nhandles = B.nhv;
    B.hv = NULL;
    if (t->nnodes > 0 && renumber_postorder(L) != 0) goto fail;
    t->height = 0;
    t->max_handles = 0;
    for (i = 0; i < t->nnodes; i++) {
        node *n = &t->nodes[i];
        if (n->joint >= 0) {
            /* children come first: their counts are final */
            int free_joint = L->joints[m->eff_joint[n->joint]].type == AQS_JOINT_FREE;
            t->node_of_eff[n->joint] = i;
            n->ncount = t->nodes[n->a].ncount + t->nodes[n->b].ncount + (free_joint ? 0 : 1);
            n->forced = free_joint || t->nodes[n->a].forced || t->nodes[n->b].forced;
        }
        if (n->nh > t->max_handles) t->max_handles = n->nh;
        total_h += n->nh;
    }
    if (t->nnodes > 0) t->height = t->nodes[t->root].height;
    t->mean_handles = t->nnodes > 0 ? (double)total_h / t->nnodes : 0.0;
    layout(t, L->dca_form);
    t->poses = NULL; /* update_poses_alloc, when the DCA, collision or a pose query first needs them */
    t->poses_stale = 1;
    t->data = NULL; /* the DCA coefficients: dca_enable, when a DCA solve first needs them */
    /* dca_node_update: Y (6nh x 6) + Z and Z D^-1 (6nh x d, d <= 6 each) = 108 nh doubles */
    t->scratch = lk_calloc_in(L, LK_MEM_TREE, 108 * (size_t)(t->max_handles + 2), sizeof(double));
    t->mscratch = lk_calloc_in(L, LK_MEM_TREE, 36 * (size_t)(t->max_handles + 1), sizeof(double));
    t->hscratch = lk_calloc_in(L, LK_MEM_TREE, (6 * (size_t)t->max_handles + 14) * (12 * (size_t)t->max_handles + 6) +
                                (size_t)t->max_handles * (sizeof(pose) / sizeof(double) + 1),
                            sizeof(double));
    t->stamp = lk_calloc_in(L, LK_MEM_TREE, (size_t)t->nnodes + 1, sizeof(uint32_t));
    t->dirty = lk_calloc_in(L, LK_MEM_TREE, (size_t)t->nnodes + 1, sizeof(int32_t));
    t->dirty_tmp = lk_calloc_in(L, LK_MEM_TREE, (size_t)t->nnodes + 1, sizeof(int32_t));
    t->epoch = 1;
    if (!t->scratch || !t->mscratch || !t->hscratch || !t->stamp || !t->dirty ||
        !t->dirty_tmp) goto fail;
    lk_free(L, B.uf);
    lk_free(L, B.uf_node);
    lk_free(L, cursor);
    return AQS_OK;
fail:
    lk_free(L, B.hv);
    lk_free(L, B.uf);
    lk_free(L, B.uf_node);
    lk_free(L, cursor);
    assembly_free(L);
    (void)st;
    return lk_fail(L, AQS_ENOMEM, "aqs_linkage_finalize: out of memory building the assembly tree");
}
