/* test_worldbound.c -- the world-space measures (AQS_METRIC_ABS_WORLD,
 * AQS_METRIC_REL_WORLD; docs/math.md §10b): the body accelerations of the
 * reference against finite differences of the body poses; the certified
 * bound against a twin exact solve on random trees, hard cases and
 * trajectories with the prediction on and off; the lower bound of the
 * relative form; the lazily updated spheres against a full recomputation
 * and against the bodies' world positions; the API. */
#include "randtree.h"
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "joint.h"
#include "scenes.h"
#include "linkage.h"
#include "frames.h"
#include "worldbound.h"

/* ------------------------------------------------------------ generators */


/* ------------------------------------------------------------ reference */

/* World centre of mass of every body (3 each) through the public pose API
 * (row i = x y z w qx qy qz) and the test's own quaternion formula. */
static void com_world(aqs_linkage *L, double *out, double *R9)
{
    double *P = malloc(sizeof(double) * 7 * (size_t)L->nbodies);
    int32_t b;
    assert_int_equal(aqs_linkage_get_body_poses_world(L, P, 7 * (size_t)L->nbodies), AQS_OK);
    for (b = 0; b < L->nbodies; b++) {
        double R[9], c[3];
        int i;
        test_quat_matrix(P + 7 * b + 3, R);
        for (i = 0; i < 3; i++)
            c[i] = R[3 * i] * L->bodies[b].com[0] + R[3 * i + 1] * L->bodies[b].com[1] +
                   R[3 * i + 2] * L->bodies[b].com[2];
        for (i = 0; i < 3; i++) out[3 * b + i] = P[7 * b + i] + c[i];
        if (R9) memcpy(R9 + 9 * b, R, sizeof R);
    }
    free(P);
}

static double ell_of(const aqs_linkage *L, int32_t b)
{
    const body_def *bd = &L->bodies[b];
    double tr = bd->inertia[0] + bd->inertia[4] + bd->inertia[8];
    return bd->mass > 0 && tr > 0 ? sqrt(tr / (2 * bd->mass)) : 0.0;
}

/* Linear acceleration of every body's centre of mass and its angular
 * acceleration (world frame, 3 + 3 per body) for joint accelerations qdd
 * at zero velocity, by the forward recursion over the bodies (parents
 * first): alpha_c = alpha_p + R_c S_ang qdd, the acceleration of c's origin
 * a_c = a_p + alpha_p x (o_c - o_p) + R_c S_lin qdd, and at the centre of
 * mass a_c + alpha_c x (com_c - o_c). */
static void body_accels(aqs_linkage *L, const double *qdd, double *lin, double *ang)
{
    int32_t nb = L->nbodies, k, b;
    double *com = malloc(sizeof(double) * 3 * (size_t)nb), *R = malloc(sizeof(double) * 9 * (size_t)nb);
    double *org = malloc(sizeof(double) * 7 * (size_t)nb), *ao = malloc(sizeof(double) * 3 * (size_t)nb);
    com_world(L, com, R);
    assert_int_equal(aqs_linkage_get_body_poses_world(L, org, 7 * (size_t)nb), AQS_OK);
    for (k = 0; k < nb; k++) {
        int32_t c = L->m.order[k], i;
        const joint_def *jd = &L->joints[L->m.parent_joint[c]];
        double a[3] = {0, 0, 0}, w[3] = {0, 0, 0};
        if (jd->parent != AQS_WORLD) {
            int32_t p = jd->parent;
            double r[3];
            for (i = 0; i < 3; i++) r[i] = org[7 * c + i] - org[7 * p + i];
            for (i = 0; i < 3; i++) w[i] = ang[3 * p + i];
            a[0] = ao[3 * p] + w[1] * r[2] - w[2] * r[1];
            a[1] = ao[3 * p + 1] + w[2] * r[0] - w[0] * r[2];
            a[2] = ao[3 * p + 2] + w[0] * r[1] - w[1] * r[0];
        }
        if (jd->type != AQS_JOINT_FIXED) {
            double S[36] = {0}, sa[3] = {0, 0, 0}, sl[3] = {0, 0, 0};
            const double *Rc = R + 9 * c;
            int d = joint_nv(jd->type), kk;
            joint_subspace(jd, L->q + jd->qoff, S);
            for (i = 0; i < 3; i++)
                for (kk = 0; kk < d; kk++) {
                    sa[i] += S[i * d + kk] * qdd[jd->voff + kk];
                    sl[i] += S[(i + 3) * d + kk] * qdd[jd->voff + kk];
                }
            for (i = 0; i < 3; i++) {
                w[i] += Rc[3 * i] * sa[0] + Rc[3 * i + 1] * sa[1] + Rc[3 * i + 2] * sa[2];
                a[i] += Rc[3 * i] * sl[0] + Rc[3 * i + 1] * sl[1] + Rc[3 * i + 2] * sl[2];
            }
        }
        memcpy(ang + 3 * c, w, sizeof w);
        memcpy(ao + 3 * c, a, sizeof a);
    }
    for (b = 0; b < nb; b++) {
        const double *w = ang + 3 * b;
        double r[3];
        int i;
        for (i = 0; i < 3; i++) r[i] = com[3 * b + i] - org[7 * b + i];
        lin[3 * b] = ao[3 * b] + w[1] * r[2] - w[2] * r[1];
        lin[3 * b + 1] = ao[3 * b + 1] + w[2] * r[0] - w[0] * r[2];
        lin[3 * b + 2] = ao[3 * b + 2] + w[0] * r[1] - w[1] * r[0];
    }
    free(com);
    free(R);
    free(org);
    free(ao);
}

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* max_b e_b of the accelerations qdd, e_b = |a_b| + ell_b |alpha_b|. */
static double world_measure(aqs_linkage *L, const double *qdd)
{
    int32_t nb = L->nbodies, b;
    double *lin = malloc(sizeof(double) * 3 * (size_t)nb), *ang = malloc(sizeof(double) * 3 * (size_t)nb);
    double m = 0;
    body_accels(L, qdd, lin, ang);
    for (b = 0; b < nb; b++) m = fmax(m, norm3(lin + 3 * b) + ell_of(L, b) * norm3(ang + 3 * b));
    free(lin);
    free(ang);
    return m;
}

/* The true acceleration of a body includes gravity's share only through
 * qdd (a free body in free fall reads R^T g): the reference's body
 * accelerations are those of qdd, checked against finite differences. */
static void test_body_accel_fd(void **state)
{
    uint64_t rng = 4242;
    int c;
    double worst = 0;
    (void)state;
    for (c = 0; c < 20; c++) {
        test_tree_spec sp = {12 + c, 0, 0, 0, 1, 3.0, c % 3 == 0, 0.8, 1, 1};
        aqs_linkage *L = test_random_tree(&rng, &sp);
        int32_t nb = L->nbodies, nq = L->nq, i;
        double *q = malloc(sizeof(double) * (size_t)nq), *qp = malloc(sizeof(double) * (size_t)nq);
        double *d = malloc(sizeof(double) * (size_t)nq), *lin = malloc(sizeof(double) * 3 * (size_t)nb);
        double *ang = malloc(sizeof(double) * 3 * (size_t)nb), *cp = malloc(sizeof(double) * 3 * (size_t)nb);
        double *cm = malloc(sizeof(double) * 3 * (size_t)nb), *Rp = malloc(sizeof(double) * 9 * (size_t)nb);
        double *Rm = malloc(sizeof(double) * 9 * (size_t)nb), h = 1e-5, scale = 0;
        int32_t b;
        assert_int_equal(nq, L->nv); /* revolute and prismatic only: q and qdd alike */
        assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
        for (i = 0; i < nq; i++) d[i] = test_uniform(&rng, -1, 1);
        body_accels(L, d, lin, ang);
        for (i = 0; i < nq; i++) qp[i] = q[i] + h * d[i];
        assert_int_equal(aqs_linkage_set_positions(L, qp, (size_t)nq), AQS_OK);
        com_world(L, cp, Rp);
        for (i = 0; i < nq; i++) qp[i] = q[i] - h * d[i];
        assert_int_equal(aqs_linkage_set_positions(L, qp, (size_t)nq), AQS_OK);
        com_world(L, cm, Rm);
        for (b = 0; b < nb; b++) scale = fmax(scale, norm3(lin + 3 * b));
        for (b = 0; b < nb; b++) {
            double fd[3], M[9], wv[3];
            int k;
            for (k = 0; k < 3; k++) fd[k] = (cp[3 * b + k] - cm[3 * b + k]) / (2 * h) - lin[3 * b + k];
            worst = fmax(worst, norm3(fd) / scale);
            /* R+ R-^T = exp(2h skew(w)): w from its skew part */
            for (k = 0; k < 9; k++) {
                int r = k / 3, s = k % 3, t;
                M[k] = 0;
                for (t = 0; t < 3; t++) M[k] += Rp[9 * b + 3 * r + t] * Rm[9 * b + 3 * s + t];
            }
            wv[0] = (M[7] - M[5]) / (4 * h) - ang[3 * b];
            wv[1] = (M[2] - M[6]) / (4 * h) - ang[3 * b + 1];
            wv[2] = (M[3] - M[1]) / (4 * h) - ang[3 * b + 2];
            worst = fmax(worst, norm3(wv) / (norm3(ang + 3 * b) + 1));
        }
        free(q), free(qp), free(d), free(lin), free(ang), free(cp), free(cm), free(Rp), free(Rm);
        aqs_linkage_destroy(L);
    }
    print_message("body accelerations against central differences: worst %.3g\n", worst);
    assert_true(worst < 1e-6);
}

/* ------------------------------------------------------------ the bound */

typedef struct {
    long checks, violations, lower_checks;
    double worst_ratio, worst_lower;
    long certified;    /* solves with certified = 1 (their error_bound + rounding_bound checked) */
    double worst_cert; /* the largest true / (error_bound + rounding_bound) over them */
} tally;

/* L solved adaptively at eps (metric) against X (exact, same positions):
 * true <= bound (1 + 1e-9) + floor, bound <= eps unless capped, and the
 * lower bound <= the true largest body measure. floor: the rounding level
 * of the reference, relative to its largest body measure. */
static void check_one(aqs_linkage *L, aqs_linkage *X, int metric, double eps, double floor_rel, tally *t)
{
    int32_t nv = L->nv, i;
    double *exact = malloc(sizeof(double) * (size_t)(nv + 1)), *approx = malloc(sizeof(double) * (size_t)(nv + 1));
    double *diff = malloc(sizeof(double) * (size_t)(nv + 1)), den, err, fl;
    aqs_solve_stats st;
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_get_accelerations(X, exact, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, approx, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_int_equal(st.metric, metric);
    for (i = 0; i < nv; i++) diff[i] = exact[i] - approx[i];
    den = world_measure(X, exact); /* X is at the positions of L's solve (L may have stepped since) */
    err = world_measure(X, diff);
    fl = floor_rel * den;
    if (metric == AQS_METRIC_REL_WORLD) {
        err = den > 0 ? err / den : 0;
        fl = floor_rel;
        /* the lower bound of the denominator */
        t->lower_checks++;
        if (!(L->wb->lower <= den * (1 + 1e-9) + floor_rel * den)) {
            t->violations++;
            print_message("lower bound %.17g above the largest body measure %.17g\n", L->wb->lower, den);
        }
        if (den > 0) t->worst_lower = fmax(t->worst_lower, L->wb->lower / den);
    }
    t->checks++;
    if (!(st.capped || st.error_bound <= eps) || !(err <= st.error_bound * (1 + 1e-9) + fl)) {
        t->violations++;
        print_message("violation: metric %d eps %g bound %.17g true %.17g floor %.3g NE %d\n", metric, eps,
                      st.error_bound, err, fl, st.computed_joints);
    }
    if (st.error_bound > 0) t->worst_ratio = fmax(t->worst_ratio, err / st.error_bound);
    /* the rounding estimate (docs/math.md §10b, "Rounding"): certified => true <=
     * error_bound + rounding_bound (plus the twin's own rounding, floor); the
     * denominator it uses is below the lower bound */
    if (metric == AQS_METRIC_REL_WORLD && !(L->wb->lower_r <= L->wb->lower)) {
        t->violations++;
        print_message("lower_r %.17g above lower %.17g\n", L->wb->lower_r, L->wb->lower);
    }
    if (st.certified) {
        const double tot = st.error_bound + st.rounding_bound;
        t->certified++;
        if (!(isfinite(st.rounding_bound) && st.rounding_bound <= eps && err <= tot * (1 + 1e-9) + fl)) {
            t->violations++;
            print_message("certified violation: metric %d eps %g bound %.17g rounding %.3g true %.17g floor %.3g\n",
                          metric, eps, st.error_bound, st.rounding_bound, err, fl);
        }
        if (tot > 0) t->worst_cert = fmax(t->worst_cert, err / tot);
    }
    free(exact);
    free(approx);
    free(diff);
}

/* A twin's solves give the exact DCA back-substitution without the exact
 * solve's refinement (docs/math.md §13a), what the adaptive solves' bound is
 * about: every joint through the adaptive path (eps = 0, a cap of every joint). */
static void unrefined_twin(aqs_linkage *X)
{
    assert_int_equal(aqs_linkage_set_max_computed(X, X->njoints + 1), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_refinement(X, 0), AQS_OK);
}

static void twin_positions(aqs_linkage *L, aqs_linkage *X)
{
    double *q = malloc(sizeof(double) * (size_t)(L->nq + 1));
    assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)L->nq), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(X, q, (size_t)L->nq), AQS_OK);
    free(q);
}

/* Both world measures at eps = 2^0, 2^-2, ..., 2^-20 on L, X the twin. */
static void check_linkage(aqs_linkage *L, aqs_linkage *X, double floor_rel, tally *t)
{
    int metric, k;
    twin_positions(L, X);
    assert_int_equal(aqs_linkage_solve(X), AQS_OK);
    /* the bound is about skipping, against the unrefined twin: a solve of L
     * computing every joint stays unrefined too (tests/test_refine.c) */
    assert_int_equal(aqs_linkage_set_exact_refinement(L, 0), AQS_OK);
    for (metric = AQS_METRIC_ABS_WORLD; metric <= AQS_METRIC_REL_WORLD; metric++)
        for (k = 0; k <= 20; k += 2) {
            double eps = ldexp(1.0, -k);
            assert_int_equal(aqs_linkage_set_tolerance(L, metric, eps), AQS_OK);
            assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
            if (aqs_linkage_solve(L) != AQS_OK) fail_msg("solve: %s", aqs_linkage_last_error(L));
            check_one(L, X, metric, eps, floor_rel, t);
        }
}

static void twins(uint64_t *rng, const test_tree_spec *sp, aqs_linkage **L, aqs_linkage **X)
{
    uint64_t r0 = *rng;
    *L = test_random_tree(rng, sp);
    *rng = r0;
    *X = test_random_tree(rng, sp);
    unrefined_twin(*X);
}

static void test_bound_random(void **state)
{
    uint64_t rng = 2026;
    tally t = {0, 0, 0, 0, 0, 0, 0};
    int c;
    (void)state;
    for (c = 0; c < 200; c++) {
        test_tree_spec sp = {0};
        aqs_linkage *L, *X;
        sp.nbodies = 2 + (int32_t)test_uniform(&rng, 0, c % 5 == 0 ? 120 : 40);
        sp.floating = c % 3 == 0;
        sp.gravity = c % 2 == 0;
        sp.nforces = 1 + (int)test_uniform(&rng, 0, sp.nbodies < 60 ? sp.nbodies : 60);
        sp.revolute_only = c % 4 == 3;
        sp.chain = c % 4 == 1;
        sp.mass_spread = 3.0;
        sp.reach = c % 7 == 0 ? 5.0 : 0.8;
        sp.some_prismatic = sp.uniform_quat = 1;
        twins(&rng, &sp, &L, &X);
        check_linkage(L, X, 1e-12, &t);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
    print_message("world bound, random: %ld checks, %ld violations, worst true/bound %.9f, worst "
                  "lower/max %.4f; %ld certified, worst true/(bound + rounding) %.3g\n", t.checks, t.violations,
                  t.worst_ratio, t.worst_lower, t.certified, t.worst_cert);
    assert_int_equal(t.violations, 0);
    assert_true(t.checks == 200 * 2 * 11 && t.lower_checks == 200 * 11);
    /* benign trees: the rounding estimate certifies (4,399 of 4,400 when written) */
    assert_true(t.certified >= 4300);
    assert_true(t.worst_ratio > 0.0 && t.worst_ratio <= 1.0 + 1e-9);
}

/* A chain of n links along x (revolute about z, or about random axes),
 * masses over 10^decades, one load at the tip or gravity. */
static aqs_linkage *hard_chain(int32_t n, double decades, int random_axes, int gravity, uint64_t *rng)
{
    aqs_linkage *L;
    int32_t i;
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    for (i = 0; i < n; i++) {
        double m = pow(10.0, decades * (i % 2 ? 1 : 0) - decades / 2), com[3] = {0.5, 0, 0};
        double I[9] = {0.01 * m, 0, 0, 0, 0.09 * m, 0, 0, 0, 0.09 * m};
        double pos[3] = {i ? 1.0 : 0.0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
        assert_int_equal(aqs_body_add(L, m, com, I, NULL), AQS_OK);
        if (random_axes) {
            axis[0] = test_uniform(rng, -1, 1);
            axis[1] = test_uniform(rng, -1, 1);
            axis[2] = test_uniform(rng, -1, 1);
        }
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, i - 1, i, pos, quat, axis, NULL), AQS_OK);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    if (gravity) {
        const double g[3] = {0, -9.81, 0};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    } else {
        const double f[3] = {0, 1, 0}, p[3] = {1, 0, 0}, z[3] = {0, 0, 0};
        assert_int_equal(aqs_body_set_force(L, n - 1, f, p, z), AQS_OK);
    }
    return L;
}

/* A star: a heavy hub on a free joint with many light legs of 3 links. */
static aqs_linkage *hard_star(int32_t legs, double light)
{
    aqs_linkage *L;
    int32_t i, k, hub;
    const double z[3] = {0, 0, 0}, I1[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double q1[4] = {1, 0, 0, 0};
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_body_add(L, 10.0, z, I1, &hub), AQS_OK);
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FREE, AQS_WORLD, hub, z, q1, z, NULL), AQS_OK);
    for (i = 0; i < legs; i++) {
        int32_t parent = hub;
        double ang = 6.283185307179586 * i / legs;
        for (k = 0; k < 3; k++) {
            int32_t b;
            double com[3] = {0.25, 0, 0}, I[9] = {light * 0.01, 0, 0, 0, light * 0.02, 0, 0, 0, light * 0.02};
            double pos[3] = {k ? 0.5 : cos(ang), k ? 0 : sin(ang), 0}, axis[3] = {0, k % 2, 1 - k % 2};
            assert_int_equal(aqs_body_add(L, light, com, I, &b), AQS_OK);
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, parent, b, pos, q1, axis, NULL), AQS_OK);
            parent = b;
        }
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    {
        const double f[3] = {0, 0, 1}, p[3] = {0.5, 0, 0};
        assert_int_equal(aqs_body_set_force(L, L->nbodies - 1, f, p, z), AQS_OK);
        assert_int_equal(aqs_body_set_force(L, 1, f, p, z), AQS_OK);
    }
    return L;
}

static void test_bound_hard(void **state)
{
    uint64_t rng = 99, r0;
    tally t = {0, 0, 0, 0, 0, 0, 0};
    struct {
        int32_t n;
        double decades;
        int random_axes, gravity;
        double floor_rel;
    } chains[] = {
        {500, 0, 0, 0, 1e-12},  /* a long straight chain pulled at the tip: levers to 500 */
        {500, 0, 1, 1, 1e-12},  /* random axes under gravity */
        {200, 4, 1, 1, 1e-9},   /* masses over 4 decades (the DCA: ~1e-9, docs/math.md §13) */
        {200, 6, 0, 0, 1e-6},   /* 6 decades alternating (the DCA: 5e-7) */
    };
    size_t c;
    (void)state;
    for (c = 0; c < sizeof chains / sizeof chains[0]; c++) {
        aqs_linkage *L, *X;
        r0 = rng;
        L = hard_chain(chains[c].n, chains[c].decades, chains[c].random_axes, chains[c].gravity, &rng);
        rng = r0;
        X = hard_chain(chains[c].n, chains[c].decades, chains[c].random_axes, chains[c].gravity, &rng);
        {   /* a bent configuration */
            double *q = malloc(sizeof(double) * (size_t)L->nq);
            int32_t i;
            for (i = 0; i < L->nq; i++) q[i] = 0.3 * sin(0.7 * i);
            assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)L->nq), AQS_OK);
            free(q);
        }
        check_linkage(L, X, chains[c].floor_rel, &t);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
    {   /* a free hub with 40 legs 1e-4 as heavy */
        aqs_linkage *L = hard_star(40, 1e-4), *X = hard_star(40, 1e-4);
        check_linkage(L, X, 1e-9, &t);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
    print_message("world bound, hard cases: %ld checks, %ld violations, worst true/bound %.9f; %ld certified, "
                  "worst true/(bound + rounding) %.3g\n", t.checks, t.violations, t.worst_ratio, t.certified,
                  t.worst_cert);
    assert_int_equal(t.violations, 0);
    assert_true(t.checks == 5 * 2 * 11);
}

/* Trajectories: L (prediction on, the default) and O (off) step together;
 * before each step X, at the same positions, is solved exactly, and the
 * step's solve is checked against it. */
static void test_bound_trajectories(void **state)
{
    uint64_t rng = 31337;
    tally t = {0, 0, 0, 0, 0, 0, 0};
    long predicted = 0, ne_on = 0, ne_off = 0;
    int c;
    (void)state;
    for (c = 0; c < 8; c++) {
        int metric = AQS_METRIC_ABS_WORLD + c % 2, step;
        double eps = ldexp(1.0, -(4 + 2 * c)), margin = -1;
        test_tree_spec sp = {150 + 20 * c, c % 3 == 0, c % 2 == 0, 1 + c, c % 2 == 1, 3.0, c % 4 == 2, 0.8, 1, 1};
        uint64_t r0 = rng;
        aqs_linkage *L, *O, *X;
        L = test_random_tree(&rng, &sp);
        rng = r0;
        O = test_random_tree(&rng, &sp);
        rng = r0;
        X = test_random_tree(&rng, &sp);
        unrefined_twin(X);
        assert_int_equal(aqs_linkage_set_tolerance(L, metric, eps), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
        assert_int_equal(aqs_linkage_set_tolerance(O, metric, eps), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(O, 0), AQS_OK); /* the adaptive solver's bound under test */
        assert_int_equal(aqs_linkage_get_prediction(L, &margin), AQS_OK);
        assert_true(margin == AQS_PREDICTION_MARGIN);
        assert_int_equal(aqs_linkage_set_prediction(O, 0.0), AQS_OK);
        for (step = 0; step < 25; step++) {
            aqs_solve_stats s1, s2;
            twin_positions(L, X);
            assert_int_equal(aqs_linkage_solve(X), AQS_OK);
            if (aqs_linkage_step(L, 0.05) != AQS_OK) fail_msg("step: %s", aqs_linkage_last_error(L));
            check_one(L, X, metric, eps, 1e-12, &t);
            /* O at L's former positions: the same solve without prediction */
            twin_positions(X, O);
            if (aqs_linkage_step(O, 0.05) != AQS_OK) fail_msg("step: %s", aqs_linkage_last_error(O));
            check_one(O, X, metric, eps, 1e-12, &t);
            s1.size = s2.size = sizeof s1;
            assert_int_equal(aqs_linkage_get_stats(L, &s1), AQS_OK);
            assert_int_equal(aqs_linkage_get_stats(O, &s2), AQS_OK);
            assert_int_equal(s2.nodes_predicted, 0);
            predicted += s1.nodes_predicted;
            ne_on += s1.computed_joints;
            ne_off += s2.computed_joints;
        }
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(O);
        aqs_linkage_destroy(X);
    }
    print_message("world bound, trajectories: %ld checks, %ld violations, worst true/bound %.9f; "
                  "%ld nodes predicted; N_E %ld (prediction on) %ld (off); %ld certified, worst true/(bound + "
                  "rounding) %.3g\n",
                  t.checks, t.violations, t.worst_ratio, predicted, ne_on, ne_off, t.certified, t.worst_cert);
    assert_int_equal(t.violations, 0);
    assert_true(predicted > 0); /* the prediction was exercised */
    assert_true(ne_on >= ne_off); /* it only ever computes more */
    assert_true(t.certified >= 380); /* 400 of 400 when written */
}

/* The paper's scenes (bench/scenes.c) with the benchmark's kind of load: a
 * 1 N pull on one body (chain30: at the tip's far end), gravity off; the
 * bound at every eps and over a few steps of a trajectory. */
static aqs_linkage *scene(bench_scene_kind kind, int32_t size)
{
    aqs_linkage *L;
    int32_t body;
    const double f[3] = {0.3, 0.8, -0.52}, z[3] = {0, 0, 0}, tip[3] = {1, 0, 0};
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(bench_build_scene(L, kind, size), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    body = kind == BENCH_SCENE_CHAIN30 ? bench_chain30_tip_body()
           : kind == BENCH_SCENE_MILLIPEDE ? bench_millipede_leg_body(400, 9)
                                           : L->nbodies / 3;
    assert_int_equal(aqs_body_set_force(L, body, f, kind == BENCH_SCENE_CHAIN30 ? tip : z, z), AQS_OK);
    return L;
}

static void test_bound_scenes(void **state)
{
    static const struct {
        bench_scene_kind kind;
        int32_t size;
    } scenes[] = {{BENCH_SCENE_CHAIN30, 30}, {BENCH_SCENE_MOLECULE, 3000}, {BENCH_SCENE_MILLIPEDE, 0}};
    tally t = {0, 0, 0, 0, 0, 0, 0};
    size_t c;
    (void)state;
    for (c = 0; c < sizeof scenes / sizeof scenes[0]; c++) {
        aqs_linkage *L = scene(scenes[c].kind, scenes[c].size), *X = scene(scenes[c].kind, scenes[c].size);
        unrefined_twin(X);
        int step;
        check_linkage(L, X, 1e-12, &t);
        if (scenes[c].kind == BENCH_SCENE_MILLIPEDE) {
            /* a body lies inside at most one queued node: the legs' inside
             * bounds are not summed. 6,695 joints at 2^-5 with the sum; with
             * min(sum, max + beyond) 300 when the world was joined first and
             * 1,509 now that a world holding only a free joint is joined last
             * (src/model/assembly.c, for the floating base's accuracy): the
             * guard is 2,000 */
            aqs_solve_stats st;
            st.size = sizeof st;
            assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, ldexp(1.0, -5)), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
            print_message("millipede, rel_world 2^-5: %d joints computed\n", st.computed_joints);
            assert_true(st.computed_joints < 2000);
        }
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, ldexp(1.0, -15)), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
        for (step = 0; step < 6; step++) {
            twin_positions(L, X);
            assert_int_equal(aqs_linkage_solve(X), AQS_OK);
            if (aqs_linkage_step(L, 0.3) != AQS_OK) fail_msg("step: %s", aqs_linkage_last_error(L));
            check_one(L, X, AQS_METRIC_REL_WORLD, ldexp(1.0, -15), 1e-12, &t);
        }
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
    print_message("world bound, scenes: %ld checks, %ld violations, worst true/bound %.9f; %ld certified, "
                  "worst true/(bound + rounding) %.3g\n", t.checks, t.violations, t.worst_ratio, t.certified,
                  t.worst_cert);
    assert_int_equal(t.violations, 0);
    assert_true(t.checks == 3 * (2 * 11 + 6));
    assert_true(t.certified >= 75); /* 81 of 84 when written */
}

/* ------------------------------------------------------------ the spheres */

/* World pose of node n's frame: the frame of the leaf reached by A children. */
static void node_world(aqs_linkage *L, int32_t n, pose *P)
{
    while (L->t.nodes[n].joint >= 0) n = L->t.nodes[n].a;
    if (L->t.nodes[n].comp == L->m.ncomp) *P = L->t.world_frame; /* the world leaf's frame (frames.h) */
    else frames_comp_world(L, L->t.nodes[n].comp, P);
}

/* Every node's sphere (lazily updated over a trajectory) holds its bodies'
 * centres of mass and equals the one a full recomputation gives. */
static void test_spheres_lazy(void **state)
{
    uint64_t rng = 5150;
    int c;
    long checked = 0;
    (void)state;
    for (c = 0; c < 6; c++) {
        test_tree_spec sp = {60 + 30 * c, c % 3 == 0, 1, 3, c % 2, 3.0, c % 4 == 1, 0.8, 1, 1};
        uint64_t r0 = rng;
        aqs_linkage *L, *Y;
        int32_t step, n, b;
        double *com;
        L = test_random_tree(&rng, &sp);
        rng = r0;
        Y = test_random_tree(&rng, &sp);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_WORLD, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
        for (step = 0; step < 20; step++)
            if (aqs_linkage_step(L, 0.05) != AQS_OK) fail_msg("step: %s", aqs_linkage_last_error(L));
        assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* brings the tree up to date */
        twin_positions(L, Y);
        assert_int_equal(aqs_linkage_set_tolerance(Y, AQS_METRIC_ABS_WORLD, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(Y, 0), AQS_OK); /* the adaptive solver's bound under test */
        assert_int_equal(aqs_linkage_solve(Y), AQS_OK); /* a full update */
        com = malloc(sizeof(double) * 3 * (size_t)L->nbodies);
        com_world(L, com, NULL);
        for (n = 0; n < L->t.nnodes; n++) {
            const double *s = L->wb->sph + 4 * n, *y = Y->wb->sph + 4 * n;
            int k;
            for (k = 0; k < 4; k++) assert_true(fabs(s[k] - y[k]) <= 1e-9 * (1 + fabs(y[k])));
        }
        /* each body's centre of mass in the sphere of each node holding it */
        for (b = 0; b < L->nbodies; b++) {
            int32_t comp = L->m.comp_of_body[b];
            if (comp == L->m.ncomp) continue;
            for (n = L->t.leaf_of_comp[comp]; n >= 0; n = L->t.nodes[n].parent) {
                pose P;
                double cw[3], d[3];
                const double *s = L->wb->sph + 4 * n;
                node_world(L, n, &P);
                mat3_vec(P.R, s, cw);
                for (int k = 0; k < 3; k++) d[k] = com[3 * b + k] - cw[k] - P.p[k];
                assert_true(norm3(d) <= s[3] * (1 + 1e-9) + 1e-12);
                checked++;
            }
        }
        free(com);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(Y);
    }
    print_message("spheres: %ld (body, node) containments checked\n", checked);
    assert_true(checked > 1000);
}

/* ------------------------------------------------------------ path sums */

/* sigma^2 of a joint type's angular (ang = 1) or linear block: every joint
 * type's columns are orthonormal, so each block's largest singular value is
 * 1 where the block is not zero. */
static double sigma2_of(int32_t type, int ang)
{
    switch (type) {
    case AQS_JOINT_REVOLUTE:
    case AQS_JOINT_SPHERICAL:
    case AQS_JOINT_UNIVERSAL: return ang ? 1.0 : 0.0;
    case AQS_JOINT_PRISMATIC: return ang ? 0.0 : 1.0;
    case AQS_JOINT_CYLINDRICAL:
    case AQS_JOINT_PLANAR: return 1.0;
    default: return 0.0; /* free: not counted */
    }
}

/* The interior bound's path sums (docs/math.md §10b): for every node n,
 * sa2[n] (sl2[n]) is the largest sum of sigma_ang^2 (sigma_lin^2) over the
 * joints of n on the path from the world to one composite of n, found here
 * by walking every composite's path to the world. */
static void test_path_sums(void **state)
{
    uint64_t rng = 777;
    int c;
    long checked = 0;
    (void)state;
    for (c = 0; c < 12; c++) {
        test_tree_spec sp = {20 + 25 * c, c % 3 == 0, 1, 2, 0, 3.0, c % 4 == 1, 0.8, 1, 1};
        aqs_linkage *L = test_random_tree(&rng, &sp);
        const model *m;
        const tree *t;
        int32_t *parent_eff, *first, n, e, k;
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, 1e-3), AQS_OK);
        m = &L->m;
        t = &L->t;
        parent_eff = malloc(sizeof(int32_t) * (size_t)(m->ncomp + 1));
        first = malloc(sizeof(int32_t) * (size_t)t->nnodes);
        for (k = 0; k <= m->ncomp; k++) parent_eff[k] = -1;
        for (e = 0; e < m->ne; e++) parent_eff[m->eff_child[e]] = e;
        /* the lowest node index in n's subtree (post-order: the first leaf below) */
        for (n = 0; n < t->nnodes; n++)
            first[n] = t->nodes[n].joint < 0 ? n : first[t->nodes[n].a] < first[t->nodes[n].b] ? first[t->nodes[n].a]
                                                                                                 : first[t->nodes[n].b];
        for (n = 0; n < t->nnodes; n++) {
            double best[2] = {0, 0};
            int ang;
            if (t->nodes[n].joint < 0) continue;
            for (k = 0; k < m->ncomp; k++) {
                int32_t leaf = t->leaf_of_comp[k], cc = k;
                double sum[2] = {0, 0};
                if (leaf < first[n] || leaf > n) continue;
                while (parent_eff[cc] >= 0) {
                    int32_t pe = parent_eff[cc], nd = t->node_of_eff[pe];
                    if (nd >= first[n] && nd <= n)
                        for (ang = 0; ang < 2; ang++)
                            sum[ang] += sigma2_of(L->joints[m->eff_joint[pe]].type, ang);
                    cc = m->eff_parent[pe];
                }
                for (ang = 0; ang < 2; ang++) best[ang] = fmax(best[ang], sum[ang]);
            }
            assert_true(fabs(L->wb->sa2[n] - best[1]) <= 1e-9 * (1 + best[1]));
            assert_true(fabs(L->wb->sl2[n] - best[0]) <= 1e-9 * (1 + best[0]));
            checked++;
        }
        free(parent_eff);
        free(first);
        aqs_linkage_destroy(L);
    }
    print_message("path sums: %ld nodes checked\n", checked);
    assert_true(checked > 1000);
}

/* ------------------------------------------------------------ API */

static void test_api(void **state)
{
    uint64_t rng = 8;
    test_tree_spec sp = {40, 0, 1, 3, 0, 3.0, 0, 0.8, 1, 1};
    aqs_linkage *L = test_random_tree(&rng, &sp);
    aqs_solve_stats st;
    double b1;
    (void)state;
    assert_int_equal(aqs_linkage_set_tolerance(L, 6, 0.1), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "metric = 6");
    assert_int_equal(aqs_linkage_set_tolerance(L, -1, 0.1), AQS_EINVAL);
    assert_null(L->wb); /* nothing allocated by a refused call */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, 0.5), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_int_equal(st.metric, AQS_METRIC_REL_WORLD);
    assert_true(st.error_bound <= 0.5);
    b1 = st.error_bound;
    /* refine continues the same queue */
    assert_int_equal(aqs_linkage_refine(L, b1 / 8), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_true(st.error_bound <= b1 / 8);
    /* a cap reports the bound reached */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_WORLD, 1e-12), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
    assert_int_equal(aqs_linkage_set_max_computed(L, 3), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_true(st.capped == 1 && st.error_bound > 1e-12);
    aqs_linkage_destroy(L);
}

/* Out of memory in set_tolerance (the world data or the factors): nothing
 * changes, and a later call sets everything up (the spheres of every node
 * computed: the solve's bound equals a linkage that never failed). */
static void test_out_of_memory(void **state)
{
    long k, failures = 0;
    (void)state;
    for (k = 1; k <= 40; k++) {
        counting_state cs = {0, 0, 0, 0, 0};
        aqs_linkage *L = NULL, *R = test_new_linkage();
        aqs_linkage *both[2];
        aqs_solve_stats a, b;
        int32_t i, w;
        aqs_status st;
        assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
        both[0] = L;
        both[1] = R;
        for (w = 0; w < 2; w++) {
            const double f[3] = {0, 1, 0}, z[3] = {0, 0, 0};
            for (i = 0; i < 30; i++) {
                test_add_body(both[w], 1.0, 0.5, 0, 0, 0.05);
                test_add_joint(both[w], AQS_JOINT_REVOLUTE, i - 1, i, i ? 1.0 : 0.0, 0, 0, 0, 0.3, 1);
            }
            assert_int_equal(aqs_linkage_finalize(both[w]), AQS_OK);
            assert_int_equal(aqs_body_set_force(both[w], 29, f, z, z), AQS_OK);
        }
        cs.fail_at = cs.count + k;
        st = aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_WORLD, 1e-3);
        if (st == AQS_ENOMEM) {
            failures++;
            assert_null(L->wb);
            test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_set_tolerance");
        } else
            assert_int_equal(st, AQS_OK);
        cs.fail_at = 0;
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_WORLD, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* the adaptive solver's bound under test */
        assert_int_equal(aqs_linkage_set_tolerance(R, AQS_METRIC_ABS_WORLD, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(R, 0), AQS_OK); /* the adaptive solver's bound under test */
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_solve(R), AQS_OK);
        a.size = b.size = sizeof a;
        assert_int_equal(aqs_linkage_get_stats(L, &a), AQS_OK);
        assert_int_equal(aqs_linkage_get_stats(R, &b), AQS_OK);
        assert_true(a.error_bound == b.error_bound && a.computed_joints == b.computed_joints);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(R);
        assert_int_equal(cs.live, 0);
    }
    print_message("out of memory: %ld of 40 injected failures hit set_tolerance\n", failures);
    assert_true(failures >= 8); /* the world data's 8 blocks at least */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_body_accel_fd),   cmocka_unit_test(test_bound_random),
        cmocka_unit_test(test_bound_hard),      cmocka_unit_test(test_bound_trajectories),
        cmocka_unit_test(test_bound_scenes),
        cmocka_unit_test(test_spheres_lazy),    cmocka_unit_test(test_path_sums),
        cmocka_unit_test(test_api),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
