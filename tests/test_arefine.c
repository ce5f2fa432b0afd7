/* test_arefine.c -- refinement of an adaptive solve's computed joints
 * (src/solve/arefine.c, docs/math.md §13c):
 *   - on the families where the DCA's own assembly loses digits (a light
 *     chain behind a heavy one, masses alternating by 1e6), adaptive solves
 *     under the four joint measures at several eps: the computed joints
 *     within 1e-14 of the articulated-body solve (relative to the largest
 *     acceleration), where the same solve with the refinement off is more
 *     than 1e-12 away (the check can fail); the certified bound still holds
 *     against the ABA;
 *   - random trees of every joint type (floating bases, spherical, prismatic
 *     joints, welded bodies), refined at every solve: the computed joints
 *     within 1e-12 of the ABA, the refinement never worse than its absence;
 *   - the stored DCA values are the solve's again: an exact unrefined solve
 *     after a refined adaptive one is bit for bit a twin's that never
 *     refined; positions changed one joint at a time (load factors kept by
 *     some nodes and not by others) keep the answers right;
 *   - the setting: default, 0 off, bad values refused; out of memory: the
 *     solve succeeds unrefined, nothing held, the next one refines.
 * The reference is the articulated-body solve, an independent algorithm
 * within 1e-15 of a __float128 reference on these families
 * (tests/reference/hardcases.cpp: light distal links 1.3e-16 .. 4e-16,
 * altmass r = 1e6 5e-16 .. 1e-15). */
#include "testutil.h"
#include "chains.h"
#include "randtree.h"
#include "refinetest.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "linkage.h"

static const int32_t kMetrics[4] = {AQS_METRIC_ABS_LINKAGE, AQS_METRIC_REL_LINKAGE, AQS_METRIC_ABS_JOINT,
                                    AQS_METRIC_REL_JOINT};

/* hardcases' lightdistal: 40 links (tests/support/chains.h), the first 20 of
 * 1000 kg, the others of mu, under gravity -z at positions uniform in
 * (-1, 1), a load mu along y at the last link's end; the automatic path off.
 * With cs, the counting allocator. */
static aqs_linkage *lightdistal_in(counting_state *cs, double mu, uint64_t seed)
{
    const double g[3] = {0, 0, -9.81}, f[3] = {0, mu, 0}, pt[3] = {1, 0, 0};
    double m[40], q[40];
    aqs_linkage *L;
    int32_t i;
    for (i = 0; i < 40; i++) {
        m[i] = i < 20 ? 1000.0 : mu;
        q[i] = test_uniform(&seed, -1.0, 1.0);
    }
    L = test_zy_chain(cs, 40, m, 0, q, g);
    assert_int_equal(aqs_body_set_force(L, 39, f, pt, NULL), AQS_OK); /* no welded bodies: link i is body i */
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    return L;
}

static aqs_linkage *lightdistal(double mu, uint64_t seed)
{
    return lightdistal_in(NULL, mu, seed);
}

/* hardcases' altmass (tests/support/chains.h), the automatic path off. */
static aqs_linkage *altmass(int n, double ratio, uint64_t seed)
{
    aqs_linkage *L = test_altmass_chain(NULL, n, ratio, 0, seed);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
    return L;
}

/* Over L's computed joints (one dof per joint here): the largest difference
 * of qdd from ref, their count into *ncomp; the largest |ref| of all joints
 * into *m. */
static double computed_diff(const aqs_linkage *L, const double *qdd, const double *ref, int32_t nv, int32_t *ncomp,
                            double *m)
{
    double e = 0.0;
    int32_t j;
    *ncomp = 0, *m = 0.0;
    for (j = 0; j < nv; j++) {
        int32_t c;
        assert_int_equal(aqs_joint_get_computed(L, j, &c), AQS_OK);
        *m = fmax(*m, fabs(ref[j]));
        if (c) {
            (*ncomp)++;
            e = fmax(e, fabs(qdd[j] - ref[j]));
        }
    }
    return e;
}

/* The largest difference over the computed joints (relative to the largest
 * reference acceleration), their count, and the skipped joints' measure
 * against ref (the ABA's: what the solve's error_bound bounds). */
static double computed_error(const aqs_linkage *L, const double *qdd, const double *ref, int32_t nv, int32_t *ncomp,
                             int32_t metric, double *skipped)
{
    double m, s2 = 0.0, smax = 0.0, all2 = 0.0;
    const double e = computed_diff(L, qdd, ref, nv, ncomp, &m);
    int32_t j;
    for (j = 0; j < nv; j++) { /* one dof per joint here */
        int32_t c;
        assert_int_equal(aqs_joint_get_computed(L, j, &c), AQS_OK);
        all2 += ref[j] * ref[j];
        if (!c) {
            s2 += ref[j] * ref[j];
            smax = fmax(smax, fabs(ref[j]));
        }
    }
    switch (metric) {
    case AQS_METRIC_ABS_LINKAGE: *skipped = sqrt(s2); break;
    case AQS_METRIC_REL_LINKAGE: *skipped = sqrt(s2 / all2); break;
    case AQS_METRIC_ABS_JOINT: *skipped = smax; break;
    default: *skipped = smax / m; break;
    }
    return e / m;
}

/* L (refinement on) and its twin X: X's refinement off, the rounding
 * fallback off in both (it would answer these families with the ABA). */
static void unrefined_twin(aqs_linkage *L, aqs_linkage *X)
{
    assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_rounding_fallback(X, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(X, 0.0), AQS_OK);
}

/* L (refinement on, the default) and its twin X (off), the rounding fallback
 * off in both (it would answer these with the ABA): for every joint measure
 * and eps 2^-1, 2^-4, 2^-10, solves that skip joints. Returns the largest
 * computed-joint error of L's and X's solves. */
static void refined_vs_off(aqs_linkage *L, aqs_linkage *X, const char *what, double *worst_on, double *worst_off,
                           double *worst_f, double *worst_fx)
{
    int32_t nv, mi, e, nsolves = 0, j;
    double *ref, *q, *fref, *f, fm = 0.0;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv), AQS_OK);
    ref = calloc((size_t)nv, sizeof *ref);
    q = calloc((size_t)nv, sizeof *q);
    fref = calloc(6 * (size_t)nv, sizeof *fref);
    f = calloc(6 * (size_t)nv, sizeof *f);
    assert_non_null(ref && q && fref && f);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* the ABA, the default exact solver */
    assert_int_equal(aqs_linkage_get_accelerations(L, ref, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, fref, 6 * (size_t)nv), AQS_OK);
    for (j = 0; j < 6 * nv; j++) fm = fmax(fm, fabs(fref[j]));
    unrefined_twin(L, X);
    *worst_on = *worst_off = *worst_f = *worst_fx = 0.0;
    for (mi = 0; mi < 4; mi++)
        for (e = 1; e <= 10; e += e < 4 ? 3 : 6) {
            aqs_solve_stats st;
            int32_t nc, ncx;
            double on, off, skipped, skipped_x, tot;
            assert_int_equal(aqs_linkage_set_tolerance(L, kMetrics[mi], ldexp(1.0, -e)), AQS_OK);
            assert_int_equal(aqs_linkage_set_tolerance(X, kMetrics[mi], ldexp(1.0, -e)), AQS_OK);
            assert_int_equal(aqs_linkage_solve(L), AQS_OK);
            assert_int_equal(aqs_linkage_solve(X), AQS_OK);
            st.size = sizeof st;
            assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
            assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
            on = computed_error(L, q, ref, nv, &nc, kMetrics[mi], &skipped);
            {
                double fe = 0.0, fex = 0.0;
                assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nv), AQS_OK);
                for (j = 0; j < 6 * nv; j++)
                    if (!isnan(f[j])) fe = fmax(fe, fabs(f[j] - fref[j]));
                assert_int_equal(aqs_linkage_get_constraint_forces(X, f, 6 * (size_t)nv), AQS_OK);
                for (j = 0; j < 6 * nv; j++)
                    if (!isnan(f[j])) fex = fmax(fex, fabs(f[j] - fref[j]));
                *worst_f = fmax(*worst_f, fe / fm);
                *worst_fx = fmax(*worst_fx, fex / fm);
            }
            assert_int_equal(aqs_linkage_get_accelerations(X, q, (size_t)nv), AQS_OK);
            off = computed_error(X, q, ref, nv, &ncx, kMetrics[mi], &skipped_x);
            if (nc == nv) continue; /* every joint computed: the exact refinement's case (test_refine.c) */
            nsolves++;
            print_message("%s metric %d eps 2^-%d: %d of %d computed, error %.2e (off %.2e), bound %.2e + %.2e, "
                          "skipped %.2e\n",
                          what, (int)kMetrics[mi], (int)e, (int)nc, (int)nv, on, off, st.error_bound,
                          st.rounding_bound, skipped);
            assert_int_equal(st.path, AQS_PATH_ADAPTIVE);
            /* the certified bound against the ABA's skipped joints (the
             * computed ones' error is 1e-14 of the largest, far below eps) */
            tot = st.error_bound + st.rounding_bound;
            if (st.certified) assert_true(skipped <= tot * (1.0 + 1e-9));
            *worst_on = fmax(*worst_on, on);
            *worst_off = fmax(*worst_off, off);
        }
    assert_true(nsolves >= 4);
    print_message("%s: joint forces %.2e of the largest (unrefined %.2e)\n", what, *worst_f, *worst_fx);
    free(ref), free(q), free(fref), free(f);
}

/* 1e-14: 45 u of the largest acceleration; measured 4e-16 .. 1.9e-15 (light
 * distal links 1e-9, altmass 1e6). The refinement off: 1.3e-11 .. 1.5e-11
 * (lightdistal), 9.7e-11 (altmass 1e6). */
static void test_hard_families(void **state)
{
    uint64_t seed;
    (void)state;
    for (seed = 1; seed <= 3; seed++) {
        double on, off, fon, foff;
        aqs_linkage *L = lightdistal(1e-9, seed), *X = lightdistal(1e-9, seed);
        refined_vs_off(L, X, "lightdistal 1e-9", &on, &off, &fon, &foff);
        assert_true(on <= 1e-14);
        assert_true(off > 1e-12);
        /* the joint forces against the ABA's, relative to the largest (the
         * heavy links'): 4e-14 .. 2e-13 refined or not (what the refinement
         * moves is far below that scale) */
        assert_true(fon <= 1e-11 && fon <= 2.0 * foff + 1e-15);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
        L = altmass(100, 1e6, seed);
        X = altmass(100, 1e6, seed);
        refined_vs_off(L, X, "altmass 1e6", &on, &off, &fon, &foff);
        assert_true(on <= 1e-14);
        assert_true(off > 1e-12);
        assert_true(fon <= 1e-10 && fon <= 2.0 * foff + 1e-15); /* measured 3e-12 .. 7.7e-12 */
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
}

/* Random trees of every joint type (free bases on odd k, welded bodies come
 * with the fixed joints the generator draws), masses over 1e4, refined at
 * every adaptive solve (a level of 1e-300): the computed joints' values
 * within 1e-12 of the ABA's (relative 2-norm over the computed dofs), and
 * never more than 2x (plus 1e-15) the unrefined twin's error; the joint
 * forces it gives (computed joints, welded bodies of the leaves it reached)
 * likewise against the ABA's. */
static void test_joint_types(void **state)
{
    uint64_t rng = 777;
    int k, nref = 0, nsolve = 0, nf = 0;
    (void)state;
    for (k = 0; k < 12; k++) {
        aqs_linkage *L, *X;
        uint64_t r2 = rng;
        int32_t nv, nj, j, e, mi;
        double fe = 0.0, fec = 0.0, fex = 0.0, fmaxall = 0.0;
        double *ref, *q, *qx, *fref, *f, *fx;
        L = test_mixed_tree(&rng, 60, k % 2, 4, 1e2);
        X = test_mixed_tree(&r2, 60, k % 2, 4, 1e2);
        assert_int_equal(aqs_linkage_get_sizes(L, NULL, &nj, NULL, &nv), AQS_OK);
        ref = calloc((size_t)nv, sizeof *ref);
        q = calloc((size_t)nv, sizeof *q);
        qx = calloc((size_t)nv, sizeof *qx);
        fref = calloc(6 * (size_t)nj, sizeof *fref);
        f = calloc(6 * (size_t)nj, sizeof *f);
        fx = calloc(6 * (size_t)nj, sizeof *fx);
        assert_non_null(ref && q && qx && fref && f && fx);
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_ABA), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(L, ref, (size_t)nv), AQS_OK);
        assert_int_equal(aqs_linkage_get_constraint_forces(L, fref, 6 * (size_t)nj), AQS_OK);
        for (j = 0; j < 6 * nj; j++) fmaxall = fmax(fmaxall, fabs(fref[j]));
        assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK);
        assert_int_equal(aqs_linkage_set_auto(X, 0), AQS_OK);
        unrefined_twin(L, X);
        assert_int_equal(aqs_linkage_set_adaptive_refinement(L, 1e-300), AQS_OK);
        for (mi = 0; mi < 4; mi++)
            for (e = 2; e <= 12; e += 5) {
                double d2 = 0.0, dx2 = 0.0, r2n = 0.0;
                int32_t refined;
                assert_int_equal(aqs_linkage_set_tolerance(L, kMetrics[mi], ldexp(1.0, -e)), AQS_OK);
                assert_int_equal(aqs_linkage_set_tolerance(X, kMetrics[mi], ldexp(1.0, -e)), AQS_OK);
                assert_int_equal(aqs_linkage_solve(L), AQS_OK);
                assert_int_equal(aqs_linkage_solve(X), AQS_OK);
                refined = L->s.arefined;
                assert_int_equal(aqs_linkage_get_accelerations(L, q, (size_t)nv), AQS_OK);
                assert_int_equal(aqs_linkage_get_accelerations(X, qx, (size_t)nv), AQS_OK);
                assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nj), AQS_OK);
                assert_int_equal(aqs_linkage_get_constraint_forces(X, fx, 6 * (size_t)nj), AQS_OK);
                for (j = 0; j < 6 * nj; j++) /* every force the solve gave (computed joints, reached welds) */
                    if (!isnan(f[j])) {
                        fe = fmax(fe, fabs(f[j] - fref[j]));
                        nf++;
                        /* the twin computed it too, unless the refinement
                         * processed lossy queued nodes first (open_lossy) */
                        if (!isnan(fx[j])) {
                            fec = fmax(fec, fabs(f[j] - fref[j]));
                            fex = fmax(fex, fabs(fx[j] - fref[j]));
                        }
                    }
                for (j = 0; j < nj; j++) {
                    int32_t c, off, n, i;
                    assert_int_equal(aqs_joint_get_computed(L, j, &c), AQS_OK);
                    if (!c) continue;
                    assert_int_equal(aqs_joint_get_layout(L, j, NULL, NULL, &off, &n), AQS_OK);
                    for (i = off; i < off + n; i++) {
                        d2 += (q[i] - ref[i]) * (q[i] - ref[i]);
                        dx2 += (qx[i] - ref[i]) * (qx[i] - ref[i]);
                        r2n += ref[i] * ref[i];
                    }
                }
                if (r2n == 0.0) continue;
                nref += refined > 0;
                nsolve++;
                assert_true(sqrt(d2 / r2n) <= 1e-12);
                assert_true(sqrt(d2) <= 2.0 * sqrt(dx2) + 1e-15 * sqrt(r2n));
            }
        print_message("tree %d: joint forces %.2e of the largest (unrefined %.2e)\n", k, fe / fmaxall, fex / fmaxall);
        /* the DCA's forces and the ABA's differ by 2e-13 .. 1.2e-12 of the
         * largest here, refined or not (the trees are benign: the corrections
         * are at the rounding level); not worse than unrefined */
        assert_true(fe <= 1e-10 * fmaxall);
        assert_true(fec <= 2.0 * fex + 1e-15 * fmaxall);
        free(ref), free(q), free(qx), free(fref), free(f), free(fx);
        aqs_linkage_destroy(L);
        aqs_linkage_destroy(X);
    }
    /* most solves kept a correction (the others' first one was not lower) */
    print_message("%d of %d solves refined, %d forces compared\n", nref, nsolve, nf);
    assert_true(nf > 0);
    assert_true(2 * nref > nsolve);
}

/* After a refined adaptive solve the stored b, rho, gamma and rounding levels
 * are the solve's: an exact unrefined DCA solve next is bit for bit a twin's
 * that never refined. */
static void test_state_restored(void **state)
{
    aqs_linkage *A = lightdistal(1e-9, 5), *B = lightdistal(1e-9, 5);
    double qa[40], qb[40];
    (void)state;
    unrefined_twin(A, B);
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(B, AQS_METRIC_REL_JOINT, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    assert_true(A->s.arefined >= 1);
    assert_int_equal(B->s.arefined, 0);
    assert_int_equal(aqs_linkage_get_accelerations(A, qa, 40), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(B, qb, 40), AQS_OK);
    assert_true(memcmp(qa, qb, sizeof qa) != 0);
    assert_int_equal(aqs_linkage_set_exact_refinement(A, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_refinement(B, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(A, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(B, AQS_EXACT_DCA), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(B, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(A, qa, 40), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(B, qb, 40), AQS_OK);
    assert_memory_equal(qa, qb, sizeof qa);
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
}

/* Positions changed one joint at a time: the lazy update recomputes that
 * joint's ancestors only, so some nodes' load factors are from this update
 * and some from earlier ones (and the first refined solve had none: every
 * correction by the full node update). Each refined solve against the ABA at
 * the same positions: within 1e-14 (as test_hard_families). */
static void test_moving(void **state)
{
    aqs_linkage *L = lightdistal(1e-9, 9), *C = lightdistal(1e-9, 9);
    uint64_t rng = 99;
    double q[40], ref[40], qd[40];
    int k;
    (void)state;
    assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.05), AQS_OK);
    for (k = 0; k < 12; k++) {
        const int32_t j = (int32_t)test_uniform(&rng, 0.0, 40.0);
        double v = test_uniform(&rng, -1.0, 1.0), m, e;
        int32_t nc;
        assert_int_equal(aqs_joint_set_position(L, j, &v, 1), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        assert_true(L->s.arefined >= 1);
        assert_int_equal(aqs_linkage_get_positions(L, q, 40), AQS_OK);
        assert_int_equal(aqs_linkage_set_positions(C, q, 40), AQS_OK);
        assert_int_equal(aqs_linkage_solve(C), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(C, ref, 40), AQS_OK);
        assert_int_equal(aqs_linkage_get_accelerations(L, qd, 40), AQS_OK);
        e = computed_diff(L, qd, ref, 40, &nc, &m);
        assert_true(nc > 0 && nc < 40);
        assert_true(e <= 1e-14 * m);
    }
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(C);
}

/* aqs_linkage_refine continues a refined solve to a smaller eps: the joints it
 * adds are computed from the refined handle forces and refined again (within
 * 1e-14 of the ABA), down to every joint. A solve the rounding fallback answers is not refined
 * first (its estimate is above the fallback's level: the ABA's answer). */
static void test_continue_and_fallback(void **state)
{
    aqs_linkage *L = lightdistal(1e-9, 3), *A = altmass(100, 1e6, 2);
    double ref[40], q[40], m, e;
    aqs_solve_stats st;
    int32_t i, n1, n2;
    (void)state;
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, ref, 40), AQS_OK);
    assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.5), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    st.size = sizeof st;
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    n1 = st.computed_joints;
    assert_int_equal(aqs_linkage_refine(L, ldexp(1.0, -3)), AQS_OK);
    assert_true(L->s.arefined >= 1);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_true(st.computed_joints > n1 && st.computed_joints < 40);
    assert_int_equal(aqs_linkage_get_accelerations(L, q, 40), AQS_OK);
    e = computed_diff(L, q, ref, 40, &n2, &m);
    assert_int_equal(n2, st.computed_joints);
    assert_true(e <= 1e-14 * m);
    /* down to every joint: refined too (aqs_linkage_refine has no exact
     * refinement after it) */
    assert_int_equal(aqs_linkage_refine(L, ldexp(1.0, -40)), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(L, &st), AQS_OK);
    assert_int_equal(st.computed_joints, 40);
    assert_true(L->s.arefined >= 1);
    assert_int_equal(aqs_linkage_get_accelerations(L, q, 40), AQS_OK);
    for (i = 0, e = 0.0; i < 40; i++) e = fmax(e, fabs(q[i] - ref[i]));
    assert_true(e <= 1e-14 * m);
    aqs_linkage_destroy(L);
    /* the fallback on (the default): the ABA answers, nothing refined */
    assert_int_equal(aqs_linkage_set_tolerance(A, AQS_METRIC_REL_JOINT, 0.0625), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_get_stats(A, &st), AQS_OK);
    assert_int_equal(st.rounding_fallback, 1);
    assert_int_equal(A->s.arefined, 0);
    assert_true(A->arf == NULL); /* its arrays were never needed */
    aqs_linkage_destroy(A);
}

/* aqs_linkage_set_adaptive_refinement: the default, 0 off, negative and
 * non-finite levels refused with nothing changed, NULL refused. */
static void test_setting(void **state)
{
    aqs_linkage *L = lightdistal(1e-9, 2);
    double lv = -1.0;
    (void)state;
    assert_int_equal(aqs_linkage_get_adaptive_refinement(L, &lv), AQS_OK);
    assert_true(lv == AQS_ADAPTIVE_REFINEMENT_LEVEL);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, -1.0), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "level");
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, NAN), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, INFINITY), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_adaptive_refinement(L, &lv), AQS_OK);
    assert_true(lv == AQS_ADAPTIVE_REFINEMENT_LEVEL);
    assert_int_equal(aqs_linkage_get_adaptive_refinement(L, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(NULL, 1.0), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_adaptive_refinement(NULL, &lv), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_get_adaptive_refinement(L, &lv), AQS_OK);
    assert_true(lv == 0.0);
    assert_int_equal(aqs_linkage_set_rounding_fallback(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(L->s.arefined, 0);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, AQS_ADAPTIVE_REFINEMENT_LEVEL), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_true(L->s.arefined >= 1);
    aqs_linkage_destroy(L);
}

/* The refinement's arrays come at the first solve that refines; when one of
 * them cannot be had, that solve still succeeds, unrefined (bit for bit a
 * twin's with the refinement off, no queued node processed for it), holding
 * nothing more; the next refines, and at eps 1/2 processes the queued nodes
 * open_lossy finds (12 joints computed instead of 7). */
static void test_out_of_memory(void **state)
{
    counting_state cs;
    aqs_linkage *L, *X = lightdistal(1e-9, 4);
    double q0[40];
    long k, live = 0;
    (void)state;
    memset(&cs, 0, sizeof cs);
    L = lightdistal_in(&cs, 1e-9, 4);
    unrefined_twin(L, X);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.5), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(X, AQS_METRIC_REL_JOINT, 0.5), AQS_OK);
    assert_int_equal(aqs_linkage_solve(X), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(X, q0, 40), AQS_OK);
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* the DCA's own arrays, first */
    assert_int_equal(aqs_linkage_set_adaptive_refinement(L, AQS_ADAPTIVE_REFINEMENT_LEVEL), AQS_OK);
    {
        /* the load factors a failed solve allocated before the failure are kept */
        const test_oom o = {L, &cs, &L->s.arefined, q0, 40, 1};
        /* dca_loads_enable's three blocks (each failure frees the others), then
         * arefine_alloc's first (the load factors kept from then on), then its
         * other ten with the load factors there */
        for (k = 0; k < 14; k++) {
            static const long fail[14] = {1, 2, 3, 4, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
            live = test_oom_unrefined(&o, fail[k]);
            assert_int_equal(L->s.computed, X->s.computed);
        }
        test_oom_refined(&o, live);
        assert_true(L->s.computed > X->s.computed);
    }
    aqs_linkage_destroy(L);
    aqs_linkage_destroy(X);
    assert_int_equal(cs.live, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hard_families), cmocka_unit_test(test_joint_types),
        cmocka_unit_test(test_state_restored), cmocka_unit_test(test_moving),
        cmocka_unit_test(test_setting),        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_continue_and_fallback),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
