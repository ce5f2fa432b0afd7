/* autopath.c -- the automatic path (src/solve/autopath.h).
 *
 * Costs, in instructions (src/solve/cost.h), of the next solve or step:
 *   adaptive = stale + E C_process [+ E (C_move + C_node) + (E - P) C_factor]
 *              (+ E C_arefine when the last adaptive solve refined its
 *              computed joints; C_node + C_keep once the linkage keeps load
 *              factors)
 *   exact    = W_exact             [+ ne C_aba_move]
 * (brackets: a step's move and its update after the move). W_exact: what
 * the last exact solve counted (cost.h's work meter: the articulated-body
 * pass ne C_aba, its refinement's passes where it refined, the exact DCA's
 * where it handed over), ne C_aba before any. stale is the
 * recomputation of the nodes stale now: every node after exact steps, which
 * leave the tree's coefficients to the next adaptive solve. E: internal
 * nodes an adaptive solve processes, P: of which predicted (their factors
 * are skipped after the move); both from the last adaptive solve, or
 * estimated from the accelerations of the last exact one (A(n) is the sum
 * of ||qdd_j||^2 over the joints of node n, so the nodes an adaptive solve
 * would process follow from the exact accelerations).
 *
 * Decision: adaptive when its cost without the stale part is below the
 * exact cost, and the stale part is paid for: adaptive <= exact + regret,
 * (the stale part counting as a switch cost only when exact steps made it:
 * nodes the caller made stale, e.g. by set_positions, an adaptive solve
 * recomputes as well),
 * where regret sums what adaptive steps would have saved over the exact
 * solves chosen since the last adaptive one (a rent-or-buy rule: a switch
 * back to the adaptive solver after exact steps costs at most what staying
 * exact has already lost). Counts only: no clock, reproducible. */
#include "autopath.h"

#include <math.h>

#include "cost.h"

/* Estimate E and P from the accelerations every this many exact solves
 * chosen by the model (the first one after an adaptive solve always). */
#define AUTOPATH_ESTIMATE_EVERY 8

void autopath_init(aqs_linkage *L)
{
    L->ap.on = 1;
    L->ap.exact = 0.0;
    autopath_reset(L);
}

void autopath_reset(aqs_linkage *L)
{
    autopath_state *a = &L->ap;
    a->known = 0;
    a->proc = a->pred = a->regret = 0.0;
    a->refines = 0;
    a->since = 0;
    a->own_stale = 0;
    /* a->exact stays: what an exact solve costs does not depend on the
     * tolerance, the cap, the prediction or this mode (an exact solve before
     * the tolerance was set prices the first choice) */
}

void autopath_tree_moved(aqs_linkage *L, int own) { L->ap.own_stale = own; }

int autopath_applies(const aqs_linkage *L)
{
    return L->ap.on && L->ap.known && L->s.eps > 0.0 && L->s.max_computed == 0 && L->t.nnodes > 0;
}

/* The exact path's solve: the count of the last exact one (cost.h's work
 * meter: refined or handed over, it priced what it did); before any, the
 * articulated-body pass, and on a linkage with a heavy child (which always
 * refines) its refinement's least: one double-double residual and the
 * accelerations it needs, one correction. */
static double exact_cost(const aqs_linkage *L)
{
    double per_joint = COST_ABA_JOINT;
    if (L->ap.exact > 0.0) return L->ap.exact;
    if (L->refine_max > 0 && L->m.heavy_ratio > AQS_HEAVY_CHILD_ABA)
        per_joint += COST_DD_ACCEL + COST_DD_RESIDUAL + COST_ABA_CORRECTION;
    return per_joint * (double)L->m.ne;
}

double autopath_update_cost(const aqs_linkage *L)
{
    const tree *t = &L->t;
    const solve_state *s = &L->s;
    const double cn = cost_node(L);
    double st = 0.0;
    int32_t k;
    if (t->all_dirty || !t->data) return (double)L->m.ne * (cn + COST_FACTOR);
    for (k = 0; k < t->ndirty; k++) {
        int32_t n = t->dirty[k];
        if (t->nodes[n].joint < 0) continue;
        st += cn + (s->pred && s->pred[n] ? 0.0 : COST_FACTOR);
    }
    return st;
}

/* The model's costs (instructions) of the next solve, or step when stepping
 * = 1, by each path; *stale: the part of *adaptive that recomputes nodes
 * already stale (the switch cost after exact steps). Reads the current
 * stale marks; changes nothing. */
static void autopath_costs(const aqs_linkage *L, int stepping, double *adaptive, double *exact,
                           double *stale)
{
    const double cn = cost_node(L), ne = (double)L->m.ne;
    const double E = L->ap.proc, P = L->ap.pred;
    const double st = autopath_update_cost(L);
    double ad = st + E * (COST_PROCESS + (L->ap.refines ? COST_AREFINE : 0.0));
    if (stepping) ad += E * (COST_MOVE + cn) + (E - P) * COST_FACTOR;
    *adaptive = ad;
    *exact = exact_cost(L) + (stepping ? ne * COST_ABA_MOVE : 0.0);
    *stale = st;
}

static int exact_by_costs(double ad, double ex, double st, double regret)
{
    return !(ad - st < ex && ad <= ex + regret);
}

int autopath_prefers_exact(const aqs_linkage *L, int stepping)
{
    double ad, ex, st;
    if (!autopath_applies(L)) return 0;
    autopath_costs(L, stepping, &ad, &ex, &st);
    /* Asked at the end of a step, before the update after its move: the
     * stale nodes are the moved ones, which that update would recompute
     * now. After it the next solve would see none stale (nothing else
     * changes within the step) and take the exact path exactly when the
     * adaptive cost without them is not below the exact one. */
    return ad - st >= ex;
}

int autopath_decide(aqs_linkage *L, int stepping)
{
    autopath_state *a = &L->ap;
    double ad, ex, st;
    int exact;
    autopath_costs(L, stepping, &ad, &ex, &st);
    /* Stale nodes the caller made stale (set_positions, loads) would be
     * recomputed by an adaptive solve as well: a cost of this solve, not of
     * switching. Only the tree left stale by exact steps is the switch. */
    if (!a->own_stale) st = 0.0;
    exact = exact_by_costs(ad, ex, st, a->regret);
    if (exact && ex > ad - st) a->regret += ex - (ad - st);
    a->cost_adaptive = ad;
    a->cost_exact = ex;
    return exact;
}

/* E and P from the accelerations of an exact solve, into L->ap. A(n) of
 * every node, children first (a child's index is below its parent's), in
 * s->aval (free after an exact solve: the predicted set is empty). The
 * joint-wise measures with the heap-top bound process the nodes with A above
 * the stopping level (with L, the largest acceleration, for rel_joint: the
 * solver's lower bound reaches it early, and a smaller one only processes
 * more); the sum-based ones the nodes above the level tau at which the
 * queued frontier's sum falls below eps^2 (times A(root) for rel_linkage),
 * found by octaves of tau. Nodes on the way to a free joint are processed
 * always (A taken as infinite). */
#define OCTAVES 200
/* floor(log2(root / a)) clamped to 0 .. OCTAVES - 1, the last where a or
 * root is 0 or the ratio is beyond double's range (an infinite or NaN
 * octave converted to int is undefined behaviour: found by the fuzzer,
 * tests/fuzz/seeds/autopath-octave-inf) */
static int octave(double root, double a)
{
    double x;
    if (!(a > 0.0) || !(root > 0.0)) return OCTAVES - 1;
    x = floor(log2(root / a));
    if (!(x < OCTAVES - 1)) return OCTAVES - 1;
    return x > 0.0 ? (int)x : 0;
}

static void estimate_from_exact(aqs_linkage *L)
{
    const tree *t = &L->t;
    solve_state *s = &L->s;
    autopath_state *a = &L->ap;
    double *A = s->aval, qmax2 = 0.0, level, eps2 = s->eps * s->eps, E = 0.0, P = 0.0, root;
    int sum_based = s->metric == AQS_METRIC_ABS_LINKAGE || s->metric == AQS_METRIC_REL_LINKAGE ||
                    s->joint_bound == AQS_JOINT_BOUND_SUM;
    int32_t n;
    if (!A) return; /* no DCA coefficients yet (dca_enable): nothing to estimate for */
    for (n = 0; n < t->nnodes; n++) {
        const node *nd = &t->nodes[n];
        const joint_def *jd;
        double q2 = 0.0;
        int k;
        if (nd->joint < 0) {
            A[n] = 0.0;
            continue;
        }
        jd = &L->joints[L->m.eff_joint[nd->joint]];
        if (jd->type != AQS_JOINT_FREE)
            for (k = 0; k < joint_nv(jd->type); k++) q2 += L->qdd[jd->voff + k] * L->qdd[jd->voff + k];
        if (q2 > qmax2) qmax2 = q2;
        A[n] = q2 + A[nd->a] + A[nd->b];
    }
    root = A[t->root];
    switch (s->metric) {
    case AQS_METRIC_REL_JOINT: level = eps2 * qmax2; break;
    case AQS_METRIC_REL_LINKAGE: level = eps2 * root; break;
    default: level = eps2; break;
    }
    if (!sum_based) {
        for (n = 0; n < t->nnodes; n++) {
            const node *nd = &t->nodes[n];
            if (nd->joint < 0) continue;
            if (nd->forced || A[n] > level) E += 1.0;
        }
    } else {
        /* frontier[k]: the sum of the queued A when the nodes with A above
         * tau_k = root 2^-k are processed; count[k]: the nodes above it */
        double frontier[OCTAVES + 1] = {0.0}, count[OCTAVES + 1] = {0.0}, f = 0.0, c = 0.0;
        int k;
        for (n = 0; n < t->nnodes; n++) {
            const node *nd = &t->nodes[n];
            int kn, kp;
            if (nd->joint < 0) continue;
            if (nd->forced) {
                count[0] += 1.0;
                continue;
            }
            /* octave of A: tau_k >= A for k <= kn ... node n is above tau_k for k > kn */
            kn = octave(root, A[n]);
            count[kn + 1] += 1.0; /* processed once tau_k < A: k > kn */
            /* queued while its parent is processed and it is not: k in (kp, kn] */
            if (nd->parent < 0) {
                kp = -1;
            } else if (t->nodes[nd->parent].forced) {
                kp = -1;
            } else {
                kp = octave(root, A[nd->parent]);
            }
            if (kp < kn) {
                frontier[kp + 1] += A[n];
                frontier[kn + 1] -= A[n];
            }
        }
        level = s->metric == AQS_METRIC_REL_LINKAGE ? eps2 * root
                : s->metric == AQS_METRIC_REL_JOINT ? eps2 * qmax2 : eps2;
        for (k = 0; k <= OCTAVES; k++) {
            f += frontier[k];
            c += count[k];
            E = c;
            if (f <= level * (1.0 + 1e-12)) break;
        }
    }
    if (s->margin > 0.0) {
        const double thr = s->margin * level;
        for (n = 0; n < t->nnodes; n++) {
            const node *nd = &t->nodes[n];
            if (nd->joint >= 0 && (nd->forced || A[n] >= thr)) P += 1.0;
        }
    }
    a->proc = E;
    a->pred = P;
}

void autopath_after_solve(aqs_linkage *L, int32_t path, int chose)
{
    autopath_state *a = &L->ap;
    const solve_state *s = &L->s;
    a->path = path;
    a->chose = chose;
    if (!chose) a->cost_adaptive = a->cost_exact = 0.0;
    if (!a->on || !(s->eps > 0.0) || s->max_computed != 0 || L->t.nnodes == 0) return;
    if (path == AQS_PATH_ADAPTIVE) {
        a->proc = (double)s->nprocessed;
        a->pred = (double)s->npred;
        a->refines = s->arefined > 0;
        a->regret = 0.0;
        a->since = 0;
        a->known = 1;
        a->own_stale = 0; /* the update before it left the tree current */
    } else if (a->since++ % AUTOPATH_ESTIMATE_EVERY == 0 || !a->known) {
        estimate_from_exact(L);
        a->known = 1;
    }
}
