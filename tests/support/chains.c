/* chains.c -- the hard-case suite's chains for the tests (chains.h). */
#include "chains.h"

#include <stdlib.h>

aqs_linkage *test_zy_chain(counting_state *cs, int32_t n, const double *m, int weld, const double *q,
                           const double g[3])
{
    aqs_linkage *L = test_new_linkage_in(cs);
    const double com[3] = {0.5, 0.0, 0.0}, quat[4] = {1, 0, 0, 0};
    const double az[3] = {0, 0, 1}, ay[3] = {0, 1, 0};
    int32_t prev = AQS_WORLD, i, b;
    for (i = 0; i < n; i++) {
        const double I[9] = {0.01 * m[i], 0, 0, 0, 0.1 * m[i], 0, 0, 0, 0.1 * m[i]};
        const double pos[3] = {i ? 1.0 : 0.0, 0, 0};
        assert_int_equal(aqs_body_add(L, m[i], com, I, &b), AQS_OK);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, prev, b, pos, quat, i % 2 ? ay : az, NULL), AQS_OK);
        if (weld && i % 3 == 0) {
            const double I2[9] = {0.01, 0, 0, 0, 0.02, 0, 0, 0, 0.03}, wpos[3] = {0.3, 0.1, 0};
            int32_t w;
            assert_int_equal(aqs_body_add(L, 0.3, com, I2, &w), AQS_OK);
            assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, b, w, wpos, quat, NULL, NULL), AQS_OK);
        }
        prev = b;
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)n), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    return L;
}

aqs_linkage *test_altmass_chain(counting_state *cs, int32_t n, double ratio, int weld, uint64_t seed)
{
    const double g[3] = {9.81, 0, 0};
    double *m = malloc(sizeof(double) * (size_t)n), *q = malloc(sizeof(double) * (size_t)n);
    aqs_linkage *L;
    int32_t i;
    assert_true(m && q);
    for (i = 0; i < n; i++) {
        m[i] = i % 2 ? ratio : 1.0;
        q[i] = test_uniform(&seed, -0.5, 0.5);
    }
    L = test_zy_chain(cs, n, m, weld, q, g);
    free(m), free(q);
    return L;
}
