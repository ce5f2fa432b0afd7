/* update.c -- hierarchical frames and the coefficient update. */
#include "update.h"

#include <string.h>

#include "collide.h"
#include "dca.h"
#include "dense.h"
#include "invariant.h"
#include "stale.h"
#include "totalacc.h"
#include "worldbound.h"

void update_leaf_poses(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *nd = &t->nodes[n];
    pose *P = t->poses + nd->poses;
    int32_t i;
    for (i = 0; i < nd->nh; i++) {
        int32_t e = t->handles[nd->handles + i];
        if (L->m.eff_child[e] == nd->comp) pose_identity(&P[i]); /* hangs from e: own frame */
        else P[i] = L->m.eff_place[e];                             /* holds e up: joint frame */
    }
}

/* Pose of B's frame (the child frame of k) in C's frame, from the stored
 * J(q_k) (refreshed by update_node_poses whenever q_k changes). */
static void child_frame_in_node(const aqs_linkage *L, const node *C, pose *out)
{
    const tree *t = &L->t;
    const pose *PA = t->poses + t->nodes[C->a].poses;
    pose_compose(&PA[C->ka], t->poses + C->J, out);
}

void update_node_poses(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    const node *C = &t->nodes[n], *A = &t->nodes[C->a], *B = &t->nodes[C->b];
    const pose *PA = t->poses + A->poses, *PB = t->poses + B->poses;
    const joint_def *jd = &L->joints[L->m.eff_joint[C->joint]];
    pose *P = t->poses + C->poses, Pk;
    int32_t i, ci = 0;
    joint_child_pose(jd, L->q + jd->qoff, t->poses + C->J); /* J(q_k), used by dca.c too */
    child_frame_in_node(L, C, &Pk);
    for (i = 0; i < A->nh; i++)
        if (i != C->ka) P[ci++] = PA[i];
    for (i = 0; i < B->nh; i++)
        if (i != C->kb) pose_compose(&Pk, &PB[i], &P[ci++]);
    AQS_ASSERT(ci == C->nh && C->nh == A->nh + B->nh - 2); /* the joined handles drop out */
    if (L->col) broadphase_node_moved(L, n); /* collision: refit its bounding sphere */
}

void update_all_poses(aqs_linkage *L)
{
    int32_t n;
    for (n = 0; n < L->t.nnodes; n++)
        if (L->t.nodes[n].joint >= 0) update_node_poses(L, n);
}

void update_poses_from_joint(aqs_linkage *L, int32_t e)
{
    int32_t n = L->t.node_of_eff[e];
    for (; n >= 0; n = L->t.nodes[n].parent) update_node_poses(L, n);
}

void update_comp_pose_world(const aqs_linkage *L, int32_t comp, pose *P)
{
    const tree *t = &L->t;
    int32_t n, parent;
    pose_identity(P);
    if (comp == L->m.ncomp || t->nnodes == 0) return;
    /* Walk up: a B child's frame is its parent's frame times A's handle k
     * times J(q_k); an A child shares its parent's frame. */
    for (n = t->leaf_of_comp[comp]; (parent = t->nodes[n].parent) >= 0; n = parent) {
        const node *C = &t->nodes[parent];
        if (C->b == n) {
            pose Pk, tmp;
            child_frame_in_node(L, C, &Pk);
            pose_compose(&Pk, P, &tmp);
            *P = tmp;
        }
    }
}

void update_body_pose_world(const aqs_linkage *L, int32_t body, pose *P)
{
    pose C;
    update_comp_pose_world(L, L->m.comp_of_body[body], &C);
    pose_compose(&C, &L->m.body_in_comp[body], P);
}

void update_all_body_poses_world(const aqs_linkage *L, pose *out)
{
    int32_t k;
    for (k = 0; k < L->nbodies; k++) {
        int32_t b = L->m.order[k];
        const joint_def *jd = &L->joints[L->m.parent_joint[b]];
        pose place, J, jp;
        pose_from_quat(jd->pos, jd->quat, &place);
        joint_child_pose(jd, L->q + jd->qoff, &J);
        pose_compose(&place, &J, &jp);
        if (jd->parent == AQS_WORLD) out[b] = jp;
        else pose_compose(&out[jd->parent], &jp, &out[b]);
    }
}

void update_body_load_in_comp(const aqs_linkage *L, int32_t body, const pose *comp_world,
                              double f[6])
{
    const body_load *ld = &L->loads[body];
    const pose *bc = &L->m.body_in_comp[body];
    double r[3], n[3];
    mat3_tvec(comp_world->R, ld->force, f + 3);
    mat3_tvec(comp_world->R, ld->torque, f);
    mat3_vec(bc->R, ld->point, r);
    r[0] += bc->p[0];
    r[1] += bc->p[1];
    r[2] += bc->p[2];
    vec3_cross(r, f + 3, n);
    f[0] += n[0];
    f[1] += n[1];
    f[2] += n[2];
}

void update_mark(aqs_linkage *L, int32_t n)
{
    tree *t = &L->t;
    /* The dirty set is top-closed: stop at the first node already in it. */
    for (; n >= 0 && t->stamp[n] != t->epoch; n = t->nodes[n].parent) {
        t->stamp[n] = t->epoch;
        t->dirty[t->ndirty++] = n;
    }
    AQS_ASSERT(t->ndirty <= t->nnodes); /* each node once per epoch */
}

/* Refresh a leaf's b and mark its ancestors. While the whole tree is stale
 * (all_dirty: after an exact step by the articulated-body algorithm, which
 * needs only the composites' loads) b is left to the full update, which
 * recomputes every leaf's; without coefficients dca_enable marks everything
 * for that full update. */
static void refresh_leaf(aqs_linkage *L, int32_t leaf)
{
    if (L->t.data && !L->t.all_dirty) dca_leaf_b(L, leaf);
    update_mark(L, L->t.nodes[leaf].parent);
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
        update_comp_pose_world(L, c, &Pc);
        update_body_load_in_comp(L, b, &Pc, f);
        for (i = 0; i < 6; i++) m->comp_force[6 * c + i] += f[i];
    }
    if (L->col && L->col->stiffness > 0.0) broadphase_penalty(L); /* contact forces */
    for (i = 0; i < m->nloaded_comps; i++) refresh_leaf(L, L->t.leaf_of_comp[m->loaded_comps[i]]);
    stale_loads_fresh(L);
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
    AQS_ASSERT(nd->lam >= 0 && nd->lam + 36 * (int64_t)nd->nh * nd->nh <= L->t.ndata);
    AQS_ASSERT(nd->rank >= 0 && nd->rank <= 6 * nd->nh);
    AQS_ASSERT(nd->xf >= 0 && nd->xf + 6 * (int64_t)nd->nh <= L->t.ndata);
    AQS_ASSERT(nd->nh <= L->t.max_handles);
    if (dca_node_update(L, n) != 0)
        return lk_fail(L, AQS_ENUMERIC, "articulated inertia across joint %d is numerically singular",
                       (int)L->m.eff_joint[nd->joint]);
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
