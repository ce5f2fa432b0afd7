/* test_assembly.c -- src/model/assembly.c: the assembly tree built by tree
 * contraction (MATH.md §10), through aqs_linkage_get_tree_stats: node
 * counts, height bounds for chains, handle bounds for chains and random
 * trees, star-shaped linkages (one body with many children), and linkages
 * with no moving joint at all. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define G 9.81

typedef struct {
    int32_t nodes, height, max_handles;
    double mean_handles;
} stats;

static stats get_stats(const aqs_linkage *L)
{
    stats s;
    assert_int_equal(aqs_linkage_get_tree_stats(L, &s.nodes, &s.height, &s.mean_handles, &s.max_handles), AQS_OK);
    return s;
}

/* A chain of n bodies on revolute joints (alternating axes), finalized. */
static aqs_linkage *chain(int n)
{
    aqs_linkage *L = test_new_linkage();
    int i;
    for (i = 0; i < n; i++) {
        test_add_body(L, 1.0, 0.5, 0, 0, 0.1);
        test_add_joint(L, AQS_JOINT_REVOLUTE, i - 1, i, i ? 1.0 : 0.0, 0, 0, 0, i % 2, 1 - i % 2);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    return L;
}

/* The height bound for a chain. The contraction sees a path of n = N + 1
 * clusters (the world and N bodies). In a round, ends are raked and pairs
 * of two-handle clusters compressed, each cluster in at most one merge, and
 * no edge of the path is left with both ends unmerged (an unmerged end
 * would have been raked, two unmerged inner clusters compressed): the
 * merges form a maximal matching, and each merge covers at most 3 of the
 * n - 1 edges, so a round removes at least ceil((n - 1) / 3) clusters. A
 * node made in round r merges clusters of earlier rounds, so its height is
 * at most r. Hence height <= R(N), the rounds of n <- n - ceil((n - 1) / 3)
 * from N + 1 down to 1; R(N) <= log_{3/2}(N) + 1 <= 2 log2(N) + 3. */
static int chain_height_bound(int N)
{
    long n = N + 1;
    int r = 0;
    while (n > 1) {
        n -= (n - 1 + 2) / 3;
        r++;
    }
    return r;
}

static void check_chain(int N)
{
    aqs_linkage *L = chain(N);
    stats s = get_stats(L);
    int lower = (int)ceil(log2((double)N + 1.0)); /* N + 1 leaves in a binary tree */
    assert_int_equal(s.nodes, 2 * N + 1);          /* N + 1 leaves + N joints */
    assert_true(s.height <= chain_height_bound(N));
    assert_true(s.height <= 2.0 * log2((double)N) + 3.0);
    assert_true(s.height >= lower);
    /* a path: every cluster has at most 2 handles, and the leaves inside
     * the chain have exactly 2 (1 when the chain is a single body) */
    assert_int_equal(s.max_handles, N == 1 ? 1 : 2);
    assert_true(s.mean_handles > 0.0 && s.mean_handles <= s.max_handles);
    aqs_linkage_destroy(L);
}

static void test_chains(void **state)
{
    static const int big[] = {333, 511, 512, 513, 777, 1000, 1023, 1024, 1025, 1500, 1999, 2000};
    int N;
    size_t i;
    (void)state;
    /* the bound itself, for small N worked by hand: N = 1: 2 -> 1 (1 round);
     * N = 2: 3 -> 2 -> 1; N = 4: 5 -> 3 -> 2 -> 1 */
    assert_int_equal(chain_height_bound(1), 1);
    assert_int_equal(chain_height_bound(2), 2);
    assert_int_equal(chain_height_bound(4), 3);
    for (N = 1; N <= 300; N++) check_chain(N);
    for (i = 0; i < sizeof big / sizeof big[0]; i++) check_chain(big[i]);
}

/* Random trees: parents uniform among earlier bodies (or biased to the last
 * few, for long branches), random joint types including fixed joints. The
 * tree has one leaf per rigid group plus the world and one node per moving
 * joint, and no cluster has more handles than the largest degree (moving
 * joints) of a rigid group or the world, or 2. */
static void test_random_trees(void **state)
{
    static const int types[] = {AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC, AQS_JOINT_SPHERICAL,
                                AQS_JOINT_FIXED,    AQS_JOINT_UNIVERSAL, AQS_JOINT_CYLINDRICAL,
                                AQS_JOINT_PLANAR,   AQS_JOINT_REVOLUTE};
    uint64_t seed = 31;
    int rep;
    (void)state;
    for (rep = 0; rep < 40; rep++) {
        int N = 2 + (int)test_uniform(&seed, 0, rep < 30 ? 60 : 1500);
        int32_t *parent = malloc(sizeof(int32_t) * (size_t)N), *type = malloc(sizeof(int32_t) * (size_t)N);
        int32_t *comp = malloc(sizeof(int32_t) * (size_t)N), *deg = calloc((size_t)N + 1, sizeof(int32_t));
        aqs_linkage *L = test_new_linkage();
        int i, ne = 0, maxdeg = 0, world = N;
        stats s;
        for (i = 0; i < N; i++) {
            double axis[3], pos[3], quat[4] = {1, 0, 0, 0};
            int k;
            if (i == 0) parent[i] = AQS_WORLD;
            else if (rep % 2) parent[i] = (int32_t)test_uniform(&seed, 0, i);
            else parent[i] = (int32_t)test_uniform(&seed, i > 4 ? i - 4 : 0, i);
            type[i] = types[(int)test_uniform(&seed, 0, 8)];
            if (i == 0 && rep % 3 == 0) type[i] = AQS_JOINT_FREE;
            test_add_body(L, test_uniform(&seed, 0.5, 2), 0.3, 0.1, 0, test_uniform(&seed, 0.05, 0.2));
            for (k = 0; k < 3; k++) {
                axis[k] = test_uniform(&seed, -1, 1);
                pos[k] = test_uniform(&seed, -1, 1);
            }
            assert_int_equal(aqs_joint_add(L, type[i], parent[i], i, pos, quat, axis, NULL), AQS_OK);
            /* rigid groups: a fixed joint puts the child in its parent's */
            comp[i] = type[i] != AQS_JOINT_FIXED ? i : parent[i] == AQS_WORLD ? world : comp[parent[i]];
            if (type[i] != AQS_JOINT_FIXED) {
                ne++;
                deg[comp[i]]++;
                deg[parent[i] == AQS_WORLD ? world : comp[parent[i]]]++;
            }
        }
        for (i = 0; i <= N; i++)
            if (deg[i] > maxdeg) maxdeg = deg[i];
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        s = get_stats(L);
        if (ne > 0) {
            assert_int_equal(s.nodes, 2 * ne + 1); /* (ne + 1) leaves + ne joints */
            assert_true(s.max_handles <= (maxdeg > 2 ? maxdeg : 2));
            assert_true(s.max_handles >= 1);
            assert_true(s.height >= (int)ceil(log2(ne + 1.0)));
            assert_true(s.height <= ne);
        }
        assert_int_equal(aqs_linkage_solve(L), AQS_OK);
        aqs_linkage_destroy(L);
        free(parent);
        free(type);
        free(comp);
        free(deg);
    }
}

/* A star: k pendulums of different lengths hang from one hub. Welded to the
 * world, the hub is part of the world, so each pendulum moves on its own:
 * qdd_i = -m_i g l_i cos(q_i) / (Izz_i + m_i l_i^2) (1e-12 relative, as in
 * test_dca). The world leaf has k handles. */
static void test_star_welded(void **state)
{
    const int k = 64;
    aqs_linkage *L = test_new_linkage();
    uint64_t seed = 32;
    double g[3] = {0, -G, 0}, *q = malloc(sizeof(double) * (size_t)k), *qdd = malloc(sizeof(double) * (size_t)k);
    double *m = malloc(sizeof(double) * (size_t)k), *len = malloc(sizeof(double) * (size_t)k), izz = 0.05;
    double hub[3] = {0, 0, 0}, hubI[9] = {0};
    int32_t h, i;
    stats s;
    (void)state;
    assert_int_equal(aqs_body_add(L, 0.0, hub, hubI, &h), AQS_OK); /* massless hub, welded */
    assert_int_equal(aqs_joint_add(L, AQS_JOINT_FIXED, AQS_WORLD, h, hub, (double[4]){1, 0, 0, 0}, NULL, NULL), AQS_OK);
    for (i = 0; i < k; i++) {
        double com[3], I[9] = {0.05, 0, 0, 0, 0.05, 0, 0, 0, 0.05};
        int32_t b;
        m[i] = test_uniform(&seed, 0.5, 2);
        len[i] = test_uniform(&seed, 0.2, 1.5);
        com[0] = len[i];
        com[1] = com[2] = 0;
        assert_int_equal(aqs_body_add(L, m[i], com, I, &b), AQS_OK);
        test_add_joint(L, AQS_JOINT_REVOLUTE, h, b, cos(i), sin(i), 0.01 * i, 0, 0, 1);
        q[i] = test_uniform(&seed, -3, 3);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    s = get_stats(L);
    assert_int_equal(s.nodes, 2 * k + 1);
    assert_int_equal(s.max_handles, k);
    /* every merge must contain the hub's cluster (leaves are not adjacent
     * to each other), so the tree is a caterpillar of height exactly k */
    assert_int_equal(s.height, k);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)k), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, (size_t)k), AQS_OK);
    for (i = 0; i < k; i++) {
        double expect = -m[i] * G * len[i] * cos(q[i]) / (izz + m[i] * len[i] * len[i]);
        assert_true(fabs(qdd[i] - expect) <= 1e-12 * fabs(expect) + 1e-14);
    }
    aqs_linkage_destroy(L);
    free(q);
    free(qdd);
    free(m);
    free(len);
}

/* A floating star: a hub on a free joint with k children on revolute,
 * prismatic and spherical joints, in gravity alone: free fall, so every
 * joint acceleration and constraint force is zero and the hub accelerates
 * by g (in its own frame, R^T g). Sums of O(k) terms of size O(10): 1e-11
 * absolute. */
static void test_star_floating(void **state)
{
    const int k = 40;
    aqs_linkage *L = test_new_linkage();
    uint64_t seed = 33;
    double g[3] = {0.5, -G, 1.5}, base[7] = {1, 2, 3, 0, 0, 0, 0}, Rg[3], R[9];
    double *qdd, *f;
    int32_t nv, nq, nb, nj, i;
    stats s;
    (void)state;
    test_add_body(L, 3.0, 0.1, 0.2, 0.3, 0.5);
    test_add_joint(L, AQS_JOINT_FREE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
    for (i = 0; i < k; i++) {
        int32_t b = test_add_body(L, test_uniform(&seed, 0.5, 2), 0.3, 0, 0, 0.05);
        int type = i % 3 == 0 ? AQS_JOINT_REVOLUTE : i % 3 == 1 ? AQS_JOINT_PRISMATIC : AQS_JOINT_SPHERICAL;
        test_add_joint(L, type, 0, b, cos(i), sin(i), 0.1, sin(2.0 * i), cos(3.0 * i), 1);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    s = get_stats(L);
    assert_int_equal(s.max_handles, k + 1); /* the hub: its free joint and k children */
    assert_int_equal(s.nodes, 2 * (k + 1) + 1);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, &nq, &nv), AQS_OK);
    test_random_quat(&seed, base + 3);
    assert_int_equal(aqs_joint_set_position(L, 0, base, 7), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    qdd = malloc(sizeof(double) * (size_t)nv);
    f = malloc(sizeof(double) * 6 * (size_t)nj);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, (size_t)nv), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 6 * (size_t)nj), AQS_OK);
    test_quat_matrix(base + 3, R);
    for (i = 0; i < 3; i++) Rg[i] = R[i] * g[0] + R[3 + i] * g[1] + R[6 + i] * g[2];
    for (i = 0; i < 3; i++) {
        assert_true(fabs(qdd[i]) < 1e-11);
        assert_true(fabs(qdd[3 + i] - Rg[i]) < 1e-11);
    }
    for (i = 6; i < nv; i++) assert_true(fabs(qdd[i]) < 1e-11);
    for (i = 0; i < 6 * nj; i++) assert_true(fabs(f[i]) < 1e-11);
    free(qdd);
    free(f);
    aqs_linkage_destroy(L);
}

/* Every body welded to the world: nothing moves (nq = nv = 0), the tree is
 * empty, and solve gives each fixed joint the force that holds its subtree
 * against gravity and the applied loads: in the child frame (all frames
 * here are parallel to the world's), f = sum over the subtree of
 * [c_i x (-m_i g) - r x F; -m_i g - F], moments about the child origin. */
static void test_all_welded(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double g[3] = {0.2, -G, 0.4}, F[3] = {1.0, 2.0, -0.5}, P[3] = {0.1, 0.2, 0.3};
    double f[18], dummy[1], world_pos[3][3] = {{1, 0, 0}, {1, 0.5, 0}, {1, 0.5, 0.7}};
    double com[3][3] = {{0.1, 0, 0}, {0, 0.2, 0}, {0, 0, 0.3}}, mass[3] = {1.0, 2.0, 0.5};
    int32_t nq, nv, b, j;
    stats s;
    (void)state;
    for (b = 0; b < 3; b++) {
        double I[9] = {0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
        assert_int_equal(aqs_body_add(L, mass[b], com[b], I, NULL), AQS_OK);
    }
    test_add_joint(L, AQS_JOINT_FIXED, AQS_WORLD, 0, 1, 0, 0, 0, 0, 1);
    test_add_joint(L, AQS_JOINT_FIXED, 0, 1, 0, 0.5, 0, 0, 0, 1);
    test_add_joint(L, AQS_JOINT_FIXED, 1, 2, 0, 0, 0.7, 0, 0, 1);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, &nv), AQS_OK);
    assert_int_equal(nq, 0);
    assert_int_equal(nv, 0);
    s = get_stats(L);
    assert_true(s.nodes <= 1 && s.height == 0 && s.max_handles == 0);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, 2, F, P, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, dummy, 0), AQS_OK);
    assert_int_equal(aqs_linkage_get_constraint_forces(L, f, 18), AQS_OK);
    for (j = 0; j < 3; j++) {
        double expect[6] = {0, 0, 0, 0, 0, 0};
        for (b = j; b < 3; b++) {
            double r[3], w[3];
            int i;
            /* body b's com relative to joint j's child origin */
            for (i = 0; i < 3; i++) {
                r[i] = world_pos[b][i] + com[b][i] - world_pos[j][i];
                w[i] = -mass[b] * g[i];
            }
            expect[0] += r[1] * w[2] - r[2] * w[1];
            expect[1] += r[2] * w[0] - r[0] * w[2];
            expect[2] += r[0] * w[1] - r[1] * w[0];
            for (i = 0; i < 3; i++) expect[3 + i] += w[i];
        }
        {
            /* the applied force on body 2 at P, held by every joint above it */
            double r[3];
            int i;
            for (i = 0; i < 3; i++) r[i] = world_pos[2][i] + P[i] - world_pos[j][i];
            expect[0] -= r[1] * F[2] - r[2] * F[1];
            expect[1] -= r[2] * F[0] - r[0] * F[2];
            expect[2] -= r[0] * F[1] - r[1] * F[0];
            for (i = 0; i < 3; i++) expect[3 + i] -= F[i];
        }
        /* O(10) values from a handful of operations: 1e-12 */
        assert_true(test_max_abs_diff(f + 6 * j, expect, 6) < 1e-12);
    }
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chains),
        cmocka_unit_test(test_random_trees),
        cmocka_unit_test(test_star_welded),
        cmocka_unit_test(test_star_floating),
        cmocka_unit_test(test_all_welded),
    };
    return cmocka_run_group_tests_name("assembly", tests, NULL, NULL);
}
