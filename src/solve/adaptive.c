/* adaptive.c -- partial back-substitution ordered by a binary max-heap keyed
 * by each queued node's total acceleration A(node) (MATH.md §6).
 *
 * Invariant: every joint that is not computed lies in exactly one queued
 * node, so sum_{queued} A = sum_{zeroed j} ||qdd_j||^2 =: eps_c^2 and
 * max_{zeroed} ||qdd_j|| <= sqrt(max_{queued} A) (the heap top). */
#include "adaptive.h"

#include <math.h>
#include <string.h>

#include "dca.h"
#include "frames.h"
#include "heap.h"
#include "arefine.h"
#include "rounding.h"
#include "stale.h"
#include "totalacc.h"
#include "worldbound.h"

aqs_status adaptive_alloc(aqs_linkage *L)
{
    solve_state *s = &L->s;
    size_t n = (size_t)L->t.nnodes + 1;
    int32_t i;
    /* The heap, the prediction and the A values: dca_enable, with the DCA
     * coefficients (an adaptive solve needs those first). */
    s->processed = lk_calloc_in(L, LK_MEM_TREE, n, sizeof(int32_t));
    s->reached = lk_calloc_in(L, LK_MEM_TREE, (size_t)L->m.ncomp + 2, sizeof(int32_t));
    if (!s->processed || !s->reached) return AQS_ENOMEM;
    s->npred = 0;
    s->margin = AQS_PREDICTION_MARGIN;
    s->counted = 0;
    for (i = 0; i < L->m.ne; i++)
        if (L->joints[L->m.eff_joint[i]].type != AQS_JOINT_FREE) s->counted++;
    s->all = 0;
    return AQS_OK;
}

void adaptive_free(aqs_linkage *L)
{
    solve_state *s = &L->s;
    lk_free(L, s->processed);
    lk_free(L, s->reached);
    lk_free(L, s->heap_key);
    lk_free(L, s->heap_item);
    lk_free(L, s->pred);
    lk_free(L, s->tstale);
    lk_free(L, s->aval);
    lk_free(L, s->plist);
    s->processed = s->reached = s->heap_item = s->plist = NULL;
    s->heap_key = s->aval = NULL;
    s->pred = s->tstale = NULL;
    s->npred = 0;
}

/* Uncomputed joints read as acceleration 0 and constraint force NaN. Undo
 * the last solve's outputs: O(N_E) after an adaptive solve. */
static void reset_outputs(aqs_linkage *L)
{
    solve_state *s = &L->s;
    const model *m = &L->m;
    int32_t i, k;
    if (s->all || !s->tracked) {
        for (i = 0; i < L->nv; i++) L->qdd[i] = 0.0;
        for (i = 0; i < 6 * L->njoints; i++) L->cforce[i] = NAN;
    } else {
        for (i = 0; i < s->nprocessed; i++) {
            int32_t j = m->eff_joint[L->t.nodes[s->processed[i]].joint];
            const joint_def *jd = &L->joints[j];
            for (k = 0; k < joint_nv(jd->type); k++) L->qdd[jd->voff + k] = 0.0;
            for (k = 0; k < 6; k++) L->cforce[6 * j + k] = NAN;
        }
        for (i = 0; i < s->nreached; i++) {
            int32_t c = s->reached[i];
            for (k = m->member_start[c]; k < m->member_start[c + 1]; k++) {
                int32_t pj = m->parent_joint[m->members[k]], r;
                if (L->joints[pj].type == AQS_JOINT_FIXED)
                    for (r = 0; r < 6; r++) L->cforce[6 * pj + r] = NAN;
            }
        }
    }
    s->nprocessed = 0;
    s->nreached = 0;
    s->computed = 0;
    s->all = 0;
    s->tracked = 1; /* from here on the lists describe the outputs */
}

static double norm_qdd(const aqs_linkage *L, const joint_def *jd)
{
    const double *qdd = L->qdd + jd->voff;
    const int nv = joint_nv(jd->type);
    double s = 0.0;
    int k;
    for (k = 0; k < nv; k++) s += qdd[k] * qdd[k];
    return sqrt(s);
}

/* Back-substitute node n and hand its children their forces; leaves with
 * welded bodies get their fixed joints' forces. Children that are internal
 * are returned through kids (count returned). */
static int process(aqs_linkage *L, int32_t n, int32_t kids[2])
{
    solve_state *s = &L->s;
    const node *nd = &L->t.nodes[n];
    int32_t child[2] = {nd->a, nd->b}, i, nk = 0;
    const joint_def *jd = &L->joints[L->m.eff_joint[nd->joint]];
    const int counted = jd->type != AQS_JOINT_FREE;
    if (L->dca_form == AQS_DCA_FORM_PHI) dca_node_backsub(L, n); /* its rounding not estimated */
    else dca_node_backsub_sums(L, n); /* the same, with the products' sums rounding_backsub reads */
    rounding_backsub(L, n, counted);
    if (worldbound_active(L)) worldbound_processed(L, n); /* children's world poses */
    s->processed[s->nprocessed++] = n;
    if (counted) {
        double q = norm_qdd(L, jd);
        s->computed++;
        s->comp_sq += q * q;
        if (q > s->lower) s->lower = q;
    }
    for (i = 0; i < 2; i++) {
        const node *c = &L->t.nodes[child[i]];
        if (c->joint >= 0) kids[nk++] = child[i];
        else if (L->m.comp_welded[c->comp]) {
            dca_welded_forces_comp(L, c->comp, L->t.data + nd_xf(c));
            s->reached[s->nreached++] = c->comp;
        }
    }
    return nk;
}

static void push(aqs_linkage *L, heap *h, int32_t n)
{
    solve_state *s = &L->s;
    double a = totalacc_eval(L, n), key = a;
    const node *nd = &L->t.nodes[n];
    /* the world measures queue by E_n, the node's bound, and sum its part
     * beyond held handles E_h (src/solve/worldbound.c) */
    if (worldbound_active(L)) {
        key = worldbound_key(L, n, a, &L->wb->beyond[n]);
        s->sum_h += L->wb->beyond[n];
    }
    s->aval[n] = a;
    heap_push(h, key, n);
    s->sum += key;
    if (nd->ncount > 0) {
        double low = sqrt(a / nd->ncount);
        if (low > s->lower) s->lower = low;
    }
}

/* The world measures' bound on max_b e_b (docs/math.md §10b, "Summing over
 * the queued nodes"): a body lies inside at most one queued node and beyond
 * held handles of any number, so max_b e_b <= max_n E_in + sum_n E_h <= top +
 * sum_h; and <= sum_n E_n. */
static double world_sum(const aqs_linkage *L, double sum, double top)
{
    const double sh = L->s.sum_h > 0.0 ? L->s.sum_h : 0.0, alt = top + sh;
    return alt < sum ? alt : sum;
}

/* The certified bound for the state of the queue (sum: eps_c^2; top: the
 * largest queued A). */
static double bound_of(const aqs_linkage *L, double sum, double top)
{
    const solve_state *s = &L->s;
    switch (s->metric) {
    case AQS_METRIC_ABS_LINKAGE: return sqrt(sum);
    case AQS_METRIC_ABS_WORLD: return world_sum(L, sum, top);
    case AQS_METRIC_REL_WORLD: return sum > 0.0 ? world_sum(L, sum, top) / (L->wb ? L->wb->lower : 0.0) : 0.0;
    case AQS_METRIC_REL_LINKAGE: {
        /* A(root) = the computed joints' squares + the queued A (every joint
         * is in one or the other): used when the root's T was not updated */
        double a_root = s->a_root >= 0.0 ? s->a_root : s->comp_sq + sum;
        return a_root > 0.0 ? sqrt(sum) / sqrt(a_root) : 0.0;
    }
    default: {
        /* joint-wise: the heap top, or the paper's sqrt of the sum */
        double b = s->joint_bound == AQS_JOINT_BOUND_SUM ? sum : top;
        if (s->metric == AQS_METRIC_ABS_JOINT) return sqrt(b);
        return b > 0.0 ? sqrt(b) / s->lower : 0.0;
    }
    }
}

/* Neumaier-compensated sum of the queued values (per: a per-node value
 * instead of the keys, e.g. the world measures' E_h). */
static double resum_of(const heap *h, const double *per)
{
    double sum = 0.0, c = 0.0;
    int32_t i;
    for (i = 0; i < h->size; i++) {
        double v = per ? per[h->item[i]] : h->key[i], t = sum + v;
        c += fabs(sum) >= fabs(v) ? (sum - t) + v : (v - t) + sum;
        sum = t;
    }
    return sum + c;
}

/* Re-sum the running sums (they drift). */
static void resum(aqs_linkage *L, const heap *h)
{
    solve_state *s = &L->s;
    s->sum = resum_of(h, NULL);
    if (worldbound_active(L)) s->sum_h = resum_of(h, L->wb->beyond);
}

/* ------------------------------------------------------------ prediction
 *
 * A node whose A exceeded the margin times the stopping level (the largest
 * A a queued node can have when the solve stops) will be processed by the
 * next solve too (A moves little in a step). The next solve processes such
 * nodes (a top-closed set: A of a parent is at least its children's)
 * without evaluating their A, like the nodes on the way to a free joint,
 * and the updates before it skip their factors T. The bound stays
 * certified: every node left queued is evaluated with a current T (its
 * descendants are outside the set), and a wrong prediction only computes
 * more joints than needed. */

int adaptive_predict_usable(const aqs_linkage *L)
{
    const solve_state *s = &L->s;
    return s->margin > 0.0 && s->eps > 0.0 && s->max_computed == 0;
}

void adaptive_predict_clear(aqs_linkage *L)
{
    solve_state *s = &L->s;
    int32_t i;
    for (i = 0; i < s->npred; i++) {
        int32_t n = s->plist[i];
        if (s->tstale[n]) stale_mark(L, n); /* its T is recomputed by the next update */
        s->pred[n] = 0;
    }
    s->npred = 0;
}

/* The largest A a queued node can have when the solve stops at eps: one
 * node above it keeps the solve going, whichever the measure. */
static double stop_level(const aqs_linkage *L, double eps)
{
    const solve_state *s = &L->s;
    switch (s->metric) {
    case AQS_METRIC_REL_JOINT: return eps * eps * s->lower * s->lower;
    case AQS_METRIC_REL_WORLD: return L->wb ? eps * eps * L->wb->lower * L->wb->lower : 0.0;
    case AQS_METRIC_REL_LINKAGE: return eps * eps * (s->a_root >= 0.0 ? s->a_root : s->comp_sq + s->sum);
    default: return eps * eps;
    }
}

/* After a run to eps: A of the nodes processed without evaluation
 * (children first: ||qdd_k||^2 plus the children's A), then the set for
 * the next solve (parents first): the nodes above margin x the stopping
 * level. Members leaving the set get their T back. */
static void predict_next(aqs_linkage *L, double eps)
{
    solve_state *s = &L->s;
    const tree *t = &L->t;
    const double thr = s->margin * stop_level(L, eps);
    int32_t i;
    if (!adaptive_predict_usable(L)) {
        adaptive_predict_clear(L);
        return;
    }
    for (i = s->nprocessed - 1; i >= 0; i--) {
        int32_t n = s->processed[i];
        const node *nd = &t->nodes[n];
        const int32_t child[2] = {nd->a, nd->b};
        double a, q;
        int k;
        if (!(s->pred[n] || nd->forced)) continue; /* evaluated when pushed */
        {
            const joint_def *jd = &L->joints[L->m.eff_joint[nd->joint]];
            q = jd->type != AQS_JOINT_FREE ? norm_qdd(L, jd) : 0.0;
        }
        a = q * q;
        for (k = 0; k < 2; k++)
            if (t->nodes[child[k]].joint >= 0) a += s->aval[child[k]];
        s->aval[n] = a;
    }
    for (i = 0; i < s->nprocessed; i++) {
        int32_t n = s->processed[i], p = t->nodes[n].parent;
        /* the world measures compare E_n^2 (its key, squared) */
        double far, key = worldbound_active(L) ? worldbound_key(L, n, s->aval[n], &far) : 0.0;
        if (worldbound_active(L)) key *= key;
        else key = s->aval[n];
        if ((p < 0 || (s->pred[p] & 2)) && (t->nodes[n].forced || key >= thr)) s->pred[n] |= 2;
    }
    s->npred = 0;
    for (i = 0; i < s->nprocessed; i++) {
        int32_t n = s->processed[i];
        if (s->pred[n] == 1 && s->tstale[n]) stale_mark(L, n); /* leaves the set */
        s->pred[n] >>= 1;
        if (s->pred[n]) s->plist[s->npred++] = n;
    }
}

static void run(aqs_linkage *L, heap *h, double eps)
{
    solve_state *s = &L->s;
    for (;;) {
        double top = heap_top(h), a;
        int32_t n, kids[2], nk, i;
        if (s->sum < 0.0) s->sum = 0.0; /* rounding of the running sum (§6.4) */
        if (s->sum_h < 0.0) s->sum_h = 0.0;
        s->bound = bound_of(L, s->sum, top);
        if (h->size == 0) {
            s->bound = 0.0;
            break;
        }
        if (s->bound <= eps) {
            /* Accept only after re-summing the queue (the running sum drifts). */
            resum(L, h);
            s->bound = bound_of(L, s->sum, top);
            if (s->bound <= eps) break;
        }
        if (s->max_computed > 0 && s->computed >= s->max_computed) {
            s->capped = 1;
            resum(L, h);
            s->bound = bound_of(L, s->sum, top);
            break;
        }
        heap_pop(h, &a, &n);
        s->sum -= a;
        if (worldbound_active(L)) s->sum_h -= L->wb->beyond[n];
        nk = process(L, n, kids);
        for (i = 0; i < nk; i++) push(L, h, kids[i]);
    }
    s->heap_size = h->size;
}

/* After the computed joints' handle forces moved (arefine_solve): the welded
 * bodies' forces of the reached leaves and the queued nodes' A from their new
 * handle forces, the heap rebuilt in place
 * (entry i is read before a push can move anything at or above it), and the
 * sums and the lower bound L from what is computed and queued now. */
static void requeue(aqs_linkage *L, heap *h)
{
    solve_state *s = &L->s;
    const int32_t size = h->size;
    int32_t i;
    s->comp_sq = 0.0;
    s->lower = 0.0;
    for (i = 0; i < s->nprocessed; i++) {
        const joint_def *jd = &L->joints[L->m.eff_joint[L->t.nodes[s->processed[i]].joint]];
        if (jd->type != AQS_JOINT_FREE) {
            const double q = norm_qdd(L, jd);
            s->comp_sq += q * q;
            if (q > s->lower) s->lower = q;
        }
    }
    for (i = 0; i < s->nprocessed; i++) { /* the welded bodies' forces from the new handle forces */
        const node *nd = &L->t.nodes[s->processed[i]];
        const int32_t child[2] = {nd->a, nd->b};
        int k;
        for (k = 0; k < 2; k++) {
            const node *c = &L->t.nodes[child[k]];
            if (c->joint < 0 && L->m.comp_welded[c->comp]) dca_welded_forces_comp(L, c->comp, L->t.data + nd_xf(c));
        }
    }
    s->sum = 0.0;
    for (i = 0; i < size; i++) {
        const int32_t n = h->item[i];
        h->size = i;
        push(L, h, n);
    }
    resum(L, h);
}

/* The cancellation in a queued node's handle accelerations a = Phi x + b
 * from its handle forces: the largest of their terms' magnitudes over the
 * largest |a| (rows weighed as motion vectors, v by 1/l); +inf where a is 0
 * and a term is not, 0 where it cannot be formed (more than AQS_CANC_MAXH
 * handles, or no I^-1: such a node is left as it is). */
#define AQS_CANC_MAXH 16
static double handle_cancellation(const aqs_linkage *L, int32_t n)
{
    const node *nd = &L->t.nodes[n];
    const double il = L->m.length > 0.0 ? 1.0 / L->m.length : 1.0;
    double a[6 * AQS_CANC_MAXH], m[6 * AQS_CANC_MAXH], am = 0.0, mm = 0.0;
    int32_t i;
    if (nd->nh > AQS_CANC_MAXH || dca_handle_accels_mag(L, n, a, m) != 0) return 0.0;
    for (i = 0; i < 6 * nd->nh; i++) {
        const double w = i % 6 < 3 ? 1.0 : il;
        am = fmax(am, fabs(a[i]) * w);
        mm = fmax(mm, m[i] * w);
    }
    return am > 0.0 ? mm / am : (mm > 0.0 ? INFINITY : 0.0);
}

/* Before the refinement: the queued nodes that would leave their error in
 * the computed joints are processed, their children queued in their place,
 * down to nodes that would not (leaves are exact). The refinement corrects
 * the processed nodes against the queued ones' handle accelerations
 * a = Phi x + b, taken as they are, so what those carry stays in the
 * computed joints. Two kinds, each against the refinement's level or its
 * default, whichever is larger, as RND_SAFETY u times a ratio:
 * - coefficients the rounding levels call lossy (the larger of the node's
 *   levels of its reduced factors and of its b): light distal links behind
 *   a queued heavy-light junction, up to 3,400x the ABA's error, now 33x;
 * - handle accelerations that cancel (handle_cancellation): a light body
 *   between the ground and heavy children, in equilibrium between large
 *   handle forces (random trees of every joint type, masses 1e-3 .. 1e3:
 *   a 1 g body on a planar joint, terms 5.9e6 for accelerations of 2; the
 *   computed joints' forces 3.5e-12 of the largest off, 540x the ABA's;
 *   processing that one node: 1.4e-15). Its rounding levels were 50: the
 *   loss is in evaluating a, not in the coefficients.
 * The list h->item is changed in place; the caller rebuilds the heap
 * (requeue). Returns the nodes processed. */
static int32_t open_lossy(aqs_linkage *L, heap *h)
{
    solve_state *s = &L->s;
    /* the refinement's level, but not below its default: a level set to
     * refine every solve would otherwise process every node */
    const double lim = fmax(L->arf_level, AQS_ADAPTIVE_REFINEMENT_LEVEL) / (RND_SAFETY * RND_U);
    int32_t i = 0, opened = 0;
    while (i < h->size) {
        int32_t n = h->item[i], kids[2], nk;
        if ((s->max_computed > 0 && s->computed >= s->max_computed) ||
            !(rounding_coeff_level(L, n) > lim || handle_cancellation(L, n) > lim)) {
            i++;
            continue;
        }
        nk = process(L, n, kids);
        opened++;
        if (nk == 0) h->item[i] = h->item[--h->size];
        else h->item[i] = kids[0];
        if (nk == 2) h->item[h->size++] = kids[1];
    }
    return opened;
}

/* The stopping measure's rounding estimate, then the computed joints refined
 * where it says they lose digits (docs/math.md §13c), and the run continued
 * if their new handle forces raised the bound. */
static void refine_run(aqs_linkage *L, heap *h, double eps, int from_solve)
{
    solve_state *s = &L->s;
    /* a linkage with a heavy child on a light parent: 1e3 times lower (the
     * computed joints of planar chains with light links between heavy ones
     * were up to 5e3x the ABA's error with estimates of 2e-11 .. 5e-11;
     * docs/math.md §13c) */
    const double level = L->arf_level * (L->m.heavy_ratio > AQS_HEAVY_CHILD ? 1.0 / AQS_HEAVY_CHILD : 1.0);
    double pre_r, pre_rel;
    int32_t opened;
    int pre_cert;
    rounding_finish(L);
    s->arefined = 0;
    if (!(level > 0.0) || L->refine_max <= 0 || s->metric >= AQS_METRIC_ABS_WORLD || s->all ||
        s->nprocessed == 0 || L->dca_form != AQS_DCA_FORM_SQRT ||
        !(s->rounding_rel > level || s->rfe_max > level * s->rfn_max))
        return;
    /* after a solve (api.c): with nothing queued every joint was computed and
     * the exact solve's refinement follows (refine_exact); with the estimate
     * above the rounding fallback's level the ABA answers it
     * (rounding_fallback_due). aqs_linkage_refine has neither. */
    if (from_solve && (h->size == 0 || (L->rfb_level > 0.0 && s->max_computed == 0 &&
                                        !(s->rounding_rel <= L->rfb_level))))
        return;
    /* out of memory: the solve as it is (no node processed for a refinement
     * that cannot run; the next solve tries again) */
    if (arefine_alloc(L) != 0) return;
    pre_r = s->rounding;
    pre_rel = s->rounding_rel;
    pre_cert = s->certified;
    opened = open_lossy(L, h);
    s->arefined = arefine_solve(L, NULL);
    if (s->arefined == 0 && opened == 0) return;
    requeue(L, h);
    run(L, h, eps);
    rounding_finish(L);
    /* The estimate before the lossy nodes were processed covered their
     * joints too (a queued node's part is the largest error of a rho below
     * it), as they were unrefined; after, their joints are estimated from
     * the lossy coefficients by the back-substitution's propagation, which
     * the refinement does not lower: it rose above the rounding fallback's
     * level on the trees where they were found, and the ABA answered (10 of
     * 6,260 adaptive solves of the hard-case suite's 13 seeds). The smaller
     * of the two is kept. */
    if (opened > 0 && pre_rel < s->rounding_rel) {
        s->rounding = pre_r;
        s->rounding_rel = pre_rel;
        s->certified = pre_cert;
    }
}

/* A solve that computed every joint: no bound, nothing queued. */
static void finish_exact(aqs_linkage *L)
{
    solve_state *s = &L->s;
    s->all = 1;
    s->bound = 0.0;
    s->a_root = 0.0;
    stale_set_refinable(L, 1);
}

void adaptive_mark_exact(aqs_linkage *L)
{
    solve_state *s = &L->s;
    s->nprocessed = s->nreached = s->computed = 0;
    s->tracked = 1;
    s->lower = s->sum = s->sum_h = 0.0;
    s->capped = 0;
    finish_exact(L);
    rounding_none(L);
}

void adaptive_solve(aqs_linkage *L)
{
    solve_state *s = &L->s;
    tree *t = &L->t;
    int32_t n, kids[2], i;
    reset_outputs(L);
    s->lower = 0.0;
    s->capped = 0;
    s->sum = s->sum_h = 0.0;
    s->comp_sq = 0.0;
    s->npredicted = 0;
    rounding_solve_start(L);
    stale_set_refinable(L, 0);
    if (t->nnodes == 0) { /* nothing moves */
        if (L->m.comp_welded[L->m.ncomp])
            dca_welded_forces_comp(L, L->m.ncomp, L->t.data + nd_xf(&t->nodes[t->leaf_of_comp[L->m.ncomp]]));
        finish_exact(L);
        rounding_finish(L);
        return;
    }
    if (s->eps == 0.0 && s->max_computed == 0) {
        /* Exact: every node, parents before children (descending index). */
        if (worldbound_active(L)) worldbound_begin(L); /* world poses and L_w, for the rounding estimate */
        for (n = t->nnodes - 1; n >= 0; n--)
            if (t->nodes[n].joint >= 0) process(L, n, kids);
        finish_exact(L);
        rounding_finish(L);
        return;
    }
    {
        heap h;
        int32_t stack_top = 0;
        heap_init(&h, s->heap_key, s->heap_item, t->nnodes);
        /* A(root) from its factor, unless the prediction skipped it (then
         * from the computed and queued joints, bound_of) */
        s->a_root = s->tstale[t->root] ? -1.0 : totalacc_eval(L, t->root);
        if (worldbound_active(L)) worldbound_begin(L);
        /* Nodes on the way to a free joint are always computed: the floating
         * base's acceleration is not part of the approximation (§3.7); so
         * are the predicted ones. They are processed first, parents before
         * children, using the heap's item array from its far end as a
         * stack. */
        if (t->nodes[t->root].forced || s->pred[t->root]) {
            int32_t *st = s->heap_item + t->nnodes; /* grows downwards */
            st[-(++stack_top)] = t->root;
            while (stack_top > 0) {
                int32_t nk;
                n = st[-(stack_top--)];
                nk = process(L, n, kids);
                if (s->pred[n]) s->npredicted++;
                for (i = 0; i < nk; i++) {
                    if (t->nodes[kids[i]].forced || s->pred[kids[i]]) st[-(++stack_top)] = kids[i];
                    else push(L, &h, kids[i]);
                }
            }
        } else {
            push(L, &h, t->root);
        }
        run(L, &h, s->eps);
        refine_run(L, &h, s->eps, 1);
        predict_next(L, s->eps);
    }
    stale_set_refinable(L, 1);
}

void adaptive_refine(aqs_linkage *L, double eps)
{
    solve_state *s = &L->s;
    heap h;
    heap_init(&h, s->heap_key, s->heap_item, L->t.nnodes);
    h.size = s->heap_size;
    s->capped = 0;
    run(L, &h, eps);
    refine_run(L, &h, eps, 0);
    predict_next(L, eps);
}

void adaptive_integrate(aqs_linkage *L, double h)
{
    solve_state *s = &L->s;
    tree *t = &L->t;
    int32_t i, n;
    if (s->all) {
        for (i = 0; i < L->m.ne; i++) {
            const joint_def *jd = &L->joints[L->m.eff_joint[i]];
            joint_integrate(jd, L->q + jd->qoff, L->qdd + jd->voff, h);
        }
        frames_positions_moved(L);
    } else {
        for (i = 0; i < s->nprocessed; i++) {
            const joint_def *jd = &L->joints[L->m.eff_joint[t->nodes[s->processed[i]].joint]];
            joint_integrate(jd, L->q + jd->qoff, L->qdd + jd->voff, h);
        }
        /* Processed nodes were taken parents first: refresh children first. */
        for (i = s->nprocessed - 1; i >= 0; i--) {
            n = s->processed[i];
            frames_node(L, n);
            stale_positions(L, n);
        }
        if (s->nprocessed == 0) stale_loads(L); /* a step never leaves a solve to refine */
    }
}
