/* refine.c -- iterative refinement of the exact DCA solve (docs/math.md
 * §13a). The DCA's back-substitution computes a light body's joint
 * acceleration between heavy ones as rho - QX x, a difference of large
 * terms: its error is about u times the local mass ratio (or 1/delta near
 * equilibrium), not u. Classical fixed-precision refinement repairs that:
 *     r = Q - ID(qdd)            (src/solve/residual.c, the real loads)
 *     qdd <- qdd + DCA^-1(r)     (the same node coefficients, r the only
 *                                 load: no gravity, no external force)
 * Each correction multiplies the error by about the DCA's own relative error
 * level where that is < 1, until the residual's rounding limits it, which is
 * what the backward-stable articulated-body solve sees too. Where it is not
 * (mass ratios 1e9: DCA^-1 M is off by O(1) in a few directions), plain
 * refinement diverges; so the corrections are the steps of GMRES on
 * M dq = r right-preconditioned by DCA^-1 (GMRES-IR, Carson & Higham 2018),
 * whose first step is the plain correction, taken as it is when resolved.
 * A Krylov cycle whose iterate lost the Arnoldi relation is followed by
 * another from the true residual; one that converged is kept where the
 * residual is at its rounding floor and cannot tell (FLOOR_FACTOR).
 *
 * The correction recomputes the nodes' load-dependent values (rho, gamma
 * and b) with the residual as the load: by the loads-only pass
 * (dca_node_loads) from the load factors the node updates keep once
 * arefine_solve enabled them, else by the node update (dca_node_update:
 * Lambda, FX, QX come out bit for bit the same, the positions being
 * unchanged); then the back-substitution into scratch. The unrefined solve's
 * load-dependent values are saved first and put back at the end, so the
 * lazy update's next solve finds them as they were. The joint forces are
 * refined first, by the DCA's own residual, and last, where they do not
 * balance the bodies, by the bodies' accelerations (FORCES below). */
#include "refine.h"

#include <math.h>
#include <string.h>

#include "aba.h"
#include "arefine.h"
#include "cost.h"
#include "dca.h"
#include "residual.h"
#include "rounding.h"

/* The size of a step (units of u, relative) after which no further one is
 * tried (resolved below): REFINE_LEVEL for a cycle's first step (the plain
 * correction's level, where one correction converges), REFINE_LEVEL_LATER
 * for the next ones (GMRES's late steps contract the error by 0.03 .. 0.4
 * each, measured, not by the DCA's relative error level). At most
 * L->refine_max cycles (aqs_linkage_set_exact_refinement). */
#define REFINE_LEVEL 1024.0
/* A first cycle's plain correction is formed by the loads-only pass where
 * the nodes keep their load factors (dca_node_loads: W = E^T E, not E, so its
 * relative error is about the square of the node update's): taken as it is
 * only when it moved the answer by at most LOADS_LEVEL u (relative, max
 * norms: the molecule of 2,000 joints 2.1 .. 2.7 u), else formed again by
 * the node update (the masses alternating by 1e9: 1.5e8 u, against 80 u
 * for the node update's). */
#define LOADS_LEVEL 64.0
#define REFINE_LEVEL_LATER 64.0
/* Krylov steps of one GMRES cycle at most (each one correction solve, one
 * node pass): altmass r = 1e9 at 1000 links takes 18, at 10^4 links 103
 * then 104. The basis is allocated for KRYLOV_FIRST steps, grown to
 * KRYLOV_MAX at the first cycle that needs more. */
#define KRYLOV_FIRST 20
#define KRYLOV_MAX 128
/* A cycle after the first (restarted because its predecessor's true
 * residual was more than RESTART_GAP times GMRES's estimate: the Arnoldi
 * relation was lost) stops only once its estimate is below LATER_DROP times
 * its starting residual: that residual sits at its rounding floor (below),
 * where the step sizes do not tell the stall from convergence. */
#define RESTART_GAP 100.0
/* ... and only when its iterate qdd + Z y summed terms |z_l y_l| above
 * RESTART_SUM u ||qdd||_inf (max norms): the directions z_l carry the DCA's
 * relative error on their loads, so a combination that cancels that much
 * carries it amplified. Measured (3 solves each, 2026-12-03): altmass 1e6 at
 * 1,000 links 5.7e5 .. 1.3e6 (a restart gained nothing: 2.4e-16 either way,
 * at 2.6x the cost), ratio 1e9 at 100 links 7.3e8 .. 2.2e9, at 1,000 links
 * 8.0e9 .. 2.7e11, at 10^4 links 4.0e9 .. 3.6e10. */
#define RESTART_SUM 1e8
#define LATER_DROP 1e-8
/* The residual's rounding floor: ||M d|| with d_i = +-u |qdd_i| (signs
 * pseudo-random), the residual that rounding the answer to doubles alone
 * leaves. A GMRES cycle whose residual went from at most FLOOR_FACTOR floors
 * to at most FLOOR_FACTOR floors is kept when it converged by its estimate:
 * there the residual cannot tell a better answer from a worse one (altmass
 * 1e9 at 10^4 links: residuals 3.4e4 and 4.5e4 at a floor of 3.5e4 for
 * errors 1.2e-12 and 8e-16). 4 rejected such a cycle at 2,000 links (1,765
 * against a floor of 439). */
#define FLOOR_FACTOR 16.0
/* FORCES. The joint forces of a refined solve. The inverse dynamics' forces
 * of the refined accelerations carry their error amplified (id_force_error):
 * on a 2,000-link chain falling under gravity 1.3e-7 of the largest, against
 * 2.9e-16 for the back-substitution's forces, which do not pass through the
 * accelerations. Those are refined first, with the accelerations, by the
 * DCA's own residual (src/solve/arefine.c with every node processed: across
 * each joint, the bodies' relative acceleration from their handle forces
 * against S qdd, and Q - S^T f), which brings them within 1.7x of the
 * articulated-body solver's forces against a __float128 reference on every
 * hard-case family (docs/hardcases.md); then GMRES refines the accelerations
 * alone. That first refinement is kept only if it converged (its last
 * correction moved nothing by more than 64 u): on the tilted chain of 10^5
 * links its residual is rounding (bodies between large, nearly balancing
 * handle forces), its corrections move the forces by 4e4 u, 2.8e4 u, ...,
 * and taking them left the forces at 4.5e-12 where the back-substitution's
 * are 1.9e-15. The inverse dynamics' forces replace them only where their
 * estimated error is at most ID_FORCE_LEVEL u (near equilibrium, where the
 * accelerations are small: 1e-20 there, 5.6e-16 on the 6-link point-mass
 * chains), and where the first refinement was not kept and their estimate
 * is below the unrefined forces' (taken as the largest change of the
 * accelerations by the refinement, relative: the iCub with link inertias
 * floored at 1e-16 of their mass, whose back-substitution is 1.6e-5 off,
 * its forces 5.9e-6, the inverse dynamics' of the refined accelerations
 * 3.4e-13, the ABA's 9.4e-13). In the inverse-inertia form (no arefine_solve) they always do:
 * its back-substitution's forces are worse still (3.1e-3 on the oblique
 * chain of 2,000 links). Before either rule, after GMRES (both forms):
 * where the forces do not balance the bodies, those of the bodies'
 * accelerations refined as the state (state_forces below); where that
 * refinement ran and they do balance, they stay as they are and the two
 * rules above are not applied. */
#define ID_FORCE_LEVEL 16.0
/* The joint forces by the bodies' accelerations (state_forces below) where
 * the back-substitution's do not balance the bodies to this many u. */
#define STATE_BALANCE 16.0
/* ... of min(the largest term, this many times the largest joint force):
 * 16, as the articulated-body check has it (ABA_FORCE_SCALE), left one of
 * twelve floating trees' forces 2.0e-14 off (54x the ABA's) at a balance of
 * 11.6 u (state_forces). */
#define STATE_FORCE_SCALE 4.0
/* ... once the bodies' accelerations are refined: the first correction
 * lowered the residual by at least this factor (state_forces). */
#define STATE_CONTRACT 16.0
/* ... with at most this many times L->refine_max corrections, each kept while
 * it lowers the residual, the last where the forces settle
 * (residual_forces_settled): spherical joints between bodies 1e9 apart
 * contract 150x a correction, and their forces, 1e-9 of the bodies'
 * weights, need the residual at 1e-25 of them (six corrections; with
 * three the forces stayed 2.6e-12 off, the articulated-body solve's
 * 5.2e-16: hardcases altmass/joints/sr0/lllH/r=1e+09/seed=1). */
#define STATE_CORRECTIONS 3

struct refine {
    double *save;   /* per node: b and the handle forces (12 nh), then internal nodes' rho and
                       gamma (d + 6), then RND_NODE_LEVELS rounding levels */
    double *r, *r2; /* nv: the residual of the accepted and of the candidate accelerations */
    double *dq;     /* nv: the correction */
    double *q1;     /* nv: the candidate */
    double *q0;     /* nv: the unrefined accelerations */
    double *df;     /* 6 njoints: the correction's joint forces (not used after) */
    double *acc;    /* 6 ne: scratch of the balance (residual_balance) */
    double *v;      /* (kcap + 1) nv: the Krylov basis of M P (orthonormal) */
    double *z;      /* kcap nv: P v_j, the preconditioned directions */
    int32_t kcap;   /* steps the basis holds (KRYLOV_FIRST or KRYLOV_MAX; 0 before it is allocated) */
    double (*h)[KRYLOV_MAX]; /* KRYLOV_MAX + 1 rows: the Hessenberg matrix, with the basis (132 KB: not
                                on the stack of the caller's thread) */
    ddouble *sacc;  /* 6 ne: the bodies' accelerations of a state correction in double-double */
    ddouble *sacc0; /* 6 ne: the same before a correction */
    ddouble *sfw;   /* 6 ne: scratch of the double-double residual */
    double *fcur;   /* 6 ne: the joint forces of sacc's state, ABA order */
    double *ftry;   /* 6 ne: those of a correction tried */
};

void refine_free(aqs_linkage *L)
{
    struct refine *R = L->rf;
    if (!R) return;
    lk_free(L, R->save);
    lk_free(L, R->r);
    lk_free(L, R->r2);
    lk_free(L, R->dq);
    lk_free(L, R->q1);
    lk_free(L, R->q0);
    lk_free(L, R->df);
    lk_free(L, R->acc);
    lk_free(L, R->v);
    lk_free(L, R->z);
    lk_free(L, R->h);
    lk_free(L, R->sacc);
    lk_free(L, R->sacc0);
    lk_free(L, R->sfw);
    lk_free(L, R->fcur);
    lk_free(L, R->ftry);
    lk_free(L, R);
    L->rf = NULL;
}

/* The refinement's arrays, at the first solve that refines. Returns 0, or -1
 * when out of memory (nothing kept: that solve is returned unrefined). */
static int refine_alloc(aqs_linkage *L)
{
    const tree *t = &L->t;
    struct refine *R;
    size_t n = 0, nv = (size_t)L->nv + 1;
    int32_t k;
    if (L->rf) return 0;
    for (k = 0; k < t->nnodes; k++) {
        const node *nd = &t->nodes[k];
        n += 12 * (size_t)nd->nh + (nd->joint >= 0 ? (size_t)nd->d + 6 + RND_NODE_LEVELS : 0);
    }
    R = lk_calloc_in(L, LK_MEM_DCA, 1, sizeof *R);
    if (!R) return -1;
    L->rf = R;
    R->save = lk_calloc_in(L, LK_MEM_DCA, n + 1, sizeof(double));
    R->r = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->r2 = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->dq = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->q1 = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->q0 = lk_calloc_in(L, LK_MEM_DCA, nv, sizeof(double));
    R->df = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->njoints + 1, sizeof(double));
    R->acc = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(double));
    R->sacc = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(ddouble));
    R->sacc0 = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(ddouble));
    R->sfw = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(ddouble));
    R->fcur = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(double));
    R->ftry = lk_calloc_in(L, LK_MEM_DCA, 6 * (size_t)L->m.ne + 1, sizeof(double));
    if (!R->save || !R->r || !R->r2 || !R->dq || !R->q1 || !R->q0 || !R->df || !R->acc || !R->sacc || !R->sacc0 ||
        !R->sfw || !R->fcur || !R->ftry) {
        refine_free(L);
        return -1;
    }
    residual_dd_select(L);
    return 0;
}

/* The Krylov basis for steps steps, at the first solve whose first
 * correction is not resolved (benign linkages never hold it), grown (its
 * contents kept) at the first cycle that needs more. Returns 0, or -1 when
 * out of memory (the basis as it was): that cycle then stops where it is
 * (the plain correction alone, if there is no basis). */
static int krylov_alloc(aqs_linkage *L, int32_t steps)
{
    struct refine *R = L->rf;
    const size_t nv = (size_t)L->nv + 1, old = (size_t)R->kcap;
    double *v, *z;
    if (R->kcap >= steps) return 0;
    if (!R->h) {
        R->h = lk_calloc_in(L, LK_MEM_DCA, KRYLOV_MAX + 1, sizeof *R->h);
        if (!R->h) return -1;
    }
    v = lk_calloc_in(L, LK_MEM_DCA, ((size_t)steps + 1) * nv, sizeof(double));
    z = lk_calloc_in(L, LK_MEM_DCA, (size_t)steps * nv, sizeof(double));
    if (!v || !z) {
        lk_free(L, v);
        lk_free(L, z);
        return -1;
    }
    if (R->v) {
        memcpy(v, R->v, (old + 1) * nv * sizeof(double));
        memcpy(z, R->z, old * nv * sizeof(double));
        lk_free(L, R->v);
        lk_free(L, R->z);
    }
    R->v = v;
    R->z = z;
    R->kcap = steps;
    return 0;
}

/* The load-dependent node values into R->save (dir 0) or back (dir 1). */
static void save_loads(aqs_linkage *L, int dir)
{
    tree *t = &L->t;
    double *s = L->rf->save;
    int32_t k;
    for (k = 0; k < t->nnodes; k++) {
        const node *nd = &t->nodes[k];
        double *b = t->data + nd->bv; /* b, then the handle forces */
        const size_t nb = 12 * (size_t)nd->nh;
        if (dir) memcpy(b, s, nb * sizeof(double));
        else memcpy(s, b, nb * sizeof(double));
        s += nb;
        if (nd->joint < 0) continue;
        {
            double *rg = t->data + nd_rho(nd); /* rho, then gamma */
            const size_t ng = (size_t)nd->d + 6;
            if (dir) memcpy(rg, s, ng * sizeof(double));
            else memcpy(s, rg, ng * sizeof(double));
            s += ng;
            if (t->rnd_node) {
                if (dir) memcpy(t->rnd_node + RND_NODE_LEVELS * (size_t)k, s, RND_NODE_LEVELS * sizeof(double));
                else memcpy(s, t->rnd_node + RND_NODE_LEVELS * (size_t)k, RND_NODE_LEVELS * sizeof(double));
            }
            s += RND_NODE_LEVELS;
        }
    }
}

/* dq = DCA^-1(r): every leaf's b zero (no gravity, no load), the node update
 * with r as the joint forces, the back-substitution into R's scratch.
 * Returns 0, or -1 when a node update fails (r not finite). */
static int correction(aqs_linkage *L, double *r, int loads_only)
{
    tree *t = &L->t;
    struct refine *R = L->rf;
    double *tau = L->tau, *qdd = L->qdd, *cforce = L->cforce;
    int32_t n, fail = 0;
    for (n = 0; n < t->nnodes; n++) {
        const node *nd = &t->nodes[n];
        if (nd->joint < 0) memset(t->data + nd->bv, 0, 6 * (size_t)nd->nh * sizeof(double));
    }
    L->tau = r;
    for (n = 0; n < t->nnodes && !fail; n++) /* children first */
        if (t->nodes[n].joint >= 0) {
            if (loads_only && dca_node_loads(L, n) == 0) {
                cost_count(L, COST_NODE_LOADS);
                continue;
            }
            cost_count(L, (loads_only ? COST_NODE_LOADS : 0.0) + cost_node(L));
            if (dca_node_update(L, n) != 0) fail = 1;
        }
    L->tau = tau;
    if (fail) return -1;
    memset(t->data + nd_xf(&t->nodes[t->root]), 0, 6 * (size_t)t->nodes[t->root].nh * sizeof(double));
    L->qdd = R->dq;
    L->cforce = R->df;
    for (n = t->nnodes - 1; n >= 0; n--) /* parents first */
        if (t->nodes[n].joint >= 0) {
            cost_count(L, COST_BACKSUB);
            dca_node_backsub(L, n);
        }
    L->qdd = qdd;
    L->cforce = cforce;
    return 0;
}

/* No further Krylov step is worth a node pass: the last one moved the
 * iterate by at most level u ||q1|| (max norms; REFINE_LEVEL, REFINE_LEVEL_LATER
 * or LOADS_LEVEL above). Each step multiplies
 * the error by about the DCA's relative error level on that load where it
 * is below 1, so the next one would be that much smaller again: at the
 * rounding level, where the random trees' first step (4e2 .. 7e2 u) already
 * leaves them. */
static int resolved(double dmax, double qmax, double level)
{
    const double u = 1.1102230246251565e-16;
    return dmax <= level * u * qmax;
}

/* One cycle of right-preconditioned GMRES on M dq = r (R->r, norm rn), P =
 * the DCA correction solve, at most KRYLOV_MAX steps: the flexible variant
 * (Saad 1993), which keeps every z_j = P v_j, since P in floating point is
 * not exactly linear. Arnoldi on M P by Gram-Schmidt applied twice, Givens
 * rotations for the small least-squares problem. After each step the iterate
 * qdd + Z y is formed in R->q1 (y minimizing the estimated residual); the
 * cycle stops once a step moved it by a resolved amount (*done set; in a
 * cycle after the first, also its estimate below LATER_DROP rn), or the
 * Krylov space is exhausted. The first cycle's first step is the plain
 * correction, taken as it is when resolved; a later cycle's is not (its
 * residual is at the rounding floor, where P r is small whatever the error:
 * altmass 1e9 at 10^4 links, 2.6e2 u against an error of 1.2e-12). *est is
 * GMRES's estimate of the last iterate's residual (rn for the plain
 * correction), *sum the largest sum of |z_l y_l| over the joints in the last
 * iterate, relative to ||q1||_inf (0 for the plain correction). Returns the
 * steps taken (0: none usable). */
static int32_t gmres_cycle(aqs_linkage *L, double rn, int cycle, int *done, double *est, double *sum)
{
    struct refine *R = L->rf;
    const int32_t nv = L->nv;
    const size_t snv = (size_t)nv + 1;
    double (*h)[KRYLOV_MAX] = NULL, cs[KRYLOV_MAX], sn[KRYLOV_MAX], g[KRYLOV_MAX + 1], y[KRYLOV_MAX];
    int32_t i, j, l, k = 0;
    g[0] = rn;
    *est = rn;
    *sum = 0.0;
    for (j = 0; j < KRYLOV_MAX; j++) {
        /* the basis is allocated at the first step that needs it: no
         * arithmetic on its NULL pointer before that */
        double *vj = NULL, *w = NULL, *zj = NULL;
        double nw = 0.0, den, dmax = 0.0, qmax = 0.0, smax = 0.0;
        int rep;
        if (j > 0 && j + 1 > R->kcap && krylov_alloc(L, KRYLOV_MAX) != 0) break;
        if (j > 0) {
            vj = R->v + (size_t)j * snv;
            w = R->v + (size_t)(j + 1) * snv;
            zj = R->z + (size_t)j * snv;
        }
        if (j == 0) {
            /* the plain correction P r first: where it is resolved, it is
             * the answer (plain refinement, bit for bit, no Arnoldi step;
             * also when the basis cannot be allocated) */
            int loads = cycle == 0 && L->t.lf != NULL, rs = 0, bad = 0;
            for (;;) {
                if (correction(L, R->r, loads) != 0) {
                    bad = 1;
                    break;
                }
                dmax = qmax = 0.0;
                for (i = 0; i < nv; i++) {
                    R->q1[i] = L->qdd[i] + R->dq[i];
                    dmax = fmax(dmax, fabs(R->dq[i]));
                    qmax = fmax(qmax, fabs(R->q1[i]));
                }
                rs = cycle == 0 && resolved(dmax, qmax, loads ? LOADS_LEVEL : REFINE_LEVEL);
                if (rs || !loads) break;
                loads = 0; /* the loads-only correction not resolved: the full one instead */
            }
            if (bad) break;
            if (rs || krylov_alloc(L, KRYLOV_FIRST) != 0) {
                *done = 1;
                return 1;
            }
            dmax = qmax = 0.0;
            h = R->h; /* allocated now, with the basis */
            vj = R->v;
            w = R->v + snv;
            zj = R->z;
            for (i = 0; i < nv; i++) {
                vj[i] = R->r[i] / rn;
                zj[i] = R->dq[i] / rn;
            }
        } else {
            if (correction(L, vj, 0) != 0) break;
            memcpy(zj, R->dq, sizeof(double) * (size_t)nv);
        }
        residual_mass_mul(L, zj, w);
        for (l = 0; l <= j; l++) h[l][j] = 0.0;
        for (rep = 0; rep < 2; rep++) /* Gram-Schmidt, twice */
            for (l = 0; l <= j; l++) {
                const double *vl = R->v + (size_t)l * snv;
                double d = 0.0;
                for (i = 0; i < nv; i++) d += vl[i] * w[i];
                for (i = 0; i < nv; i++) w[i] -= d * vl[i];
                h[l][j] += d;
            }
        for (i = 0; i < nv; i++) nw += w[i] * w[i];
        nw = sqrt(nw);
        if (!isfinite(nw)) break;
        h[j + 1][j] = nw;
        if (nw > 0.0)
            for (i = 0; i < nv; i++) w[i] /= nw;
        for (l = 0; l < j; l++) { /* the previous rotations */
            const double a = h[l][j], b = h[l + 1][j];
            h[l][j] = cs[l] * a + sn[l] * b;
            h[l + 1][j] = -sn[l] * a + cs[l] * b;
        }
        den = hypot(h[j][j], h[j + 1][j]);
        if (!(den > 0.0) || !isfinite(den)) break;
        cs[j] = h[j][j] / den;
        sn[j] = h[j + 1][j] / den;
        h[j][j] = den;
        h[j + 1][j] = 0.0;
        g[j + 1] = -sn[j] * g[j];
        g[j] = cs[j] * g[j];
        for (l = j; l >= 0; l--) { /* y = H^-1 g, H upper triangular */
            double s = g[l];
            for (i = l + 1; i <= j; i++) s -= h[l][i] * y[i];
            y[l] = s / h[l][l];
        }
        for (i = 0; i < nv; i++) { /* q1 = qdd + Z y, and how far it moved */
            double d = 0.0, sa = 0.0;
            for (l = 0; l <= j; l++) {
                const double t = R->z[(size_t)l * snv + i] * y[l];
                d += t;
                sa += fabs(t);
            }
            smax = fmax(smax, sa);
            dmax = fmax(dmax, fabs(d - (j ? R->q1[i] - L->qdd[i] : 0.0)));
            R->q1[i] = L->qdd[i] + d;
            qmax = fmax(qmax, fabs(R->q1[i]));
        }
        k = j + 1;
        *est = fabs(g[j + 1]);
        *sum = qmax > 0.0 ? smax / qmax : 0.0;
        if ((resolved(dmax, qmax, j || cycle ? REFINE_LEVEL_LATER : REFINE_LEVEL) &&
             (cycle == 0 || *est <= LATER_DROP * rn)) ||
            nw == 0.0) { /* nw = 0: the exact solution is in the space */
            *done = 1;
            break;
        }
    }
    return k;
}

/* The residual's rounding floor at q (see FLOOR_FACTOR): one product by M
 * (R->dq and R->df as scratch; df holds 6 njoints >= nv). */
static double rounding_floor(aqs_linkage *L, const double *q)
{
    struct refine *R = L->rf;
    const double u = 1.1102230246251565e-16;
    uint32_t seed = 12345u;
    double f = 0.0;
    int32_t i;
    for (i = 0; i < L->nv; i++) {
        seed = seed * 1664525u + 1013904223u;
        R->dq[i] = (seed >> 31 ? u : -u) * fabs(q[i]);
    }
    residual_mass_mul(L, R->dq, R->df);
    for (i = 0; i < L->nv; i++) f += R->df[i] * R->df[i];
    return sqrt(f);
}

/* The inverse dynamics' joint forces of the refined accelerations carry
 * their error amplified: f_j sums I_i a_i over the subtree, a_i sums S qdd_k
 * over the path, and where the accelerations are large and cancel in a_i (a
 * long chain falling) an error of u |qdd| per joint becomes u |M qdd| in the
 * forces (2,000-link chain under gravity: 1.3e-7 of the largest, the
 * back-substitution's forces 2.9e-16). Their error estimated as the forces
 * of qdd perturbed by d_i = +-u |qdd_i| (signs as in rounding_floor), max
 * norm relative to the largest joint force in L->cforce (the
 * back-substitution's, refined); R->dq and R->df are scratch. */
static double id_force_error(aqs_linkage *L)
{
    struct refine *R = L->rf;
    const aba_state *a = &L->aba;
    double fm = 0.0, em = 0.0;
    int32_t k, i;
    (void)rounding_floor(L, L->qdd);
    residual_forces(L, R->df);
    for (k = 0; k < L->m.ne; k++) {
        const double *f = L->cforce + 6 * (size_t)a->joint[k].joint, *e = R->df + 6 * (size_t)a->joint[k].joint;
        for (i = 0; i < 6; i++) {
            fm = fmax(fm, fabs(f[i]));
            em = fmax(em, fabs(e[i]));
        }
    }
    return fm > 0.0 ? em / fm : (em > 0.0 ? INFINITY : 0.0);
}

/* The joint forces by the bodies' accelerations, as the articulated-body
 * refinement forms them (src/solve/abarefine.c), where the
 * back-substitution's do not balance the bodies. The bodies' spatial
 * accelerations a_c (relative to a world that moves with -g, so near a free
 * fall they are small) are the state refined, not recomputed from qdd: a_c
 * from qdd sums X a_p + S qdd along the path, and a free joint's qdd near g
 * leaves u |g| in every body's a_c, u m |g| in the forces, however accurate
 * qdd is. Each correction dq = DCA^-1(Q - ID(a_c)) moves a_c by dq's
 * accelerations from rest and is kept when it lowers the residual; qdd
 * stays as GMRES left it (adding dq to it would add back the rounding of
 * a_c(qdd) that dq removes). The refined a_c is trusted when the first
 * correction lowered the residual by at least STATE_CONTRACT (the DCA solves
 * that residual well: alternating masses 1e9 apart lower it 1.7x, 2.7x,
 * and the balance below would then judge good forces by poor
 * accelerations).
 * The balance (residual_balance: some body's f_c - sum X^T f_child -
 * (I_c a_c - f_ext,c)) is measured against min(the largest sum of a body's
 * terms with its weight, STATE_FORCE_SCALE x the largest joint force), as
 * the articulated-body solve's check measures its own (src/solve/aba.c):
 * first at a_c(qdd), where below STATE_BALANCE u nothing is done (the
 * molecule of 5,000 joints under gravity: 1.9 u; straight, tilted, oblique
 * chains at most 3.3 u; floating mixed-mass trees 42 .. 4.3e4 u), then at
 * the refined a_c: above STATE_BALANCE u the forces become ID(a_c)'s.
 * Measured (twelve random floating trees of tests/support/randtree.c,
 * masses over 1e6 apart, gravity tilted off the axes, against __float128):
 * where the back-substitution's forces are 2.0e-14 .. 1.6e-11 of the
 * largest off their balance at the refined a_c is 46 .. 4.3e4 u, and
 * ID(a_c)'s forces are 3.0e-16 .. 2.6e-15 off; where they are right it is
 * 0.57 .. 16.5 u (either set is right there); on the near-singular chain of 1,000 links with a tip force
 * (1.5e3 u at a_c(qdd)) 0.46 u, where ID(a_c)'s forces, summed inward over
 * the chain, would be the worse ones (4.4e-14 against 7.7e-16). The DCA's
 * own refinement (src/solve/arefine.c) does not reach it: on the worst tree
 * its corrections moved the forces by 8.3e4 u, then 1.5e4 u, and its
 * residual stopped decreasing (not converged: not kept). Returns the
 * corrections kept when their forces are taken (L->cforce refined), -1 when
 * the back-substitution's forces balance at the refined a_c, 0 when it did
 * not run or its a_c is not trusted (L->cforce as it was in both). *bs_err:
 * the back-substitution's forces' balance at the a_c of the refined joint
 * accelerations over the largest joint force (their error, relative, as far
 * as the balance tells it), INFINITY where it was not formed. Between
 * save_loads(L, 0) and (L, 1).
 * The state and its residual are in double-double (src/solve/residual.c,
 * residual_dd_*, as the articulated-body refinement has them), the
 * corrections in double: in double the residual's own rounding, u |I_c a_c|
 * of a heavy body, was the floor of the forces (a planar chain with 1e6 kg
 * links held by 1 kg ones, in millimetres: 1.9e-13 of the largest force,
 * the double-double state 7.0e-17). After a kept correction it stops where
 * the next one would move the forces by less than u/8 (residual_forces_settled): the
 * residual contracts by 1e-6 .. 1e-7 a correction where the DCA solves it
 * well, so one correction is the rule (a double-double pass is about 13x a
 * double one with Dekker's product, docs/bench.md). */
static int32_t state_forces(aqs_linkage *L, double *bs_err)
{
    struct refine *R = L->rf;
    aba_state *a = &L->aba;
    const double lim = STATE_BALANCE * 1.1102230246251565e-16, il = L->m.length > 0.0 ? 1.0 / L->m.length : 1.0;
    const size_t n6 = 6 * (size_t)L->m.ne;
    double rn, fm = 0.0, *tmp, bal, scale;
    int32_t kept = 0, it, k;
    size_t i;
    int converged = 0, settled;
    for (k = 0; k < L->m.ne; k++) { /* the largest joint force, as residual_balance weighs it */
        const double *c = L->cforce + 6 * (size_t)a->joint[k].joint;
        fm = fmax(fm, (fabs(c[0]) + fabs(c[1]) + fabs(c[2])) * il + fabs(c[3]) + fabs(c[4]) + fabs(c[5]));
    }
    residual_accelerations(L, L->qdd);
    bal = residual_balance(L, L->cforce, R->acc, &scale); /* at a_c(qdd) */
    *bs_err = fm > 0.0 && bal == bal ? bal / fm : INFINITY;
    if (!(bal > lim * fmin(scale, STATE_FORCE_SCALE * fm))) return 0;
    residual_dd_accelerations(L, L->qdd, R->sacc);
    rn = residual_dd_eval(L, R->sacc, R->sfw, R->r, R->fcur);
    if (!isfinite(rn) || !(rn > 0.0)) return 0;
    for (it = 0; it < STATE_CORRECTIONS * L->refine_max && rn > 0.0; it++) {
        double rn1;
        if (correction(L, R->r, 0) != 0) break;
        memcpy(R->sacc0, R->sacc, n6 * sizeof(ddouble));
        residual_dd_acc_add(L, R->dq, R->sacc);
        rn1 = residual_dd_eval(L, R->sacc, R->sfw, R->r2, R->ftry);
        if (!(rn1 < rn)) { /* at the residual's floor */
            memcpy(R->sacc, R->sacc0, n6 * sizeof(ddouble));
            break;
        }
        if (it == 0) converged = rn1 * STATE_CONTRACT <= rn;
        settled = residual_forces_settled(R->ftry, R->fcur, n6, rn1 / rn);
        tmp = R->r, R->r = R->r2, R->r2 = tmp;
        tmp = R->fcur, R->fcur = R->ftry, R->ftry = tmp;
        rn = rn1;
        kept++;
        if (settled) break;
    }
    if (!converged) return 0;
    for (i = 0; i < n6; i++) a->node[i / 6].v.s.acc[i % 6] = dd_to_double(R->sacc[i]);
    bal = residual_balance(L, L->cforce, R->acc, &scale);
    if (!(bal > lim * fmin(scale, STATE_FORCE_SCALE * fm))) return -1;
    for (i = 0; i < n6; i++) L->cforce[6 * (size_t)a->joint[i / 6].joint + i % 6] = R->fcur[i];
    if (L->m.nwelded > 0) aba_welded_forces(L);
    return kept;
}

/* GMRES's true residual: residual_eval's, or on a linkage with a heavy child
 * (model.heavy_ratio above AQS_HEAVY_CHILD_ABA) the same r formed in
 * double-double and rounded once (src/solve/residual.c, residual_dd_*; the
 * articulated-body refinement's): in double its floor, u times a heavy body's
 * terms, hides a light link's error. Returns ||r||_2. */
static double true_residual(aqs_linkage *L, const double *q, double *r)
{
    if (!(L->m.heavy_ratio > AQS_HEAVY_CHILD_ABA)) return residual_eval(L, q, r);
    return residual_dd_norm(L, q, L->rf->sacc, L->rf->sfw, r);
}

void refine_exact(aqs_linkage *L)
{
    struct refine *R;
    double rn, *tmp, rfloor = -1.0;
    int32_t cycle, nv = L->nv, kept = 0, akept = 0, skept = 0, i;
    double bs_err = INFINITY;
    int done = 0, frefined = 0;
    L->s.refined = 0;
    if (L->t.nnodes == 0 || L->m.ne == 0 || L->refine_max <= 0) return;
    if (refine_alloc(L) != 0) return; /* out of memory: the answer as it is */
    R = L->rf;
    /* the joint forces (and the accelerations with them) by the DCA's own
     * residual first, kept only if that refinement converged (R->df, not used
     * yet, holds the unrefined forces meanwhile): see FORCES above */
    memcpy(R->q0, L->qdd, sizeof(double) * (size_t)nv);
    if (L->refine_forces) {
        int conv = 0;
        memcpy(R->df, L->cforce, 6 * sizeof(double) * (size_t)L->njoints);
        akept = arefine_solve(L, &conv);
        if (akept > 0 && !conv) {
            memcpy(L->qdd, R->q0, sizeof(double) * (size_t)nv);
            memcpy(L->cforce, R->df, 6 * sizeof(double) * (size_t)L->njoints);
            akept = 0;
        } else if (akept > 0) {
            frefined = 1;
            if (L->m.nwelded > 0) aba_welded_forces(L);
        }
    }
    L->s.refined = akept;
    residual_poses(L);
    rn = true_residual(L, L->qdd, R->r);
    if (!isfinite(rn) || rn == 0.0) return;
    save_loads(L, 0);
    for (cycle = 0; cycle < L->refine_max && !done; cycle++) {
        double rn1, est, sum;
        int at_floor = 0;
        const int32_t k = gmres_cycle(L, rn, cycle, &done, &est, &sum);
        if (k == 0) break;
        rn1 = true_residual(L, R->q1, R->r2); /* the true residual */
        if (!isfinite(rn1)) break; /* a non-finite candidate's residual is not finite */
        if (k > 1 && done && !(rn1 < rn) && est <= LATER_DROP * rn) {
            /* a converged Krylov cycle that did not lower the residual: kept
             * only where both residuals are at the rounding floor */
            if (rfloor < 0.0) rfloor = rounding_floor(L, R->q1);
            at_floor = rn <= FLOOR_FACTOR * rfloor && rn1 <= FLOOR_FACTOR * rfloor;
        }
        /* kept only when the residual went down, or it cannot tell (above) */
        if (!(rn1 < rn || at_floor)) break;
        /* a Krylov cycle whose true residual is far above its estimate lost
         * the Arnoldi relation: restart from the true residual, if its
         * iterate cancelled enough for that to matter (RESTART_SUM) */
        if (k > 1 && !at_floor && rn1 > RESTART_GAP * est && sum > RESTART_SUM * 1.1102230246251565e-16) done = 0;
        memcpy(L->qdd, R->q1, sizeof(double) * (size_t)nv);
        tmp = R->r, R->r = R->r2, R->r2 = tmp;
        rn = rn1;
        kept += k;
        if (rn == 0.0) break;
    }
    if (kept) skept = state_forces(L, &bs_err);
    save_loads(L, 1);
    if (kept && skept == 0) {
        /* the inverse dynamics' joint forces of the refined accelerations
         * where their estimated error is at the rounding level, or below the
         * unrefined forces' when those were not refined (estimated by how
         * far the accelerations moved, and by how well those forces balance
         * the bodies at the refined accelerations: an alternating chain of
         * 1 and 1e9 kg under gravity out of its plane, whose accelerations
         * moved by 3.3e-9, kept forces 5.0e-15 off that balance to 7.6e-15,
         * where the inverse dynamics' are 9.0e-13 off), and in the
         * inverse-inertia form (FORCES above) */
        int use_id = L->dca_form != AQS_DCA_FORM_SQRT;
        if (!use_id) {
            const double e_id = id_force_error(L);
            double d = 0.0, m = 0.0;
            for (i = 0; i < nv; i++) {
                d = fmax(d, fabs(L->qdd[i] - R->q0[i]));
                m = fmax(m, fabs(L->qdd[i]));
            }
            use_id = e_id <= ID_FORCE_LEVEL * 1.1102230246251565e-16 ||
                     (!frefined && e_id <= (m > 0.0 ? d / m : 0.0) && e_id < bs_err);
        }
        if (use_id) {
            (void)residual_eval(L, L->qdd, R->r2);
            residual_forces(L, L->cforce);
            if (L->m.nwelded > 0) aba_welded_forces(L);
        }
    }
    L->s.refined = akept + kept + (skept > 0 ? skept : 0);
    if (L->m.heavy_ratio > AQS_HEAVY_CHILD_ABA && !L->handover) {
        /* corrections by the articulated-body factors (aba_polish; docs/math.md
         * 13a): the answer as it is where those factors cannot make them.
         * Corrected accelerations are kept where their residual is at most
         * the DCA's or at 16 rounding floors (there a lower residual does not
         * mean a smaller error: 0.22 against 1.2, floor 2.7, where the DCA
         * was 1.2e-13 off and the corrected answer 1.5e-16) */
        int32_t pk;
        const double level = fmax(rn, FLOOR_FACTOR * rounding_floor(L, L->qdd));
        memcpy(R->q0, L->qdd, sizeof(double) * (size_t)nv);
        memcpy(R->df, L->cforce, 6 * sizeof(double) * (size_t)L->njoints);
        pk = aba_polish(L, R->q0, level);
        if (pk < 0) {
            memcpy(L->qdd, R->q0, sizeof(double) * (size_t)nv);
            memcpy(L->cforce, R->df, 6 * sizeof(double) * (size_t)L->njoints);
        } else {
            L->s.refined += pk;
        }
    }
}

