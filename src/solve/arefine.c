/* arefine.c -- iterative refinement of an adaptive solve's computed joints
 * (docs/math.md §13c).
 *
 * An adaptive solve back-substitutes a top-closed set P of nodes (the
 * processed list, parents first); every body lies in one node of the
 * frontier F (the children of P outside it: queued nodes and leaves), whose
 * coefficients give its handles' accelerations from its handle forces,
 * a = Phi x + b. The computed joints' accelerations and the handle forces of
 * P and F solve the reduced system: across each computed joint k (children
 * A, B of its node), a^B_k - X a^A_k = S qdd_k and S^T f_k = Q_k. Its
 * residual needs no uncomputed joint: each handle's acceleration comes from
 * the frontier node that holds it. The correction is the DCA on P with that
 * residual as its only load (frontier b = 0 but for the joint's residual,
 * put into B's b at k, the joint force residual as Q), so the rounding of
 * P's own node updates and back-substitution (a light side joined to a
 * heavy one: docs/hardcases.md) is refined away; what F's coefficients
 * carry is not. */
#include "arefine.h"

#include <math.h>
#include <string.h>

#include "cost.h"
#include "dca.h"
#include "rounding.h"

/* A correction that moved no computed joint's acceleration, and no joint
 * force, by more than this many u (relative, max norms) ends the refinement:
 * it converged. */
#define AREFINE_LEVEL 64.0
/* The joint forces have also converged when every correction after the
 * first moved them by at most 1/AREFINE_CONTRACT of what the first did: the
 * first removed the error and the later ones are the residual's rounding
 * floor (random trees of every joint type, masses 1e-3 .. 1e3, seed 13:
 * 3,830 u, then 108 u and 149 u; the forces 3.1e-13 of the largest off
 * before, 5.7e-14 after, the ABA's 2.5e-14). A refinement whose residual is
 * rounding from its first correction on moves them by as much each time and
 * is not kept (the tilted chain of 10^6 links: 4.7e-8, 4.7e-8, 4.3e-10 of
 * the largest; keeping it would leave 1.1e-10 where the back-substitution's
 * forces are 8.4e-15). */
#define AREFINE_CONTRACT 16.0

struct arefine {
    double *save;        /* per node (soff): b and the handle forces (12 nh), then internal nodes'
                            rho and gamma (d + 6), then 5 rounding levels */
    int64_t *soff;       /* nnodes: each node's place in save */
    unsigned char *inp;  /* nnodes: processed by the solve being refined (0 outside a call) */
    double *kin;         /* 6 per processed node: the relative-acceleration residual of its joint */
    double *cf;          /* 6 per processed node: its joint force before the last correction */
    double *r;           /* nv: each computed joint's force residual Q - S^T f */
    double *dq, *q1;     /* nv: the correction; the accelerations before it */
    double *df;          /* 6 njoints: the correction's joint forces */
    double *hacc;        /* 6 per handle (tree.handles' order): the frontier's handle accelerations */
};

/* Handle h of internal node *n, as the handle of the child that holds it
 * (dca_node_backsub's order: A's handles but ka, then B's but kb). */
static int32_t child_handle(const tree *t, int32_t *n, int32_t h)
{
    const node *C = &t->nodes[*n];
    const int32_t nA = t->nodes[C->a].nh;
    if (h < nA - 1) {
        *n = C->a;
        return h < C->ka ? h : h + 1;
    }
    h -= nA - 1;
    *n = C->b;
    return h < C->kb ? h : h + 1;
}

/* The acceleration of node n's handle h from the frontier node holding it. */
static const double *frontier_accel(const aqs_linkage *L, int32_t n, int32_t h)
{
    const unsigned char *inp = L->arf->inp;
    while (inp[n]) h = child_handle(&L->t, &n, h);
    return L->arf->hacc + 6 * (L->t.nodes[n].handles + h);
}

/* The reduced system's residual at the current answer: R->kin (6 per
 * processed node) and R->r (each computed joint's Q - S^T f). Returns the
 * 2-norm of the relative-acceleration residuals in the length unit of the
 * linkage (|(w, v / l)|), or -1 if an acceleration cannot be formed. */
static double adaptive_residual(aqs_linkage *L)
{
    const tree *t = &L->t;
    struct arefine *R = L->arf;
    const solve_state *s = &L->s;
    const double il = L->m.length > 0.0 ? 1.0 / L->m.length : 1.0;
    double sum = 0.0;
    int32_t i, r, c, k;
    /* the frontier's handle accelerations, once per node */
    for (i = 0; i < s->nprocessed; i++) {
        const node *C = &t->nodes[s->processed[i]];
        const int32_t ch[2] = {C->a, C->b};
        for (k = 0; k < 2; k++)
            if (!R->inp[ch[k]] && dca_handle_accels(L, ch[k], R->hacc + 6 * t->nodes[ch[k]].handles) != 0) return -1.0;
    }
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i];
        const node *C = &t->nodes[n];
        const int32_t j = L->m.eff_joint[C->joint];
        const joint_def *jd = &L->joints[j];
        const double *S = t->data + nd_S(C), *qdd = L->qdd + jd->voff, *f = L->cforce + 6 * j;
        const double *Q = L->tau + jd->voff, *aB = frontier_accel(L, C->b, C->kb);
        double xa[6], *kr = R->kin + 6 * i;
        spatial_xform_motion(t->poses + nd_J(C), frontier_accel(L, C->a, C->ka), xa);
        for (r = 0; r < 6; r++) {
            double v = aB[r] - xa[r];
            for (c = 0; c < C->d; c++) v -= S[r * C->d + c] * qdd[c];
            kr[r] = v;
            sum += r < 3 ? v * v : v * v * il * il;
        }
        for (c = 0; c < C->d; c++) {
            double v = Q[c];
            for (r = 0; r < 6; r++) v -= S[r * C->d + c] * f[r];
            R->r[jd->voff + c] = v;
        }
    }
    return isfinite(sum) ? sqrt(sum) : -1.0;
}

/* The node's place in R->save and what it holds there: b and x (12 nh),
 * then for internal nodes rho, gamma (d + 6) and 5 rounding levels. */
static void save_node(aqs_linkage *L, int32_t n, int dir, int with_x)
{
    tree *t = &L->t;
    const node *nd = &t->nodes[n];
    double *sv = L->arf->save + L->arf->soff[n], *b = t->data + nd->bv;
    const size_t nb = (with_x ? 12 : 6) * (size_t)nd->nh;
    if (dir) memcpy(b, sv, nb * sizeof(double));
    else memcpy(sv, b, nb * sizeof(double));
    if (nd->joint < 0 || !L->arf->inp[n]) return;
    sv += 12 * (size_t)nd->nh;
    {
        double *rg = t->data + nd_rho(nd);
        const size_t ng = (size_t)nd->d + 6;
        if (dir) memcpy(rg, sv, ng * sizeof(double));
        else memcpy(sv, rg, ng * sizeof(double));
        sv += ng;
        if (t->rnd_node) {
            if (dir) memcpy(t->rnd_node + RND_NODE_LEVELS * (size_t)n, sv, RND_NODE_LEVELS * sizeof(double));
            else memcpy(sv, t->rnd_node + RND_NODE_LEVELS * (size_t)n, RND_NODE_LEVELS * sizeof(double));
        }
    }
}

/* P and F (each once: F's nodes are the children of P outside it) */
static void save_adaptive(aqs_linkage *L, int dir, int with_x)
{
    const tree *t = &L->t;
    const solve_state *s = &L->s;
    int32_t i, k;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i], ch[2] = {t->nodes[n].a, t->nodes[n].b};
        save_node(L, n, dir, with_x);
        for (k = 0; k < 2; k++)
            if (!L->arf->inp[ch[k]]) save_node(L, ch[k], dir, with_x);
    }
}

/* The handle forces of P and F (but the root's) into the save area. */
static void save_x(aqs_linkage *L)
{
    const tree *t = &L->t;
    const solve_state *s = &L->s;
    int32_t i, k;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i], ch[2] = {t->nodes[n].a, t->nodes[n].b};
        for (k = 0; k < 2; k++) {
            const node *c = &t->nodes[ch[k]];
            memcpy(L->arf->save + L->arf->soff[ch[k]] + 6 * c->nh, t->data + nd_xf(c), 6 * (size_t)c->nh * sizeof(double));
        }
    }
}

/* x <- saved x + the correction's x (now in the nodes), for P's children. */
static void add_x(aqs_linkage *L)
{
    tree *t = &L->t;
    const solve_state *s = &L->s;
    int32_t i, k, j;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i], ch[2] = {t->nodes[n].a, t->nodes[n].b};
        for (k = 0; k < 2; k++) {
            const node *c = &t->nodes[ch[k]];
            const double *sv = L->arf->save + L->arf->soff[ch[k]] + 6 * c->nh;
            double *x = t->data + nd_xf(c);
            for (j = 0; j < 6 * c->nh; j++) x[j] += sv[j];
        }
    }
}

/* One correction of P from the residual in R->kin, R->r: into R->dq, R->df
 * and the handle forces of P's children. Returns 0, or -1 if a node update
 * fails. */
static int adaptive_correction(aqs_linkage *L)
{
    tree *t = &L->t;
    struct arefine *R = L->arf;
    const solve_state *s = &L->s;
    double *tau = L->tau, *qdd = L->qdd, *cforce = L->cforce;
    int32_t i, k, r, fail = 0;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i], ch[2] = {t->nodes[n].a, t->nodes[n].b};
        for (k = 0; k < 2; k++)
            if (!R->inp[ch[k]]) memset(t->data + t->nodes[ch[k]].bv, 0, 6 * (size_t)t->nodes[ch[k]].nh * sizeof(double));
    }
    L->tau = R->r;
    for (i = s->nprocessed - 1; i >= 0 && !fail; i--) { /* children first */
        const int32_t n = s->processed[i];
        const node *C = &t->nodes[n];
        double *bB = t->data + t->nodes[C->b].bv + 6 * C->kb;
        for (r = 0; r < 6; r++) bB[r] += R->kin[6 * i + r];
        if (dca_node_loads(L, n) != 0 && dca_node_update(L, n) != 0) fail = 1;
    }
    L->tau = tau;
    if (fail) return -1;
    memset(t->data + nd_xf(&t->nodes[t->root]), 0, 6 * (size_t)t->nodes[t->root].nh * sizeof(double));
    L->qdd = R->dq;
    L->cforce = R->df;
    for (i = 0; i < s->nprocessed; i++) dca_node_backsub(L, s->processed[i]); /* parents first */
    L->qdd = qdd;
    L->cforce = cforce;
    return 0;
}

/* Apply (dir 1) or take back (dir 0) the correction in R->dq, R->df to the
 * computed joints (R->q1, R->cf hold what they were). Returns the largest
 * change and sets *qmax to the largest |qdd| after, *fstep to the largest
 * change of a joint force over the largest joint force after (max norms). */
static double apply_adaptive(aqs_linkage *L, int dir, double *qmax, double *fstep)
{
    const tree *t = &L->t;
    struct arefine *R = L->arf;
    const solve_state *s = &L->s;
    double dmax = 0.0, m = 0.0, fd = 0.0, fm = 0.0;
    int32_t i, c;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t j = L->m.eff_joint[t->nodes[s->processed[i]].joint];
        const joint_def *jd = &L->joints[j];
        double *q = L->qdd + jd->voff, *f = L->cforce + 6 * j;
        for (c = 0; c < joint_nv(jd->type); c++) {
            if (dir) {
                R->q1[jd->voff + c] = q[c];
                q[c] += R->dq[jd->voff + c];
                if (fabs(R->dq[jd->voff + c]) > dmax) dmax = fabs(R->dq[jd->voff + c]);
            } else {
                q[c] = R->q1[jd->voff + c];
            }
            if (fabs(q[c]) > m) m = fabs(q[c]);
        }
        for (c = 0; c < 6; c++) {
            if (dir) {
                R->cf[6 * i + c] = f[c];
                f[c] += R->df[6 * j + c];
                fd = fmax(fd, fabs(R->df[6 * j + c]));
            } else {
                f[c] = R->cf[6 * i + c];
            }
            fm = fmax(fm, fabs(f[c]));
        }
    }
    *qmax = m;
    *fstep = fm > 0.0 ? fd / fm : 0.0;
    return dmax;
}

void arefine_free(aqs_linkage *L)
{
    struct arefine *R = L->arf;
    if (!R) return;
    lk_free(L, R->save);
    lk_free(L, R->soff);
    lk_free(L, R->inp);
    lk_free(L, R->kin);
    lk_free(L, R->cf);
    lk_free(L, R->r);
    lk_free(L, R->dq);
    lk_free(L, R->q1);
    lk_free(L, R->df);
    lk_free(L, R->hacc);
    lk_free(L, R);
    L->arf = NULL;
}

/* The arrays, at the first solve that refines. Returns 0, or -1 when out of
 * memory (nothing kept: that solve is returned unrefined). */
int arefine_alloc(aqs_linkage *L)
{
    const tree *t = &L->t;
    struct arefine *R;
    const size_t nn = (size_t)t->nnodes + 1, nv = (size_t)L->nv + 1;
    int64_t off = 0;
    int32_t k;
    if (L->arf) return 0;
    if (dca_loads_enable(L) != AQS_OK) return -1;
    R = lk_calloc_in(L, LK_MEM_DCA, 1, sizeof *R);
    if (!R) return -1;
    L->arf = R;
    for (k = 0; k < t->nnodes; k++) {
        const node *nd = &t->nodes[k];
        off += 12 * (int64_t)nd->nh + (nd->joint >= 0 ? (int64_t)nd->d + 6 + RND_NODE_LEVELS : 0);
    }
    R->save = lk_calloc_in(L, LK_MEM_DCA, (size_t)off + 1, sizeof(double));
    R->soff = lk_calloc_in(L, LK_MEM_DCA, nn, sizeof(int64_t));
    R->inp = lk_calloc_in(L, LK_MEM_DCA, nn, 1);
    R->kin = lk_calloc_in(L, LK_MEM_DCA, 6 * nn, sizeof(double));
    R->cf = lk_calloc_in(L, LK_MEM_DCA, 6 * nn, sizeof(double));
    R->r = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->dq = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->q1 = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->df = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->njoints + 1, sizeof(double));
    R->hacc = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)t->nhandles + 1, sizeof(double));
    if (!R->save || !R->soff || !R->inp || !R->kin || !R->cf || !R->r || !R->dq || !R->q1 || !R->df || !R->hacc) {
        arefine_free(L);
        return -1;
    }
    off = 0;
    for (k = 0; k < t->nnodes; k++) {
        const node *nd = &t->nodes[k];
        R->soff[k] = off;
        off += 12 * (int64_t)nd->nh + (nd->joint >= 0 ? (int64_t)nd->d + 6 + RND_NODE_LEVELS : 0);
    }
    return 0;
}

/* The load factors are enabled by the first solve that refines, after its
 * node updates ran, and a node keeps them from its next update on: a
 * processed node without them is updated again here (the same positions
 * and loads, so its values come out bit for bit the same) to keep them, so
 * that this solve's corrections take the path of any later solve at the
 * same state (the loads-only pass wherever a node has its factors).
 * Without it the first of repeated solves at one state differed from the
 * others (masses alternating by 1e9, 300 links, exact DCA: by 2.1e-13, 1.6e-15
 * relative). Each node pays this once. Returns 0, or -1 when a node update
 * fails (it did not before). */
static int keep_factors(aqs_linkage *L)
{
    const solve_state *s = &L->s;
    const tree *t = &L->t;
    int32_t i;
    for (i = 0; i < s->nprocessed; i++) {
        const int32_t n = s->processed[i];
        if (t->nodes[n].joint >= 0 && !t->lfok[n] && dca_node_update(L, n) != 0) return -1;
    }
    return 0;
}

int32_t arefine_solve(aqs_linkage *L, int *converged)
{
    const solve_state *s = &L->s;
    struct arefine *R;
    double rn, qmax;
    int32_t i, it, kept = 0;
    double last_fstep = INFINITY; /* the last correction's force step (relative) */
    double first_fstep = 0.0, later_fstep = 0.0; /* the first's; the largest after it */
    if (s->nprocessed == 0 || L->refine_max <= 0 || L->dca_form != AQS_DCA_FORM_SQRT) return 0;
    if (arefine_alloc(L) != 0 || keep_factors(L) != 0) return 0; /* out of memory: the answer as it is */
    cost_count(L, COST_AREFINE * (double)s->nprocessed);
    R = L->arf;
    for (i = 0; i < s->nprocessed; i++) R->inp[s->processed[i]] = 1;
    rn = adaptive_residual(L);
    if (rn > 0.0) {
        save_adaptive(L, 0, 1);
        for (it = 0; it < L->refine_max; it++) {
            double rn1, dmax, fstep;
            if (adaptive_correction(L) != 0) break;
            add_x(L);
            save_adaptive(L, 1, 0); /* the solve's b, rho, gamma and levels back, for the residual */
            dmax = apply_adaptive(L, 1, &qmax, &fstep);
            last_fstep = fstep;
            if (it == 0) first_fstep = fstep;
            else later_fstep = fmax(later_fstep, fstep);
            if (dmax <= AREFINE_LEVEL * RND_U * qmax && fstep <= AREFINE_LEVEL * RND_U) {
                /* resolved: a step this small is kept as it is (no residual
                 * to evaluate), and none follows */
                save_x(L);
                kept++;
                break;
            }
            rn1 = adaptive_residual(L);
            if (!(rn1 >= 0.0 && rn1 < rn)) { /* not lower: the answer as it was */
                apply_adaptive(L, 0, &qmax, &fstep);
                break;
            }
            save_x(L);
            kept++;
            rn = rn1;
            if (rn == 0.0) {
                last_fstep = 0.0;
                break;
            }
        }
        save_adaptive(L, 1, 1); /* b, rho, gamma, levels as the solve left them; x the kept one */
    }
    for (i = 0; i < s->nprocessed; i++) R->inp[s->processed[i]] = 0;
    /* the forces converged: the last correction, kept or not, moved them by
     * at most AREFINE_LEVEL u (or the residual reached 0), or every one after
     * the first by at most 1/AREFINE_CONTRACT of the first's move */
    if (converged)
        *converged = last_fstep <= AREFINE_LEVEL * RND_U ||
                     (kept > 0 && later_fstep > 0.0 && later_fstep * AREFINE_CONTRACT <= first_fstep);
    return kept;
}
