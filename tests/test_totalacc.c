/* test_totalacc.c -- Lemma 1 in square-root form: at the forces of an exact
 * solve, every node's A(C) = ||T_C [x; 1]||^2 equals the sum of
 * ||qdd_j||^2 over the counted joints inside C, computed from the exact
 * accelerations; T_C is upper trapezoidal; free joints do not count. */
#include "testutil.h"
#include "factor.h"

#include <math.h>
#include <stdlib.h>

#include "linkage.h"
#include "totalacc.h"

/* Sum of ||qdd_j||^2 over the principal joints of n's subtree (free joints
 * excluded), recursively. */
static double subtree_sum(const aqs_linkage *L, int32_t n)
{
    const node *nd = &L->t.nodes[n];
    const joint_def *jd;
    double s = 0;
    int k;
    if (nd->joint < 0) return 0.0;
    jd = &L->joints[L->m.eff_joint[nd->joint]];
    if (jd->type != AQS_JOINT_FREE)
        for (k = 0; k < joint_nv(jd->type); k++) s += L->qdd[jd->voff + k] * L->qdd[jd->voff + k];
    return s + subtree_sum(L, nd->a) + subtree_sum(L, nd->b);
}

static aqs_linkage *random_tree(uint64_t *rng, int32_t n, int floating)
{
    static const int32_t kinds[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,
                                    AQS_JOINT_UNIVERSAL, AQS_JOINT_PLANAR, AQS_JOINT_FIXED};
    aqs_linkage *L = NULL;
    int32_t i;
    double g[3] = {0, -9.81, 0};
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    for (i = 0; i < n; i++) test_add_body(L, test_uniform(rng, 0.5, 2), test_uniform(rng, -.3, .3), 0.1, 0, 0.1);
    for (i = 0; i < n; i++) {
        int32_t parent = i ? (int32_t)test_uniform(rng, 0, i) : AQS_WORLD;
        int32_t type = i ? kinds[(int)test_uniform(rng, 0, 6)] : (floating ? AQS_JOINT_FREE : AQS_JOINT_REVOLUTE);
        test_add_joint(L, type, parent, i, test_uniform(rng, -1, 1), test_uniform(rng, -1, 1), 0.2,
                       test_uniform(rng, -1, 1), 1, test_uniform(rng, -1, 1));
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    for (i = 0; i < 5; i++) {
        double f[3] = {test_uniform(rng, -3, 3), test_uniform(rng, -3, 3), test_uniform(rng, -3, 3)};
        assert_int_equal(aqs_body_set_force(L, (int32_t)test_uniform(rng, 0, n), f, NULL, NULL), AQS_OK);
    }
    return L;
}

static void test_lemma1_square_root_form(void **state)
{
    uint64_t rng = 3;
    int c;
    double worst = 0;
    (void)state;
    for (c = 0; c < 60; c++) {
        aqs_linkage *L = random_tree(&rng, 2 + c * 2, c % 3 == 0);
        int32_t n;
        /* enable the factors, then an exact solve by the DCA fills every
         * node's x (the articulated-body solver does not touch the tree) */
        assert_int_equal(aqs_linkage_set_exact_solver(L, AQS_EXACT_DCA), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_LINKAGE, 1.0), AQS_OK);
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_ABS_LINKAGE, 0.0), AQS_OK);
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        for (n = 0; n < L->t.nnodes; n++) {
            const node *nd = &L->t.nodes[n];
            double a, ref, rel;
            int32_t r, cols = 6 * nd->nh + 1, j;
            double *full;
            if (nd->joint < 0) continue;
            full = calloc((size_t)cols * (size_t)cols, sizeof(double));
            assert_non_null(full);
            a = totalacc_eval(L, n);
            ref = subtree_sum(L, n);
            /* both sides carry rounding of order u * cond of the node; these
             * trees are well conditioned: 1e-9 relative to the root's A */
            rel = fabs(a - ref) / (subtree_sum(L, L->t.root) + 1e-300);
            if (rel > worst) worst = rel;
            assert_true(rel < 1e-9);
            assert_true(a >= 0.0);
            assert_true(L->t.tf[n].trows <= cols);
            /* upper triangular with rows missing: row r starts at column
             * pos[r] >= r, strictly increasing, zeros left of it */
            test_unpack_factor(L, n, full);
            for (r = 0; r < L->t.tf[n].trows; r++) {
                const int32_t *pos = L->t.trowpos + L->t.tf[n].tpos;
                assert_true(pos[r] >= r && pos[r] < cols && (r == 0 || pos[r] > pos[r - 1]));
                for (j = 0; j < pos[r]; j++) assert_true(full[(int64_t)r * cols + j] == 0.0);
            }
            /* the packed rows evaluate as the full ones: A = ||T_full z||^2 */
            {
                const int32_t *perm = L->t.tperm + nd->handles;
                const double *x = L->t.data + nd_xf(nd);
                double sum = 0;
                for (r = 0; r < L->t.tf[n].trows; r++) {
                    double v = full[(int64_t)r * cols + cols - 1];
                    int32_t q, k;
                    for (q = 0; q < nd->nh; q++)
                        for (k = 0; k < 6; k++) v += full[(int64_t)r * cols + 6 * q + k] * x[6 * perm[q] + k];
                    sum += v * v;
                }
                assert_true(fabs(sum - a) <= 1e-12 * (a + 1e-300) + 1e-300);
            }
            free(full);
        }
        aqs_linkage_destroy(L);
    }
    print_message("A(node) vs sum of squared accelerations: worst %.3g of A(root)\n", worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_lemma1_square_root_form)};
    return cmocka_run_group_tests_name("totalacc", tests, NULL, NULL);
}
