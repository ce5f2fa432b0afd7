/* test_dca_form.c -- the two forms of the divide-and-conquer solver
 * (aqs_linkage_set_dca_form): the setting and its errors, both forms against
 * the articulated-body solver on random trees, and the cases where only the
 * square-root form keeps its digits (a straight chain of 20,000 links, a
 * near point mass, light distal links).
 *
 * The reference is the articulated-body solver (AQS_EXACT_ABA): it does not
 * use the assembly tree at all, and it agrees with an extended-precision
 * (__float128) reference to 1e-15..1e-13 on these families
 * (tests/reference/hardcases.cpp, docs/hardcases.md). */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* qdd of the exact solve by the ABA and by the DCA, into a and d (n each). */
static void solve_both(aqs_linkage *L, double *a, double *d, int32_t n, aqs_status *dca_status)
{
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_ABA), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, a, n), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    *dca_status = aqs_linkage_solve(L);
    if (*dca_status == AQS_OK) assert_int_equal(aqs_linkage_get_accelerations(L, d, n), AQS_OK);
}

static void test_form_setting(void **state)
{
    aqs_linkage *L = test_new_linkage();
    int32_t form = -1, b;
    (void)state;
    assert_int_equal(aqs_linkage_get_dca_form(L, &form), AQS_OK);
    assert_int_equal(form, AQS_DCA_FORM_SQRT); /* the default */
    assert_int_equal(aqs_linkage_set_dca_form(L, 7), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_set_dca_form: form = 7");
    assert_int_equal(aqs_linkage_get_dca_form(L, &form), AQS_OK);
    assert_int_equal(form, AQS_DCA_FORM_SQRT); /* unchanged */
    assert_int_equal(aqs_linkage_set_dca_form(L, AQS_DCA_FORM_PHI), AQS_OK);
    assert_int_equal(aqs_linkage_get_dca_form(L, &form), AQS_OK);
    assert_int_equal(form, AQS_DCA_FORM_PHI);
    assert_int_equal(aqs_linkage_get_dca_form(L, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_set_dca_form(NULL, AQS_DCA_FORM_PHI), AQS_EINVAL);
    b = test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, b, 0, 0, 0, 0, 0, 1);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_dca_form(L, AQS_DCA_FORM_SQRT), AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "finalized");
    assert_int_equal(aqs_linkage_get_dca_form(L, &form), AQS_OK);
    assert_int_equal(form, AQS_DCA_FORM_PHI);
    aqs_linkage_destroy(L);
}

/* A random tree of n bodies with revolute, prismatic, universal and
 * cylindrical joints, random frames and axes, positions and loads. */
static aqs_linkage *random_tree(int32_t form, int32_t n, uint64_t *rng, int32_t *nv)
{
    aqs_linkage *L = test_new_linkage();
    /* joints without quaternion positions, so that every position can be perturbed */
    static const int32_t types[4] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_UNIVERSAL,
                                     AQS_JOINT_CYLINDRICAL};
    const double g[3] = {0.3, -9.81, 1.1};
    int32_t i, nq = 0;
    double *q;
    assert_int_equal(aqs_linkage_set_dca_form(L, form), AQS_OK);
    for (i = 0; i < n; i++) {
        const double com[3] = {test_uniform(rng, 0.1, 0.8), test_uniform(rng, -0.1, 0.1), test_uniform(rng, -0.1, 0.1)};
        const double d0 = test_uniform(rng, 0.02, 0.2), d1 = test_uniform(rng, 0.02, 0.2), d2 = test_uniform(rng, 0.02, 0.2);
        const double I[9] = {d0 + d1, 0, 0, 0, d1 + d2, 0, 0, 0, d0 + d2}; /* triangle inequality holds */
        const double pos[3] = {test_uniform(rng, 0.3, 1.2), test_uniform(rng, -0.3, 0.3), test_uniform(rng, -0.3, 0.3)};
        double quat[4], axis[3], nrm;
        int32_t b, parent = i == 0 ? AQS_WORLD : (int32_t)test_uniform(rng, 0, i), type = types[i % 4];
        assert_int_equal(aqs_body_add(L, test_uniform(rng, 0.5, 2.0), com, I, &b), AQS_OK);
        test_random_quat(rng, quat);
        axis[0] = test_uniform(rng, -1, 1);
        axis[1] = test_uniform(rng, -1, 1);
        axis[2] = test_uniform(rng, -1, 1);
        nrm = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        axis[0] /= nrm, axis[1] /= nrm, axis[2] /= nrm;
        assert_int_equal(aqs_joint_add(L, type, parent, b, pos, quat, axis, NULL), AQS_OK);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, nv), AQS_OK);
    q = malloc(sizeof(double) * (size_t)nq);
    assert_non_null(q);
    assert_int_equal(aqs_linkage_get_positions(L, q, nq), AQS_OK);
    for (i = 0; i < nq; i++) q[i] += test_uniform(rng, -0.5, 0.5);
    assert_int_equal(aqs_linkage_set_positions(L, q, nq), AQS_OK);
    free(q);
    return L;
}

/* Both forms equal the articulated-body solver on 40 random trees of 30
 * bodies. Ordinary data (masses 0.5..2, lengths ~1): the DCA's rounding is
 * a few hundred ulps at most (1e-14 measured); 1e-11 leaves a wide margin
 * and still catches any wrong formula, whose error would be O(1). */
static void test_forms_agree(void **state)
{
    uint64_t rng = 12345;
    int32_t form, k;
    (void)state;
    for (form = AQS_DCA_FORM_SQRT; form <= AQS_DCA_FORM_PHI; form++)
        for (k = 0; k < 40; k++) {
            int32_t nv = 0;
            aqs_linkage *L = random_tree(form, 30, &rng, &nv);
            double a[200], d[200];
            aqs_status st;
            assert_true(nv <= 200);
            solve_both(L, a, d, nv, &st);
            assert_int_equal(st, AQS_OK);
            assert_true(test_rel_diff(d, a, (size_t)nv) < 1e-11);
            aqs_linkage_destroy(L);
        }
}

/* The README's chain, straight, with N links (1 kg, 1 m, axes all z). */
static aqs_linkage *straight_chain(int32_t form, int32_t n)
{
    aqs_linkage *L = test_new_linkage();
    const double com[3] = {0.5, 0, 0}, I[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1}, g[3] = {0, -9.81, 0};
    int32_t i, prev = AQS_WORLD;
    assert_int_equal(aqs_linkage_set_dca_form(L, form), AQS_OK);
    for (i = 0; i < n; i++) {
        int32_t b;
        assert_int_equal(aqs_body_add(L, 1.0, com, I, &b), AQS_OK);
        test_add_joint(L, AQS_JOINT_REVOLUTE, prev, b, i ? 1.0 : 0.0, 0, 0, 0, 0, 1);
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    return L;
}

/* 20,000 straight links: the inverse-inertia form calls this numerically
 * singular (from 13,000 links on, docs/hardcases.md); the square-root form
 * solves it, exactly and adaptively. The ABA is good to 1e-15 here against
 * the __float128 reference; the square-root DCA measured 3.7e-16 at 10^5
 * links: 1e-13 is a margin of ~300. */
static void test_long_straight_chain(void **state)
{
    const int32_t n = 20000;
    aqs_linkage *L = straight_chain(AQS_DCA_FORM_SQRT, n);
    double *a = malloc(sizeof(double) * n), *d = malloc(sizeof(double) * n);
    aqs_solve_stats stats;
    aqs_status st;
    (void)state;
    assert_non_null(a);
    assert_non_null(d);
    solve_both(L, a, d, n, &st);
    assert_int_equal(st, AQS_OK);
    assert_true(test_rel_diff(d, a, (size_t)n) < 1e-13);
    /* adaptive: the bound holds against the ABA's answer */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    memset(&stats, 0, sizeof stats);
    stats.size = sizeof stats;
    assert_int_equal(aqs_linkage_get_stats(L, &stats), AQS_OK);
    assert_true(stats.computed_joints < n);
    assert_int_equal(aqs_linkage_get_accelerations(L, d, n), AQS_OK);
    {
        double worst = 0.0, top = 0.0;
        int32_t i;
        for (i = 0; i < n; i++) {
            if (fabs(a[i]) > top) top = fabs(a[i]);
            /* an uncomputed joint reads 0 */
            if (d[i] == 0.0 && fabs(a[i]) > worst) worst = fabs(a[i]);
        }
        assert_true(worst / top <= stats.error_bound * (1 + 1e-9) + 1e-13);
    }
    free(a);
    free(d);
    aqs_linkage_destroy(L);
}

/* A nearly straight planar chain (1,500 links, angles of 1e-6, a tip force,
 * no gravity): its out-of-plane rows are exact zeros up to subnormal
 * rounding, which once made a Householder reflection divide by an
 * underflowed 0 (NaN, then "numerically singular"; found by
 * tests/python/test_threads.py). Both the exact DCA (against the ABA, 1e-12:
 * ordinary data) and an adaptive solve at every eps must succeed. */
static void test_nearly_straight_chain(void **state)
{
    const int32_t n = 1500;
    aqs_linkage *L = straight_chain(AQS_DCA_FORM_SQRT, n);
    double *a = malloc(sizeof(double) * n), *d = malloc(sizeof(double) * n), zero[3] = {0, 0, 0};
    const double tip[3] = {0, 1.0, 0};
    uint64_t rng = 7;
    aqs_status st;
    int32_t i, k;
    (void)state;
    assert_non_null(a);
    assert_non_null(d);
    assert_int_equal(aqs_linkage_set_gravity(L, zero), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, n - 1, tip, NULL, NULL), AQS_OK);
    for (i = 0; i < n; i++) a[i] = test_uniform(&rng, -1e-6, 1e-6);
    assert_int_equal(aqs_linkage_set_positions(L, a, n), AQS_OK);
    solve_both(L, a, d, n, &st);
    assert_int_equal(st, AQS_OK);
    assert_true(test_rel_diff(d, a, (size_t)n) < 1e-12);
    for (k = 0; k < 20; k++) {
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -k)), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    }
    /* the sequence of the Python test: from q = 0, an exact step, then an adaptive solve */
    for (i = 0; i < n; i++) a[i] = 0.0;
    assert_int_equal(aqs_linkage_set_positions(L, a, n), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_ABA), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 1e-3), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    free(a);
    free(d);
    aqs_linkage_destroy(L);
}

/* A 6-link spatial chain whose third body is a 0.75 kg near point mass
 * (rotational inertia k I), and one with 20 links of 1e-9 kg behind 20 of
 * 1000 kg. Measured (docs/hardcases.md): square-root form 1.3e-11 at
 * k = 1e-12 and 2.3e-13 at mu = 1e-9 against the ABA's 1e-16; the
 * inverse-inertia form 1.3e-5 at k = 1e-12. The tolerances leave about two
 * orders of margin over the square-root form. */
/* A spatial chain of n revolute links (axes alternating z, y) with link i of
 * mass mass[i] and rotational inertia inertia[i] (3x3), random positions and a
 * tilted gravity: the square-root DCA against the ABA, relative 2-norm < tol. */
static void check_chain(int32_t n, const double *mass, const double *inertia, double tol, uint64_t *rng)
{
    const double com[3] = {0.5, 0, 0}, g[3] = {0.2, -9.81, 0.4};
    aqs_linkage *L = test_new_linkage();
    double q[40], a[40], d[40];
    int32_t i, prev = AQS_WORLD;
    aqs_status st;
    assert_true(n <= 40);
    for (i = 0; i < n; i++) {
        int32_t b;
        assert_int_equal(aqs_body_add(L, mass[i], com, inertia + 9 * i, &b), AQS_OK);
        test_add_joint(L, AQS_JOINT_REVOLUTE, prev, b, i ? 1.0 : 0.0, 0, 0, 0, i % 2 ? 1 : 0, i % 2 ? 0 : 1);
        prev = b;
        q[i] = test_uniform(rng, -1, 1);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, n), AQS_OK);
    solve_both(L, a, d, n, &st);
    assert_int_equal(st, AQS_OK);
    assert_true(test_rel_diff(d, a, (size_t)n) < tol);
    aqs_linkage_destroy(L);
}

static void test_small_inertias(void **state)
{
    double mass[40], inertia[9 * 40];
    uint64_t rng = 99;
    int32_t i;
    (void)state;
    memset(inertia, 0, sizeof inertia);
    for (i = 0; i < 6; i++) { /* body 2: 0.75 kg with inertia 1e-12 I */
        mass[i] = i == 2 ? 0.75 : 1.0;
        inertia[9 * i] = i == 2 ? 1e-12 : 0.01;
        inertia[9 * i + 4] = inertia[9 * i + 8] = i == 2 ? 1e-12 : 0.1;
    }
    check_chain(6, mass, inertia, 1e-9, &rng);
    for (i = 0; i < 40; i++) { /* 20 links of 1000 kg, then 20 of 1e-9 kg */
        mass[i] = i < 20 ? 1000.0 : 1e-9;
        inertia[9 * i] = 0.01 * mass[i];
        inertia[9 * i + 4] = inertia[9 * i + 8] = 0.1 * mass[i];
    }
    check_chain(40, mass, inertia, 1e-10, &rng);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_form_setting),
        cmocka_unit_test(test_forms_agree),
        cmocka_unit_test(test_long_straight_chain),
        cmocka_unit_test(test_small_inertias),
        cmocka_unit_test(test_nearly_straight_chain),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
