/* test_autopath.c -- the automatic path (aqs_linkage_set_auto, src/solve/autopath.c):
 *   (a) the setting: on by default, 0/1 only, bad values refused with a
 *       message naming the argument, nothing changed; any phase;
 *   (b) stats.path names the path that ran, auto_chosen whether the model
 *       chose it; eps = 0 is never a choice;
 *   (c) on a molecule-like tree of 4,000 joints the model picks the adaptive
 *       path with one force and the exact one with 400, and each choice
 *       agrees with the counts of a twin that always runs the adaptive
 *       solver (its nodes updated, factors updated and nodes processed priced
 *       with src/solve/cost.h against the articulated-body step): counts, no clock;
 *   (d) a trajectory whose loads go from one force to 400 and back mixes
 *       both paths (and returns to the adaptive one after exact steps, whose
 *       tree is stale): every step's solve is within its certified bound of
 *       an exact solve at the same positions (the exact steps to rounding,
 *       bound 0, every joint computed);
 *   (e) off: every solve adaptive, as before; on again: adaptive first;
 *   (f) the exact fallback, when set, takes precedence (stats.fallback);
 *   (g) positions set by the caller before every solve make the whole tree
 *       stale each time: an adaptive solve would recompute it every time, so
 *       the model stays exact (it never pays that update to switch back),
 *       while after exact steps (the tree stale by their own moves) it does
 *       switch back;
 *   (h) the adaptive refinement's cost is counted after a solve that found it
 *       worth it;
 *   (i) the exact path is priced as the last exact solve ran (the work meter
 *       of src/solve/cost.h), one before the tolerance was set included:
 *       refined on a linkage with heavy bodies, the pass alone with the
 *       refinement off;
 *   (j) on that linkage, with a few forces, the model keeps the adaptive
 *       path, dearer than the pass alone and cheaper than the refined solve. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cost.h"

#define NJ 4000
/* molecule_ex's heavy bodies: every this many-th */
#define HEAVY_EVERY 400

/* A molecule-like tree: revolute torsions about the incoming bond, a
 * backbone with side chains of 1-4 atoms on about half its atoms. */
static aqs_linkage *molecule_ex(uint64_t seed, double heavy)
{
    aqs_linkage *L = test_new_linkage();
    uint64_t rng = seed;
    int32_t i, back = -1;
    double q1[4] = {1, 0, 0, 0};
    for (i = 0; i < NJ; i++) {
        double m = test_uniform(&rng, 12, 33) * (i % HEAVY_EVERY == HEAVY_EVERY / 2 ? heavy : 1.0), com[3] = {0, 0, 0},
               I[9] = {0};
        I[0] = I[4] = I[8] = 0.1 * m;
        assert_int_equal(aqs_body_add(L, m, com, I, NULL), AQS_OK);
    }
    for (i = 0; i < NJ;) {
        /* one backbone atom, then maybe a side chain hanging from it */
        int32_t parent = back, side = test_uniform(&rng, 0, 1) < 0.5 ? 1 + (int32_t)test_uniform(&rng, 0, 4) : 0, k;
        double pos[3] = {test_uniform(&rng, -0.5, 0.5), test_uniform(&rng, -0.5, 0.5), 1.5};
        double axis[3] = {0, 0, 1};
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, parent, i, pos, q1, axis, NULL), AQS_OK);
        back = i++;
        for (k = 0; k < side && i < NJ; k++, i++) {
            double p2[3] = {test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1), 1.0};
            double ax[3] = {test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1), 1.0};
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, k == 0 ? back : i - 1, i, p2, q1, ax, NULL),
                             AQS_OK);
        }
    }
    if (aqs_linkage_finalize(L) != AQS_OK) fail_msg("finalize: %s", aqs_linkage_last_error(L));
    /* The rounding fallback off: these tests are about the cost model. This
     * backbone is a straight chain of ~1,300 bonds of 1.5 m along z, and the
     * rounding estimate carries the handle forces' errors down lever arms
     * of up to 2 km: 1.1e-9 .. 1.4e-9 relative (the DCA is 1.5e-13 from the
     * ABA here), 7x below the fallback's level (docs/math.md §10a): too
     * close for a test whose choices count every solve */
    assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK);
    /* The same estimate is above the adaptive refinement's level, and on this
     * backbone the refinement is worth it (the DCA's 1.5e-13): the tests
     * below count the solve paths without it; test_refinement_priced counts
     * it. */
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, 0.0), AQS_OK);
    return L;
}

static aqs_linkage *molecule(uint64_t seed) { return molecule_ex(seed, 1.0); }

/* nf forces of 1 N on seeded bodies (the same on every call with seed). */
static void set_forces(aqs_linkage *L, int nf, uint64_t seed)
{
    uint64_t rng = seed;
    int k;
    assert_int_equal(aqs_linkage_clear_forces(L), AQS_OK);
    for (k = 0; k < nf; k++) {
        int32_t b = (int32_t)test_uniform(&rng, 0, NJ);
        double f[3] = {test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1)};
        assert_int_equal(aqs_body_set_force(L, b, f, NULL, NULL), AQS_OK);
    }
}

static aqs_solve_stats stats_of(aqs_linkage *L)
{
    aqs_solve_stats s;
    memset(&s, 0, sizeof s);
    s.size = sizeof s;
    assert_int_equal(aqs_linkage_get_stats(L, &s), AQS_OK);
    return s;
}

static void test_setting(void **state)
{
    aqs_linkage *L = test_new_linkage();
    int32_t on = -1;
    (void)state;
    assert_int_equal(aqs_linkage_get_auto(L, &on), AQS_OK); /* before finalize too */
    assert_int_equal(on, 1);
    assert_int_equal(aqs_linkage_set_auto(L, 2), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "enabled = 2");
    assert_int_equal(aqs_linkage_set_auto(L, -1), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "enabled = -1");
    assert_int_equal(aqs_linkage_get_auto(L, &on), AQS_OK);
    assert_int_equal(on, 1);
    assert_int_equal(aqs_linkage_get_auto(L, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "enabled is NULL");
    assert_int_equal(aqs_linkage_set_auto(NULL, 0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_auto(NULL, &on), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_get_auto(L, &on), AQS_OK);
    assert_int_equal(on, 0);
    aqs_linkage_destroy(L);
}

/* The adaptive step's cost from a twin's counts (the same formula as the
 * model, but from what the twin's step really did). */
static double adaptive_step_cost(const aqs_solve_stats *t, int32_t ne)
{
    (void)ne;
    return t->nodes_updated * COST_DCA_NODE_SQRT + t->factors_updated * COST_FACTOR +
           t->nodes_processed * (COST_PROCESS + COST_MOVE);
}

static void test_choice_follows_counts(void **state)
{
    /* 1 force: far below the break-even; 2-8: around it; 400: far above */
    static const int forces[] = {1, 2, 3, 5, 8, 400};
    int c, near = 0, adaptive_kept = 0;
    (void)state;
    for (c = 0; c < (int)(sizeof forces / sizeof forces[0]); c++) {
        aqs_linkage *L = molecule(7), *T = molecule(7);
        const double eps = ldexp(1.0, -19);
        int32_t ne, step, exact_steps = 0, agree = 0, compared = 0;
        assert_int_equal(aqs_linkage_get_sizes(L, NULL, &ne, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(T, 0), AQS_OK);
        set_forces(L, forces[c], 11);
        set_forces(T, forces[c], 11);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, eps), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(T, AQS_METRIC_REL_JOINT, eps), AQS_OK);
        /* the first solve after the tolerance is set is adaptive */
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        {
            aqs_solve_stats s = stats_of(L);
            assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
            assert_int_equal(s.auto_chosen, 0);
            assert_true(s.cost_adaptive == 0.0 && s.cost_exact == 0.0);
        }
        assert_int_equal(aqs_linkage_solve(T), AQS_OK);
        for (step = 0; step < 8; step++) {
            aqs_solve_stats s, t;
            double twin_cost, exact_cost = ne * (COST_ABA_JOINT + COST_ABA_MOVE);
            assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
            assert_int_equal(aqs_linkage_step(T, 1e-3), AQS_OK);
            s = stats_of(L);
            t = stats_of(T);
            assert_int_equal(s.auto_chosen, 1);
            assert_true(s.cost_adaptive > 0.0 && s.cost_exact == exact_cost);
            twin_cost = adaptive_step_cost(&t, ne);
            if (s.path == AQS_PATH_EXACT_ABA) {
                exact_steps++;
                assert_true(s.error_bound == 0.0);
                assert_int_equal(s.computed_joints, s.counted_joints);
                assert_int_equal(s.nodes_updated, 0);
            } else {
                assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
                assert_true(s.error_bound <= eps);
                assert_int_equal(s.computed_joints, t.computed_joints); /* the same steps so far */
                assert_int_equal(s.nodes_updated, t.nodes_updated);
            }
            /* the choice agrees with what the twin's adaptive step really did
             * (L's tree is as fresh as the twin's until L's first exact
             * step); within 5 % of the break-even either is right */
            if (fabs(twin_cost - exact_cost) > 0.05 * exact_cost) {
                compared++;
                if ((twin_cost < exact_cost) == (s.path == AQS_PATH_ADAPTIVE)) agree++;
            } else {
                near++;
            }
            if (s.path == AQS_PATH_EXACT_ABA) break; /* the twin's positions differ from here */
        }
        assert_int_equal(agree, compared);
        if (exact_steps == 0) adaptive_kept++; /* the adaptive path, kept while it is cheaper */
        if (c == 0) assert_int_equal(exact_steps, 0);             /* one force: adaptive throughout */
        if (forces[c] == 400) assert_true(exact_steps == 1 && step == 0); /* exact from the first step */
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(T);
    }
    /* at least the one-force case (asserted above); with the exact pass at
     * ~1,560 instructions per joint (cost.h) the break-even on this 4,000-joint
     * tree lies between 1 and 2 forces */
    assert_true(adaptive_kept >= 1);
    (void)near;
}

/* max over joints of the difference against the exact accelerations, and
 * the rel_joint error measure over the uncomputed joints. */
static void compare(aqs_linkage *L, const double *exact, const double *approx, int32_t nv,
                    double *rel_joint, double *computed_diff)
{
    int32_t j, nj;
    double maxe = 0.0, maxu = 0.0, maxc = 0.0;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, &nj, NULL, NULL), AQS_OK);
    (void)nv;
    for (j = 0; j < nj; j++) {
        int32_t off, computed;
        assert_int_equal(aqs_joint_get_layout(L, j, NULL, NULL, &off, NULL), AQS_OK);
        assert_int_equal(aqs_joint_get_computed(L, j, &computed), AQS_OK);
        if (fabs(exact[off]) > maxe) maxe = fabs(exact[off]);
        if (computed) {
            if (fabs(exact[off] - approx[off]) > maxc) maxc = fabs(exact[off] - approx[off]);
        } else {
            assert_true(approx[off] == 0.0);
            if (fabs(exact[off]) > maxu) maxu = fabs(exact[off]);
        }
    }
    *rel_joint = maxe > 0.0 ? maxu / maxe : 0.0;
    *computed_diff = maxe > 0.0 ? maxc / maxe : 0.0;
}

static void test_mixed_trajectory(void **state)
{
    aqs_linkage *L = molecule(3), *X = molecule(3);
    const double eps = ldexp(1.0, -10);
    int32_t nq, nv, step, adaptive = 0, exact = 0, back = 0, last = -1;
    double *q, *a, *e;
    (void)state;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, &nv), AQS_OK);
    q = malloc(sizeof(double) * (size_t)nq);
    a = malloc(sizeof(double) * (size_t)nv);
    e = malloc(sizeof(double) * (size_t)nv);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, eps), AQS_OK);
    for (step = 0; step < 70; step++) {
        aqs_solve_stats s;
        double err, cdiff;
        /* one force, then 400 (exact is cheaper), then one again */
        if (step == 0 || step == 10 || step == 25) set_forces(L, step == 10 ? 400 : 1, 5 + (uint64_t)step);
        /* the exact twin at L's positions and loads, solved by the ABA */
        assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
        assert_int_equal(aqs_linkage_set_positions(X, q, (size_t)nq), AQS_OK);
        if (step == 0 || step == 10 || step == 25) set_forces(X, step == 10 ? 400 : 1, 5 + (uint64_t)step);
        assert_int_equal(aqs_linkage_solve(X), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(X, e, (size_t)nv), AQS_OK);
        assert_int_equal(aqs_linkage_step(L, 2e-3), AQS_OK);
        s = stats_of(L);
        assert_int_equal(aqs_linkage_get_accelerations(L, a, (size_t)nv), AQS_OK);
        compare(L, e, a, nv, &err, &cdiff);
        /* the computed joints are exact (the DCA and the ABA agree to
         * rounding), the others within the certified bound */
        assert_true(cdiff <= 1e-10);
        assert_true(err <= s.error_bound * (1.0 + 1e-9) + 1e-12);
        if (s.path == AQS_PATH_EXACT_ABA) {
            exact++;
            assert_true(s.error_bound == 0.0 && err == 0.0);
            assert_int_equal(s.computed_joints, s.counted_joints);
        } else {
            assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
            assert_true(s.error_bound <= eps);
            assert_true(s.computed_joints < s.counted_joints);
            adaptive++;
            if (last == AQS_PATH_EXACT_ABA) back++; /* after exact steps: the whole tree recomputed */
        }
        last = s.path;
    }
    assert_true(adaptive > 0 && exact > 0);
    assert_true(back >= 1);
    free(q);
    free(a);
    free(e);
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(X);
}

static void test_off_and_on(void **state)
{
    aqs_linkage *L = molecule(9);
    int k;
    (void)state;
    set_forces(L, 400, 2);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    for (k = 0; k < 3; k++) {
        aqs_solve_stats s;
        assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        s = stats_of(L);
        assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
        assert_int_equal(s.auto_chosen, 0);
        assert_true(s.cost_adaptive == 0.0 && s.cost_exact == 0.0);
    }
    assert_int_equal(aqs_linkage_set_auto(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK); /* adaptive first, to learn */
    assert_int_equal(stats_of(L).path, AQS_PATH_ADAPTIVE);
    for (k = 0; k < 3; k++) {
        aqs_solve_stats s;
        assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        s = stats_of(L);
        assert_int_equal(s.path, AQS_PATH_EXACT_ABA);
        assert_int_equal(s.auto_chosen, 1);
        assert_true(s.cost_adaptive > s.cost_exact);
        assert_int_equal(s.fallback, 0);
    }
    /* refine after an exact solve: nothing to do */
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_refine(L, ldexp(1.0, -25)), AQS_OK);
    assert_true(stats_of(L).error_bound == 0.0);
    /* eps = 0: exact by the chosen exact solver, never the model's choice */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(stats_of(L).path, AQS_PATH_EXACT_ABA);
    assert_int_equal(stats_of(L).auto_chosen, 0);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(stats_of(L).path, AQS_PATH_EXACT_DCA);
    /* a cap: the adaptive solver, never a choice */
    assert_int_equal(aqs_linkage_set_max_computed(L, 50), AQS_OK);
    for (k = 0; k < 3; k++) {
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(stats_of(L).path, AQS_PATH_ADAPTIVE);
        assert_int_equal(stats_of(L).auto_chosen, 0);
    }
    aqs_linkage_destroy(L);
}

static void test_fallback_first(void **state)
{
    aqs_linkage *L = molecule(9);
    aqs_solve_stats s;
    int k;
    (void)state;
    set_forces(L, 400, 2);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_fallback(L, 0.2), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK); /* adaptive, computes most joints */
    s = stats_of(L);
    assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
    assert_true(s.computed_joints > s.counted_joints / 5);
    for (k = 0; k < AQS_FALLBACK_RUN; k++) {
        assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        s = stats_of(L);
        assert_int_equal(s.path, AQS_PATH_EXACT_ABA);
        assert_int_equal(s.fallback, 1);
        assert_int_equal(s.auto_chosen, 0);
    }
    /* the fallback's probe: the model decides it; after exact steps the
     * whole tree is stale, so exact is cheaper */
    assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
    s = stats_of(L);
    assert_int_equal(s.fallback, 0);
    assert_int_equal(s.auto_chosen, 1);
    assert_true(s.cost_adaptive > s.cost_exact);
    assert_int_equal(s.path, AQS_PATH_EXACT_ABA);
    /* solves without a move after an adaptive solve: the tree is current,
     * and back-substituting every node (no update) is cheaper than the ABA:
     * the model takes the adaptive path */
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_fallback(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* adaptive first after set_auto */
    for (k = 0; k < 3; k++) {
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        s = stats_of(L);
        assert_int_equal(s.auto_chosen, 1);
        assert_true(s.cost_adaptive < s.cost_exact);
        assert_int_equal(s.path, AQS_PATH_ADAPTIVE);
    }
    aqs_linkage_destroy(L);
}

static void test_caller_staleness_is_no_switch(void **state)
{
    aqs_linkage *L = molecule(3);
    int32_t nq, k, exact = 0, back = 0;
    double *q;
    (void)state;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
    q = malloc(sizeof(double) * (size_t)nq);
    set_forces(L, 1, 5);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -10)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* adaptive, learns */
    assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
    for (k = 0; k < 60; k++) {
        aqs_solve_stats s;
        q[k % nq] += 1e-3; /* a new configuration, set in bulk */
        assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        s = stats_of(L);
        assert_int_equal(s.auto_chosen, 1);
        exact += s.path == AQS_PATH_EXACT_ABA;
    }
    assert_int_equal(exact, 60); /* never the full update */
    /* steps: the exact step's own staleness is a switch cost, repaid by the
     * cheaper adaptive steps after enough exact ones */
    for (k = 0; k < 60 && !back; k++) {
        assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        back = stats_of(L).path == AQS_PATH_ADAPTIVE;
    }
    assert_true(back);
    free(q);
    aqs_linkage_destroy(L);
}

/* (h) the adaptive refinement (docs/math.md §13c) is priced: after an
 * adaptive solve that refined its computed joints and found it worth it,
 * the model's adaptive cost of the next solve adds COST_AREFINE per processed
 * node; a twin with the refinement off is priced without it. */
static void test_refinement_priced(void **state)
{
    aqs_linkage *A = molecule(5), *B = molecule(5);
    aqs_solve_stats sa, sb;
    double ea, eb, expect;
    (void)state;
    assert_int_equal(aqs_linkage_set_adaptive_refinement(A, AQS_ADAPTIVE_REFINEMENT_LEVEL), AQS_OK);
    set_forces(A, 1, 3);
    set_forces(B, 1, 3);
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(B, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(A, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(B, 0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    sa = stats_of(A);
    sb = stats_of(B);
    ea = sa.nodes_processed;
    eb = sb.nodes_processed;
    assert_int_equal(aqs_linkage_set_auto(A, 1), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(B, 1), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK); /* adaptive first after set_auto */
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    sa = stats_of(A);
    sb = stats_of(B);
    assert_int_equal(sa.auto_chosen, 1);
    assert_int_equal(sb.auto_chosen, 1);
    expect = ea * (COST_PROCESS + COST_AREFINE) - eb * COST_PROCESS;
    print_message("refined: adaptive %.4g, unrefined %.4g (E %g / %g)\n", sa.cost_adaptive, sb.cost_adaptive, ea, eb);
    assert_true(fabs((sa.cost_adaptive - sb.cost_adaptive) - expect) <= 1e-9 * sa.cost_adaptive);
    assert_true(sa.cost_exact == sb.cost_exact);
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
}

/* (i) The exact path priced as it ran (cost.h's work meter): on a linkage
 * with heavy bodies (1e3 times their neighbours: every articulated-body
 * solve refines) the model's exact cost is more than the pass and what its
 * refinement always does (one double-double residual and the accelerations
 * it needs, one correction): so from the first choice on, priced by the
 * exact solve made before the tolerance was set; and exactly the pass where
 * the refinement is off (the same linkage and loads, or the same linkage
 * once its refinement is turned off). */
static void test_exact_priced_as_run(void **state)
{
    aqs_linkage *H = molecule_ex(5, 1e3), *R = molecule_ex(5, 1e3);
    aqs_linkage *both[2];
    int32_t ne, k, step;
    (void)state;
    both[0] = H;
    both[1] = R;
    assert_int_equal(aqs_linkage_get_sizes(H, NULL, &ne, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_refinement(R, 0), AQS_OK);
    for (k = 0; k < 2; k++) {
        set_forces(both[k], 400, 11);
        /* an exact solve before the tolerance: its count prices the first
         * choice (the tolerance starts the model over, not the price) */
        assert_int_equal(aqs_linkage_solve(both[k]), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(both[k], AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
        assert_int_equal(aqs_linkage_solve(both[k]), AQS_OK); /* adaptive: the first after the tolerance */
    }
    for (step = 0; step < 3; step++) {
        aqs_solve_stats h, r;
        const double pass = ne * (COST_ABA_JOINT + COST_ABA_MOVE);
        const double least = ne * (COST_ABA_JOINT + COST_DD_ACCEL + COST_DD_RESIDUAL + COST_ABA_CORRECTION + COST_ABA_MOVE);
        assert_int_equal(aqs_linkage_step(H, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_step(R, 1e-3), AQS_OK);
        h = stats_of(H);
        r = stats_of(R);
        print_message("step %d: exact priced %.4g refined, %.4g unrefined; the pass %.4g\n", (int)step,
                      h.cost_exact, r.cost_exact, pass);
        assert_int_equal(h.path, AQS_PATH_EXACT_ABA); /* 400 forces: exact from the first step */
        assert_int_equal(r.path, AQS_PATH_EXACT_ABA);
        assert_true(h.auto_chosen && r.auto_chosen);
        assert_true(r.cost_exact == pass);
        assert_true(h.cost_exact > least);
    }
    /* a new refinement count drops the price: the next choice is priced at
     * the pass (no refinement to add) */
    assert_int_equal(aqs_linkage_set_exact_refinement(H, 0), AQS_OK);
    assert_int_equal(aqs_linkage_step(H, 1e-3), AQS_OK);
    {
        const aqs_solve_stats h = stats_of(H);
        assert_true(h.auto_chosen && h.cost_exact == ne * (COST_ABA_JOINT + COST_ABA_MOVE));
    }
    aqs_linkage_destroy(H);
    aqs_linkage_destroy(R);
}

/* (j) The same heavy linkage with 8 forces: an adaptive step there costs
 * 1.75x the articulated-body pass alone (its twin's counts, priced by
 * cost.h) but less than the refined exact solve, so the model keeps the
 * adaptive path on every step (priced at the pass, as before the work
 * meter, the exact path looked cheaper: the model took it and paid the
 * refinement, 2.4 .. 4.5x the pass, on every step). */
static void test_heavy_stays_adaptive(void **state)
{
    aqs_linkage *L = molecule_ex(5, 1e3), *T = molecule_ex(5, 1e3);
    int32_t ne, step, exact_steps = 0;
    (void)state;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, &ne, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(T, 0), AQS_OK);
    set_forces(L, 8, 11);
    set_forces(T, 8, 11);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(T, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_solve(T), AQS_OK);
    for (step = 0; step < 8; step++) {
        aqs_solve_stats s, t;
        const double pass = ne * (COST_ABA_JOINT + COST_ABA_MOVE);
        double twin;
        assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
        assert_int_equal(aqs_linkage_step(T, 1e-3), AQS_OK);
        s = stats_of(L);
        t = stats_of(T);
        twin = adaptive_step_cost(&t, ne);
        print_message("step %d: path %d, adaptive %.4g (twin %.4g), exact %.4g, the pass %.4g\n", (int)step, (int)s.path,
                      s.cost_adaptive, twin, s.cost_exact, pass);
        exact_steps += s.path != AQS_PATH_ADAPTIVE;
        assert_true(s.auto_chosen);
        /* the regime: dearer than the pass, cheaper than the refined solve */
        assert_true(twin > 1.25 * pass && twin < s.cost_exact);
        assert_int_equal(s.computed_joints, t.computed_joints); /* the same steps */
    }
    assert_int_equal(exact_steps, 0);
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(T);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_setting),
        cmocka_unit_test(test_choice_follows_counts),
        cmocka_unit_test(test_mixed_trajectory),
        cmocka_unit_test(test_off_and_on),
        cmocka_unit_test(test_fallback_first),
        cmocka_unit_test(test_caller_staleness_is_no_switch),
        cmocka_unit_test(test_refinement_priced),
        cmocka_unit_test(test_exact_priced_as_run),
        cmocka_unit_test(test_heavy_stays_adaptive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
