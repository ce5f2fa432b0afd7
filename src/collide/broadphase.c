/* broadphase.c -- bounding spheres on the assembly tree, refitted lazily,
 * and the top-down traversal of node pairs (self-collision and obstacles:
 * the obstacles live in the world's leaf). The brute-force all-pairs query
 * is here too, as the reference the tree query must reproduce exactly. */
#include "collide.h"
#include "invariant.h"
#include "kintree.h"

#include <math.h>
#include <string.h>

/* A certificate's margin: the larger of CERT_MARGIN times the smallest
 * shape (bounding sphere radius) of its node's subassembly and CERT_SIZE
 * times the node's sphere radius at build (docs/collision.md). */
#ifndef CERT_MARGIN
#define CERT_MARGIN 0.5
#endif
#ifndef CERT_SIZE
#define CERT_SIZE 0.003
#endif

/* ------------------------------------------------------------ filters */

static uint32_t body_group(const collision *c, int32_t b)
{
    if (b < 0) return c->world_group;
    return b < c->nfilter ? c->group[b] : 1u;
}

static uint32_t body_mask(const collision *c, int32_t b)
{
    if (b < 0) return c->world_mask;
    return b < c->nfilter ? c->mask[b] : 0xFFFFFFFFu;
}

static int excluded(const collision *c, int32_t a, int32_t b)
{
    uint64_t key;
    int32_t lo = 0, hi = c->nexcl;
    if (a > b) { int32_t t = a; a = b; b = t; }
    key = ((uint64_t)(uint32_t)(a + 1) << 32) | (uint32_t)(b + 1);
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (c->excl[mid] < key) lo = mid + 1;
        else hi = mid;
    }
    return lo < c->nexcl && c->excl[lo] == key;
}

/* Whether shapes i and j (on different rigid groups) may touch. */
static int pair_allowed(const aqs_linkage *L, const collision *c, int32_t i, int32_t j)
{
    int32_t a = c->shapes[i].body, b = c->shapes[j].body;
    if (!(body_group(c, a) & body_mask(c, b)) || !(body_group(c, b) & body_mask(c, a))) return 0;
    if (!c->joined && a >= 0 && b >= 0 &&
        (L->joints[L->m.parent_joint[a]].parent == b || L->joints[L->m.parent_joint[b]].parent == a))
        return 0;
    return c->nexcl == 0 || !excluded(c, a, b);
}

/* ------------------------------------------------------------ spheres */

/* Spheres (cx, rx), (cy, ry) in one frame may overlap: conservative by a
 * relative 1e-9 of the radii and 1e-12 of the coordinates, for rounding in
 * the transforms (squared distances: no square root). */
static int spheres_overlap(const double cx[3], double rx, const double cy[3], double ry)
{
    double d0 = cx[0] - cy[0], d1 = cx[1] - cy[1], d2 = cx[2] - cy[2];
    double r = (rx + ry) * (1.0 + 1e-9) +
               1e-12 * (fabs(cx[0]) + fabs(cx[1]) + fabs(cx[2]) + fabs(cy[0]) + fabs(cy[1]) + fabs(cy[2]));
    return d0 * d0 + d1 * d1 + d2 * d2 <= r * r;
}


/* ------------------------------------------------------------ frames */

/* Pose of B's frame (the child frame of the principal joint) in C's frame,
 * and B's world pose from C's. Same operations as src/solve/frames.c. */
static void child_in_node(const aqs_linkage *L, const node *C, pose *Pk)
{
    const tree *t = &L->t;
    pose_compose(&t->poses[t->nodes[C->a].poses + C->ka], t->poses + nd_J(C), Pk);
}

/* World pose of node n's child b from n's world pose (cached Pk). */
static void child_world(const collision *c, int32_t n, const pose *Wc, pose *Wb)
{
    pose_compose(Wc, &c->pk[n], Wb);
}

static void world_centre(const double *s, const pose *W, double out[3])
{
    mat3_vec(W->R, s, out);
    out[0] += W->p[0];
    out[1] += W->p[1];
    out[2] += W->p[2];
}

/* ------------------------------------------------------------ state */

/* Forget the built data of c without freeing it (a copy holds it). */
static void forget_built(collision *c)
{
    c->shape_in = NULL;
    c->comp_start = c->comp_shapes = NULL;
    c->sph = c->centres = NULL;
    c->moved = c->cached = NULL;
    c->ncont = c->xoff = c->xcnt = c->noff = c->ncnt = NULL;
    memset(&c->xp, 0, sizeof c->xp);
    memset(&c->np, 0, sizeof c->np);
    c->mabs = c->mrel = c->mchild = c->mcert = c->margin = NULL;
    c->cert = NULL;
    c->comp_world = c->pk = c->wpose = NULL;
    c->wcen = NULL;
    c->wstamp = NULL;
    c->qstamp = 0;
    c->placed = NULL;
    c->built = 0;
}

/* Free the built data of c (L->col or a saved copy of it) and forget it. */
static void release(aqs_linkage *L, collision *c)
{
    lk_free(L, c->shape_in);
    lk_free(L, c->comp_start);
    lk_free(L, c->comp_shapes);
    lk_free(L, c->sph);
    lk_free(L, c->moved);
    lk_free(L, c->cached);
    lk_free(L, c->ncont);
    lk_free(L, c->xoff);
    lk_free(L, c->xcnt);
    lk_free(L, c->xp.buf[0]);
    lk_free(L, c->xp.buf[1]);
    lk_free(L, c->np.buf[0]);
    lk_free(L, c->np.buf[1]);
    lk_free(L, c->mabs);
    lk_free(L, c->mrel);
    lk_free(L, c->mchild);
    lk_free(L, c->cert);
    lk_free(L, c->mcert);
    lk_free(L, c->margin);
    lk_free(L, c->noff);
    lk_free(L, c->ncnt);
    lk_free(L, c->pk);
    lk_free(L, c->wpose);
    lk_free(L, c->wcen);
    lk_free(L, c->wstamp);
    lk_free(L, c->comp_world);
    lk_free(L, c->placed);
    lk_free(L, c->centres);
    forget_built(c);
}

void broadphase_reset(aqs_linkage *L)
{
    if (L->col) release(L, L->col);
}

aqs_status broadphase_rebuild(aqs_linkage *L, int32_t nshapes, const char *fn)
{
    collision *c = L->col, old = *c;
    aqs_status st;
    /* the new data is built beside the old, which a failure restores whole
       (counters and caches included) */
    forget_built(c);
    c->nshapes = nshapes;
    st = broadphase_build(L, fn);
    if (st != AQS_OK) {
        old.shapes = c->shapes; /* the caller's array (possibly grown) stays */
        old.shape_cap = c->shape_cap;
        *c = old;
        return st;
    }
    release(L, &old);
    return AQS_OK;
}

void broadphase_forget(aqs_linkage *L)
{
    collision *c = L->col;
    if (c && c->built && L->t.nnodes > 0) {
        memset(c->cached, 0, (size_t)L->t.nnodes);
        c->xp.used = 0;
        memset(c->cert, 0, (size_t)L->t.nnodes); /* near lists were filtered */
        c->np.used = 0;
    }
}

void broadphase_node_moved(aqs_linkage *L, int32_t n)
{
    collision *c = L->col;
    if (!c->built) return;
    for (; n >= 0 && !c->moved[n]; n = L->t.nodes[n].parent) c->moved[n] = 1;
}

static int32_t comp_of_shape(const aqs_linkage *L, const shape_def *s)
{
    return s->body < 0 ? L->m.ncomp : L->m.comp_of_body[s->body];
}

/* Motion bounds of node n at its refit, from the old and new Pk (pose of B
 * in n's frame) and its children's bounds. A point of A moved by at most
 * dA = mabs[a] - its value at n's last refit, in A's frame = n's; a point x
 * of B moved by at most dB in B's frame, so by |x_new - x_old| + |Pk_new x_old
 * - Pk_old x_old| <= dB + placement_motion(B's new sphere grown by dB) in n's.
 * Hence mabs[n] += max(dA, dB + dP) and the relative motion mrel[n] += dA +
 * dB + dP, rounded up (certificate.c). */
static void account_motion(const aqs_linkage *L, collision *c, int32_t n, const pose *old_pk)
{
    const node *C = &L->t.nodes[n];
    double dA, dB, dP;
    if (c->first_fit) {
        dA = dB = dP = 0.0;
    } else {
        dA = (c->mabs[C->a] - c->mchild[2 * n]) * (1.0 + 1e-12);
        dB = (c->mabs[C->b] - c->mchild[2 * n + 1]) * (1.0 + 1e-12);
        dP = placement_motion(old_pk, &c->pk[n], c->sph + 4 * C->b, dB);
    }
    c->mchild[2 * n] = c->mabs[C->a];
    c->mchild[2 * n + 1] = c->mabs[C->b];
    if (dA == 0.0 && dB == 0.0 && dP == 0.0) return;
    c->mabs[n] = bound_up(c->mabs[n] + fmax(dA, bound_up(dB + dP)));
    c->mrel[n] = bound_up(c->mrel[n] + bound_up(bound_up(dA + dB) + dP));
}

/* Refit node n if it moved (children first). */
static void refit(aqs_linkage *L, collision *c, int32_t n)
{
    const node *C = &L->t.nodes[n];
    pose Pk;
    double sb[4];
    if (!c->moved[n]) return;
    c->moved[n] = 0;
    c->cached[n] = 0;
    if (C->joint < 0) return; /* leaves are fixed at build */
    c->nodes_refit++;
    refit(L, c, C->a);
    refit(L, c, C->b);
    Pk = c->pk[n];
    child_in_node(L, C, &c->pk[n]);
    account_motion(L, c, n, &Pk);
    Pk = c->pk[n];
    mat3_vec(Pk.R, c->sph + 4 * C->b, sb);
    sb[0] += Pk.p[0];
    sb[1] += Pk.p[1];
    sb[2] += Pk.p[2];
    sb[3] = c->sph[4 * C->b + 3];
    sphere_merge(c->sph + 4 * C->a, sb, c->sph + 4 * n);
}

/* Certificate margins (0 for shapeless nodes, never certified): a node's
 * motion bound grows with its size (rotations times lever arms), so a margin
 * in proportion keeps large nodes' certificates as long-lived as small ones';
 * the shape floor keeps small nodes' from expiring at once. Returns the
 * smallest shape radius below n. */
static double set_margins(const aqs_linkage *L, collision *c, int32_t n)
{
    const node *C = &L->t.nodes[n];
    double r = HUGE_VAL;
    int32_t k;
    if (C->joint >= 0) {
        r = fmin(set_margins(L, c, C->a), set_margins(L, c, C->b));
    } else {
        for (k = c->comp_start[C->comp]; k < c->comp_start[C->comp + 1]; k++)
            r = fmin(r, c->shapes[c->comp_shapes[k]].radius);
    }
    c->margin[n] = r < HUGE_VAL ? fmax(CERT_MARGIN * r, CERT_SIZE * c->sph[4 * n + 3]) : 0.0;
    return r;
}

static void fit_leaf(aqs_linkage *L, collision *c, int32_t n)
{
    int32_t comp = L->t.nodes[n].comp, k, lo = c->comp_start[comp], hi = c->comp_start[comp + 1];
    double *s = c->sph + 4 * n, ctr[3] = {0, 0, 0}, r = 0.0;
    s[0] = s[1] = s[2] = 0.0;
    s[3] = -1.0;
    if (lo == hi) return;
    for (k = lo; k < hi; k++) {
        double w[3];
        int32_t i = c->comp_shapes[k];
        mat3_vec(c->shape_in[i].R, c->shapes[i].centre, w);
        ctr[0] += (w[0] + c->shape_in[i].p[0]) / (hi - lo);
        ctr[1] += (w[1] + c->shape_in[i].p[1]) / (hi - lo);
        ctr[2] += (w[2] + c->shape_in[i].p[2]) / (hi - lo);
    }
    for (k = lo; k < hi; k++) {
        double w[3], d;
        int32_t i = c->comp_shapes[k];
        mat3_vec(c->shape_in[i].R, c->shapes[i].centre, w);
        w[0] += c->shape_in[i].p[0];
        w[1] += c->shape_in[i].p[1];
        w[2] += c->shape_in[i].p[2];
        d = vec3_dist(w, ctr) + c->shapes[i].radius;
        if (d > r) r = d;
    }
    memcpy(s, ctr, sizeof ctr);
    s[3] = r * (1.0 + 1e-12);
}

aqs_status broadphase_build(aqs_linkage *L, const char *fn)
{
    collision *c = L->col;
    const model *m = &L->m;
    int32_t nn = L->t.nnodes, ns = c->nshapes, i, n;
    if (c->built) return AQS_OK;
    c->shape_in = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)ns + 1, sizeof(pose));
    c->comp_start = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)m->ncomp + 2, sizeof(int32_t));
    c->comp_shapes = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)ns + 1, sizeof(int32_t));
    c->sph = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn * 4 + 1, sizeof(double));
    c->moved = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, 1);
    c->cached = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, 1);
    c->ncont = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(int32_t));
    c->xoff = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(int32_t));
    c->xcnt = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(int32_t));
    c->xp.cap = 4 * ns + 1024;
    c->xp.buf[0] = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)c->xp.cap * 2, sizeof(int32_t));
    c->xp.buf[1] = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)c->xp.cap * 2, sizeof(int32_t));
    c->np.cap = 8 * ns + 4096;
    c->np.buf[0] = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)c->np.cap * 2, sizeof(int32_t));
    c->np.buf[1] = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)c->np.cap * 2, sizeof(int32_t));
    c->mabs = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(double));
    c->mrel = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(double));
    c->mchild = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn * 2 + 1, sizeof(double));
    c->cert = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, 1);
    c->mcert = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(double));
    c->margin = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(double));
    c->noff = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(int32_t));
    c->ncnt = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(int32_t));
    c->comp_world = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)m->ncomp + 1, sizeof(pose));
    c->pk = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(pose));
    c->wpose = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(pose));
    c->wcen = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn * 3 + 1, sizeof(double));
    c->wstamp = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)nn + 1, sizeof(uint32_t));
    c->placed = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)ns + 1, sizeof(placed_shape));
    c->centres = lk_calloc_in(L, LK_MEM_COLLISION, (size_t)ns * 3 + 1, sizeof(double));
    if (!c->shape_in || !c->comp_start || !c->comp_shapes || !c->sph || !c->moved || !c->cached ||
        !c->ncont || !c->xoff || !c->xcnt || !c->xp.buf[0] || !c->xp.buf[1] || !c->np.buf[0] ||
        !c->np.buf[1] || !c->mabs || !c->mrel || !c->mchild || !c->cert || !c->mcert ||
        !c->margin || !c->noff || !c->ncnt ||
        !c->comp_world || !c->pk || !c->wpose || !c->wcen || !c->wstamp || !c->placed || !c->centres) {
        broadphase_reset(L);
        return lk_fail(L, AQS_ENOMEM, "%s: out of memory (collision data of %d nodes, %d shapes)",
                       fn, (int)nn, (int)ns);
    }
    /* Shapes grouped by rigid group, in index order within a group: count,
     * prefix sums (start of each group), fill (start -> end), shift back. */
    for (i = 0; i < ns; i++) c->comp_start[comp_of_shape(L, &c->shapes[i]) + 1]++;
    for (i = 0; i <= m->ncomp; i++) c->comp_start[i + 1] += c->comp_start[i];
    for (i = 0; i < ns; i++) c->comp_shapes[c->comp_start[comp_of_shape(L, &c->shapes[i])]++] = i;
    for (i = m->ncomp + 1; i > 0; i--) c->comp_start[i] = c->comp_start[i - 1];
    c->comp_start[0] = 0;
    for (i = 0; i < ns; i++) {
        const shape_def *s = &c->shapes[i];
        pose B, W;
        if (s->body < 0) pose_identity(&B);
        else kin_body_in_comp(L, s->body, &B);
        pose_compose(&B, &s->local, &W);
        if (comp_of_shape(L, s) == m->ncomp) {
            /* fixed in the world: in the world leaf's frame (frames.h) */
            pose Wi;
            pose_inverse(&L->t.world_frame, &Wi);
            pose_compose(&Wi, &W, &c->shape_in[i]);
        } else {
            c->shape_in[i] = W;
        }
    }
    for (n = 0; n < nn; n++) {
        if (L->t.nodes[n].joint < 0) fit_leaf(L, c, n);
        else c->moved[n] = 1;
    }
    c->built = 1;
    c->nodes_refit = 0;
    c->first_fit = 1;
    if (nn > 0) {
        refit(L, c, L->t.root);
        (void)set_margins(L, c, L->t.root);
    }
    c->first_fit = 0;
    return AQS_OK;
}

/* ------------------------------------------------------------ queries */

typedef struct {
    aqs_linkage *L;
    collision *c;
    aqs_contact *out;
    size_t cap, count;
    int any, stop;
    int rec;      /* record hits as cross pairs of the node being computed */
    int penalty;  /* apply penalty forces instead of writing contacts */
    int overflow; /* the pair pool ran full during this query: cache nothing more */
    double grow;  /* certifying: every sphere's radius grows by grow (half the margin) */
    int near_full; /* the near-list pool ran full during this query: certify nothing more */
    int full;      /* AQS_COLLIDE_FULL: no certificate used or made */
} query;

static int shapes_may_touch(const placed_shape *a, const double ca[3], const placed_shape *b,
                            const double cb[3])
{
    return spheres_overlap(ca, a->s->radius, cb, b->s->radius);
}

static const pose *world(query *q, int32_t n);

/* Force sign * k depth n at world point p on the rigid group of shape i's body. */
static void push_group(query *q, int32_t i, double sign, double depth, const double n[3],
                       const double p[3])
{
    aqs_linkage *L = q->L;
    model *m = &L->m;
    int32_t body = q->c->shapes[i].body, comp, k;
    const pose *W;
    double fw[3], f[3], r[3], d[3], mom[3];
    if (body < 0 || (comp = m->comp_of_body[body]) == m->ncomp) return; /* fixed: takes nothing */
    W = world(q, L->t.leaf_of_comp[comp]);
    for (k = 0; k < 3; k++) {
        fw[k] = sign * q->c->stiffness * depth * n[k];
        d[k] = p[k] - W->p[k];
    }
    mat3_tvec(W->R, fw, f); /* in the group's frame, about its origin */
    mat3_tvec(W->R, d, r);
    vec3_cross(r, f, mom);
    for (k = 0; k < 3; k++) {
        m->comp_force[6 * comp + k] += mom[k];
        m->comp_force[6 * comp + 3 + k] += f[k];
    }
    if (!m->comp_loaded[comp]) {
        m->comp_loaded[comp] = 1;
        m->loaded_comps[m->nloaded_comps++] = comp;
    }
}

static void apply_penalty(query *q, int32_t a, int32_t b, double depth, const double n[3],
                          const double p[3])
{
    push_group(q, a, -1.0, depth, n, p);
    push_group(q, b, 1.0, depth, n, p);
}

/* Narrow phase of shapes i and j (allowed) placed at pi, pj (sphere centres
 * ci, cj): a is the lower index, or the body when the other is an obstacle. */
static void narrow_pair(query *q, int32_t i, const placed_shape *pi, const double ci[3], int32_t j,
                        const placed_shape *pj, const double cj[3])
{
    collision *c = q->c;
    double depth, nrm[3], pt[3];
    int swap;
    if (!shapes_may_touch(pi, ci, pj, cj)) return;
    swap = c->shapes[i].body < 0 || (c->shapes[j].body >= 0 && j < i);
    c->narrow_tests++;
    if (!(swap ? narrow_contact(pj, pi, &depth, nrm, pt) : narrow_contact(pi, pj, &depth, nrm, pt)))
        return;
    if (q->penalty) {
        apply_penalty(q, swap ? j : i, swap ? i : j, depth, nrm, pt);
    } else if (q->count < q->cap) {
        aqs_contact *o = &q->out[q->count];
        o->shape_a = swap ? j : i;
        o->shape_b = swap ? i : j;
        o->body_a = c->shapes[o->shape_a].body;
        o->body_b = c->shapes[o->shape_b].body;
        o->depth = depth;
        o->nx = nrm[0];
        o->ny = nrm[1];
        o->nz = nrm[2];
        o->px = pt[0];
        o->py = pt[1];
        o->pz = pt[2];
    }
    q->count++;
    if (q->any) q->stop = 1;
    if (q->rec && !pair_pool_push(&c->xp, i, j)) q->overflow = 1;
}

static void test_shapes(query *q, int32_t i, const placed_shape *pi, const double ci[3], int32_t j,
                        const placed_shape *pj, const double cj[3])
{
    if (pair_allowed(q->L, q->c, i, j)) narrow_pair(q, i, pi, ci, j, pj, cj);
}

/* World pose of node n's frame and its sphere's world centre, memoized per
 * query; computed from the parent's by the operations of all_comp_world. */
static const pose *world(query *q, int32_t n)
{
    collision *c = q->c;
    if (c->wstamp[n] != c->qstamp) {
        int32_t p = q->L->t.nodes[n].parent;
        const pose *Wp = world(q, p);
        if (q->L->t.nodes[p].a == n) c->wpose[n] = *Wp;
        else child_world(c, p, Wp, &c->wpose[n]);
        world_centre(c->sph + 4 * n, &c->wpose[n], c->wcen + 3 * n);
        c->wstamp[n] = c->qstamp;
    }
    return &c->wpose[n];
}

static void leaf_pair(query *q, int32_t x, int32_t y)
{
    collision *c = q->c;
    const pose *Wx = world(q, x), *Wy = world(q, y);
    int32_t cx = q->L->t.nodes[x].comp, cy = q->L->t.nodes[y].comp, k, l;
    for (k = c->comp_start[cx]; k < c->comp_start[cx + 1] && !q->stop; k++) {
        int32_t i = c->comp_shapes[k];
        placed_shape pi;
        double ci[3];
        narrow_place(&c->shapes[i], Wx, &c->shape_in[i], &pi);
        narrow_centre(&pi, ci);
        for (l = c->comp_start[cy]; l < c->comp_start[cy + 1] && !q->stop; l++) {
            int32_t j = c->comp_shapes[l];
            placed_shape pj;
            double cj[3];
            narrow_place(&c->shapes[j], Wy, &c->shape_in[j], &pj);
            narrow_centre(&pj, cj);
            if (q->grow > 0.0) { /* certifying: pairs closer than the margin are near */
                if (!pair_allowed(q->L, c, i, j) ||
                    !spheres_overlap(ci, pi.s->radius + q->grow, cj, pj.s->radius + q->grow))
                    continue;
                if (!pair_pool_push(&c->np, i, j)) q->near_full = 1;
                narrow_pair(q, i, &pi, ci, j, &pj, cj);
            } else {
                test_shapes(q, i, &pi, ci, j, &pj, cj);
            }
        }
    }
}

static void pair(query *q, int32_t x, int32_t y)
{
    collision *c = q->c;
    const node *X = &q->L->t.nodes[x], *Y = &q->L->t.nodes[y];
    if (q->stop || c->sph[4 * x + 3] < 0.0 || c->sph[4 * y + 3] < 0.0) return;
    c->volume_tests++;
    world(q, x);
    world(q, y);
    if (!spheres_overlap(c->wcen + 3 * x, c->sph[4 * x + 3] + q->grow, c->wcen + 3 * y,
                         c->sph[4 * y + 3] + q->grow))
        return;
    if (X->joint < 0 && Y->joint < 0) {
        leaf_pair(q, x, y);
    } else if (Y->joint < 0 || (X->joint >= 0 && c->sph[4 * x + 3] >= c->sph[4 * y + 3])) {
        pair(q, X->a, y);
        pair(q, X->b, y);
    } else {
        pair(q, x, Y->a);
        pair(q, x, Y->b);
    }
}

/* Shape i placed at its rigid group's world frame, and its sphere centre. */
static void place_shape(query *q, int32_t i, placed_shape *p, double ctr[3])
{
    collision *c = q->c;
    const shape_def *s = &c->shapes[i];
    int32_t comp = s->body < 0 ? q->L->m.ncomp : q->L->m.comp_of_body[s->body];
    narrow_place(s, world(q, q->L->t.leaf_of_comp[comp]), &c->shape_in[i], p);
    narrow_centre(p, ctr);
}

/* Test again the pairs off .. off + cnt of pool p at the current placements
 * (the same bits as a traversal would give). */
static void retest(query *q, const pair_pool *p, int32_t off, int32_t cnt)
{
    int32_t k;
    for (k = off; k < off + cnt && !q->stop; k++) {
        int32_t i = p->buf[p->cur][2 * k], j = p->buf[p->cur][2 * k + 1];
        placed_shape pi, pj;
        double ci[3], cj[3];
        place_shape(q, i, &pi, ci);
        place_shape(q, j, &pj, cj);
        test_shapes(q, i, &pi, ci, j, &pj, cj);
    }
}

/* Node n did not move since its contacts were cached: test again only the
 * cached pairs. */
static void replay(query *q, int32_t n)
{
    collision *c = q->c;
    const node *C = &q->L->t.nodes[n];
    if (q->stop || C->joint < 0 || c->ncont[n] == 0) return;
    replay(q, C->a);
    replay(q, C->b);
    retest(q, &c->xp, c->xoff[n], c->xcnt[n]);
}

static int known(const collision *c, const aqs_linkage *L, int32_t n)
{
    return L->t.nodes[n].joint < 0 || c->sph[4 * n + 3] < 0.0 || c->cached[n];
}

/* The pair test (A, B) of internal node n, in the current mode: re-test the
 * near list if n's certificate still holds (its children moved apart by less
 * than the margin since), else traverse with the spheres grown by half a
 * fresh margin and certify; FULL mode traverses plainly. */
static void cross(query *q, int32_t n)
{
    collision *c = q->c;
    const node *C = &q->L->t.nodes[n];
    int32_t off;
    if (q->full) {
        pair(q, C->a, C->b);
        return;
    }
    /* 1e-6 of the margin kept back: the pairs off the near list stay apart by
     * far more than the sphere tests' rounding slack */
    if (c->cert[n] && (c->mrel[n] - c->mcert[n]) * (1.0 + 1e-12) < c->margin[n] * (1.0 - 1e-6)) {
        c->certs_reused++;
        c->near_tests += c->ncnt[n];
        retest(q, &c->np, c->noff[n], c->ncnt[n]);
        return;
    }
    c->cert[n] = 0;
    off = c->np.used;
    q->grow = 0.5 * c->margin[n];
    pair(q, C->a, C->b);
    q->grow = 0.0;
    if (q->stop || q->near_full) return;
    c->cert[n] = 1;
    c->certs_made++;
    c->mcert[n] = c->mrel[n];
    c->noff[n] = off;
    c->ncnt[n] = c->np.used - off;
}

static void self(query *q, int32_t n)
{
    collision *c = q->c;
    const node *C = &q->L->t.nodes[n];
    size_t before = q->count;
    int32_t off;
    if (q->stop || C->joint < 0 || c->sph[4 * n + 3] < 0.0) return;
    if (c->cached[n]) {
        c->nodes_skipped++;
        replay(q, n);
        return;
    }
    self(q, C->a);
    self(q, C->b);
    off = c->xp.used;
    q->rec = 1;
    cross(q, n);
    q->rec = 0;
    if (!q->stop && !q->overflow && known(c, q->L, C->a) && known(c, q->L, C->b)) {
        c->cached[n] = 1;
        c->ncont[n] = (int32_t)(q->count - before);
        c->xoff[n] = off;
        c->xcnt[n] = c->xp.used - off;
    }
}

/* After a query: compact a pool that ran full or is half full. A cached
 * node's replay reads its descendants' lists, so the contact lists are kept
 * all or none (live[] cleared); a certificate stands alone, so near lists
 * that do not fit are dropped one by one. */
static void compact(aqs_linkage *L, pair_pool *p, int overflowed, unsigned char *live, int32_t *off,
                    const int32_t *cnt, int partial)
{
    if (!overflowed && p->used <= p->cap / 2) return;
    if (!pair_pool_compact(p, L->t.nnodes, live, off, cnt, partial)) {
        memset(live, 0, (size_t)L->t.nnodes);
        p->used = 0;
    }
}

/* World poses of every rigid group, top-down, by the traversal's operations. */
static void all_comp_world(const aqs_linkage *L, collision *c, int32_t n, const pose *W)
{
    const node *C = &L->t.nodes[n];
    pose Wb;
    if (C->joint < 0) {
        c->comp_world[C->comp] = *W;
        return;
    }
    child_world(c, n, W, &Wb);
    all_comp_world(L, c, C->a, W);
    all_comp_world(L, c, C->b, &Wb);
}

static void brute(query *q)
{
    aqs_linkage *L = q->L;
    collision *c = q->c;
    int32_t i, j, ns = c->nshapes;
    all_comp_world(L, c, L->t.root, &L->t.world_frame); /* the root's frame (src/solve/frames.h) */
    for (i = 0; i < ns; i++) {
        narrow_place(&c->shapes[i], &c->comp_world[comp_of_shape(L, &c->shapes[i])],
                     &c->shape_in[i], &c->placed[i]);
        narrow_centre(&c->placed[i], c->centres + 3 * i);
    }
    for (i = 0; i < ns && !q->stop; i++) {
        const double *ci = c->centres + 3 * i, ri = c->shapes[i].radius;
        int32_t comp = comp_of_shape(L, &c->shapes[i]);
        for (j = i + 1; j < ns && !q->stop; j++) {
            c->volume_tests++;
            if (!spheres_overlap(ci, ri, c->centres + 3 * j, c->shapes[j].radius)) continue;
            if (comp == comp_of_shape(L, &c->shapes[j])) continue;
            test_shapes(q, i, &c->placed[i], ci, j, &c->placed[j], c->centres + 3 * j);
        }
    }
}

static size_t run_query(aqs_linkage *L, int32_t mode, aqs_contact *out, size_t capacity, int any,
                        int penalty)
{
    collision *c = L->col;
    query q;
    int32_t n;
    q.L = L;
    q.c = c;
    q.out = out;
    q.cap = capacity;
    q.count = 0;
    q.any = any;
    q.stop = 0;
    q.rec = 0;
    q.overflow = 0;
    q.penalty = penalty;
    q.grow = 0.0;
    q.near_full = 0;
    q.full = mode == AQS_COLLIDE_FULL;
    c->nodes_refit = c->volume_tests = c->narrow_tests = c->nodes_skipped = 0;
    c->certs_reused = c->certs_made = c->near_tests = 0;
    if (L->t.nnodes == 0) return 0; /* everything welded to the world */
    if (q.full) { /* a query from scratch: no cached knowledge */
        for (n = 0; n < L->t.nnodes; n++)
            if (L->t.nodes[n].joint >= 0) c->moved[n] = 1;
        memset(c->cert, 0, (size_t)L->t.nnodes);
        c->np.used = 0;
    }
    refit(L, c, L->t.root);
    if (mode == AQS_COLLIDE_BRUTE) {
        brute(&q);
    } else {
        if (++c->qstamp == 0) { /* wrapped: forget every stamp */
            memset(c->wstamp, 0, (size_t)L->t.nnodes * sizeof(uint32_t));
            c->qstamp = 1;
        }
        n = L->t.root;
        c->wpose[n] = L->t.world_frame; /* the root's frame (src/solve/frames.h) */
        world_centre(c->sph + 4 * n, &c->wpose[n], c->wcen + 3 * n);
        c->wstamp[n] = c->qstamp;
        self(&q, n);
        compact(L, &c->xp, q.overflow, c->cached, c->xoff, c->xcnt, 0);
        compact(L, &c->np, q.near_full, c->cert, c->noff, c->ncnt, 1);
    }
    return q.count;
}

size_t broadphase_query(aqs_linkage *L, int32_t mode, aqs_contact *out, size_t capacity, int any)
{
    return run_query(L, mode, out, capacity, any, 0);
}

void broadphase_penalty(aqs_linkage *L)
{
    /* with stiffness set, shapes are never left unbuilt (push_shape, the setter) */
    AQS_ASSERT(L->col->built || L->col->nshapes == 0);
    if (L->col->built && L->col->nshapes > 0) (void)run_query(L, AQS_COLLIDE_LAZY, NULL, 0, 0, 1);
}
