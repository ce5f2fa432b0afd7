/* randtree.c -- random linkages for the tests (randtree.h). */
#include "randtree.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void random_quat(uint64_t *rng, const test_tree_spec *sp, double q[4])
{
    double n = 0;
    int i;
    if (sp->uniform_quat) {
        test_random_quat(rng, q);
        return;
    }
    for (i = 0; i < 4; i++) {
        q[i] = test_uniform(rng, -1, 1);
        n += q[i] * q[i];
    }
    n = sqrt(n);
    for (i = 0; i < 4; i++) q[i] /= n;
}

aqs_linkage *test_random_tree(uint64_t *rng, const test_tree_spec *sp)
{
    aqs_linkage *L = NULL;
    int32_t i, j;
    static const int32_t kinds[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,
                                    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL, AQS_JOINT_PLANAR,
                                    AQS_JOINT_FIXED, AQS_JOINT_REVOLUTE, AQS_JOINT_REVOLUTE};
    const double reach = sp->reach > 0.0 ? sp->reach : 0.8;
    double branch = test_uniform(rng, 0, 1);
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
    for (i = 0; i < sp->nbodies; i++) {
        double m = exp(test_uniform(rng, -log(sp->mass_spread), log(sp->mass_spread)));
        double com[3], I[9] = {0}, a = test_uniform(rng, 0.5, 1.5), b = test_uniform(rng, 0.5, 1.5);
        for (j = 0; j < 3; j++) com[j] = test_uniform(rng, -0.3, 0.3);
        /* principal moments obeying the triangle inequality: (a, b, in [|a-b|, a+b]) */
        I[0] = 0.1 * m * a;
        I[4] = 0.1 * m * b;
        I[8] = 0.1 * m * test_uniform(rng, fabs(a - b) + 0.05, a + b);
        assert_int_equal(aqs_body_add(L, m, com, I, NULL), AQS_OK);
    }
    for (i = 0; i < sp->nbodies; i++) {
        int32_t type, parent;
        double pos[3], quat[4], axis[3];
        for (j = 0; j < 3; j++) {
            pos[j] = test_uniform(rng, -reach, reach);
            axis[j] = test_uniform(rng, -1, 1);
        }
        random_quat(rng, sp, quat);
        if (i == 0) {
            parent = AQS_WORLD;
            type = sp->floating ? AQS_JOINT_FREE : AQS_JOINT_REVOLUTE;
        } else {
            int32_t lo = (int32_t)(i - 1 - branch * branch * i);
            parent = lo + (int32_t)test_uniform(rng, 0, i - lo);
            if (parent > i - 1 || sp->chain) parent = i - 1;
            if (sp->revolute_only)
                type = sp->some_prismatic && i % 5 == 2 ? AQS_JOINT_PRISMATIC : AQS_JOINT_REVOLUTE;
            else
                type = kinds[(int)test_uniform(rng, 0, sizeof kinds / sizeof kinds[0])];
        }
        assert_int_equal(aqs_joint_add(L, type, parent, i, pos, quat, axis, NULL), AQS_OK);
    }
    if (aqs_linkage_finalize(L) != AQS_OK) fail_msg("finalize: %s", aqs_linkage_last_error(L));
    {
        int32_t nq, nj;
        double *q;
        assert_int_equal(aqs_linkage_get_sizes(L, NULL, &nj, &nq, NULL), AQS_OK);
        q = malloc(sizeof(double) * (size_t)(nq + 1));
        assert_non_null(q);
        assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
        for (j = 0; j < nj; j++) {
            int32_t off, n, k;
            assert_int_equal(aqs_joint_get_layout(L, j, &off, &n, NULL, NULL), AQS_OK);
            if (n == 4) random_quat(rng, sp, q + off);
            else if (n == 7) {
                for (k = 0; k < 3; k++) q[off + k] = test_uniform(rng, -1, 1);
                random_quat(rng, sp, q + off + 3);
            } else {
                for (k = 0; k < n; k++) q[off + k] = test_uniform(rng, -1.5, 1.5);
            }
        }
        assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
        free(q);
    }
    if (sp->gravity) {
        double g[3] = {test_uniform(rng, -2, 2), -9.81, test_uniform(rng, -2, 2)};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    }
    for (i = 0; i < sp->nforces; i++) {
        double f[3], p[3], tq[3];
        for (j = 0; j < 3; j++) {
            f[j] = test_uniform(rng, -5, 5);
            p[j] = test_uniform(rng, -0.5, 0.5);
            tq[j] = test_uniform(rng, -1, 1);
        }
        assert_int_equal(aqs_body_set_force(L, (int32_t)test_uniform(rng, 0, sp->nbodies), f, p, tq), AQS_OK);
    }
    return L;
}

aqs_linkage *test_mixed_tree(uint64_t *rng, int32_t nbodies, int floating, int nforces, double mass_spread)
{
    test_tree_spec sp;
    memset(&sp, 0, sizeof sp);
    sp.nbodies = nbodies;
    sp.floating = floating;
    sp.gravity = 1;
    sp.nforces = nforces;
    sp.mass_spread = mass_spread;
    return test_random_tree(rng, &sp);
}
