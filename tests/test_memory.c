/* test_memory.c -- aqs_linkage_get_memory against an independent count: a
 * byte-counting allocator installed with aqs_linkage_create_with_allocator
 * sees every request, so at every phase (empty, built, finalized, solved
 * exactly, with a tolerance, a world measure, shapes, names) the library's
 * bytes, blocks and peak must equal the allocator's, and its categories must
 * add up to the bytes; which categories are empty or grow follows from the
 * phases (docs/api.md, "Memory"). Bad arguments fail with a message and
 * write nothing. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Bytes and blocks the allocator handed out and has not got back. */
typedef struct {
    size_t now, peak, blocks;
} byte_counter;

typedef union {
    size_t size;
    long double align;
} prefix;

static void *byte_alloc(void *user, size_t size)
{
    byte_counter *c = user;
    prefix *p = malloc(sizeof(prefix) + size);
    if (!p) return NULL;
    p->size = size;
    c->now += size;
    c->blocks++;
    if (c->now > c->peak) c->peak = c->now;
    return p + 1;
}

static void byte_free(void *user, void *ptr)
{
    byte_counter *c = user;
    prefix *p = (prefix *)ptr - 1;
    c->now -= p->size;
    c->blocks--;
    free(p);
}

static aqs_memory_stats memory(const aqs_linkage *L)
{
    aqs_memory_stats m;
    memset(&m, 0xAB, sizeof m);
    m.size = sizeof m;
    assert_int_equal(aqs_linkage_get_memory(L, &m), AQS_OK);
    assert_int_equal(m.size, sizeof m);
    return m;
}

/* The library's count is the allocator's, and the categories add up. */
static aqs_memory_stats check(const aqs_linkage *L, const byte_counter *c)
{
    aqs_memory_stats m = memory(L);
    assert_int_equal(m.bytes, c->now);
    assert_int_equal(m.blocks, c->blocks);
    assert_int_equal(m.peak, c->peak);
    assert_int_equal(m.model + m.tree + m.exact + m.dca + m.factors + m.world + m.collision, m.bytes);
    return m;
}

/* A branched tree of n bodies: body i hangs from (i - 1) / 2 by a revolute
 * joint (a binary tree, every node a few handles). */
static void build(aqs_linkage *L, int32_t n)
{
    int32_t i;
    for (i = 0; i < n; i++) {
        test_add_body(L, 1.0 + 0.01 * i, 0.2, 0.0, 0.0, 0.05);
        test_add_joint(L, AQS_JOINT_REVOLUTE, i == 0 ? AQS_WORLD : (i - 1) / 2, i, 0.4, 0.1 * (i % 3), 0.0,
                       i % 2 ? 0.0 : 1.0, i % 2 ? 1.0 : 0.0, 0.0);
    }
}

static void test_counts_match_allocator(void **state)
{
    byte_counter c = {0, 0, 0};
    aqs_linkage *L = NULL;
    aqs_memory_stats m0, m1, m2, m3, m4, m5;
    const double f[3] = {0.0, 0.0, 1.0}, g[3] = {0.0, -9.81, 0.0};
    const double size[3] = {0.1, 0.1, 0.1}, pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0};
    int32_t i;
    (void)state;
    assert_int_equal(aqs_linkage_create_with_allocator(byte_alloc, byte_free, &c, &L), AQS_OK);
    m0 = check(L, &c); /* the handle alone */
    assert_int_equal(m0.blocks, 1);
    assert_true(m0.model == m0.bytes && m0.bytes > 0);
    build(L, 200);
    m1 = check(L, &c);
    assert_true(m1.model > m0.model);
    assert_true(m1.tree == 0 && m1.exact == 0 && m1.dca == 0 && m1.factors == 0 && m1.world == 0 &&
                m1.collision == 0);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, 150, f, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    m2 = check(L, &c);
    /* finalize built the tree and the exact solver, not the DCA's storage */
    assert_true(m2.tree > 0 && m2.exact > 0);
    assert_true(m2.dca == 0 && m2.factors == 0 && m2.world == 0 && m2.collision == 0);
    /* finalize's scratch was released: the peak is above what is held */
    assert_true(m2.peak > m2.bytes);
    for (i = 0; i < 3; i++) assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_int_equal(check(L, &c).bytes, m2.bytes); /* steps allocate nothing */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, ldexp(1.0, -19)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    m3 = check(L, &c);
    /* the tolerance brought the DCA coefficients and the factors, and the
     * tree's poses; the model and the exact solver are as they were */
    assert_true(m3.dca > 0 && m3.factors > 0 && m3.tree > m2.tree);
    assert_int_equal(m3.model, m2.model);
    assert_int_equal(m3.exact, m2.exact);
    for (i = 0; i < 3; i++) assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(check(L, &c).bytes, m3.bytes); /* kept for the next tolerance, not grown */
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_WORLD, ldexp(1.0, -10)), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    m4 = check(L, &c);
    assert_true(m4.world > 0);
    /* the world measure reads the composites' inverse inertias (dca): one block of
     * ncomp + 1 = 201 6 x 6 matrices, the square-root form had not needed them */
    assert_int_equal(m4.dca - m3.dca, 201 * 36 * sizeof(double) + 16); /* and its header */
    assert_int_equal(m4.factors, m3.factors);
    assert_int_equal(aqs_shape_add(L, 10, AQS_SHAPE_BOX, size, pos, quat, NULL), AQS_OK);
    assert_int_equal(aqs_shape_add(L, 11, AQS_SHAPE_SPHERE, size, pos, quat, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_any_contact(L, &i), AQS_OK);
    assert_int_equal(aqs_body_set_name(L, 3, "a body with a name"), AQS_OK);
    m5 = check(L, &c);
    assert_true(m5.collision > 0 && m5.model > m4.model);
    assert_true(m5.peak >= m5.bytes && m5.peak >= m4.peak);
    aqs_linkage_destroy(L);
    assert_int_equal(c.now, 0);
    assert_int_equal(c.blocks, 0);
}

/* A failed allocation counts nothing: the figures stay the allocator's. */
typedef struct {
    byte_counter c;
    int fail;
} failing;

static void *failing_alloc(void *user, size_t size)
{
    failing *f = user;
    return f->fail ? NULL : byte_alloc(&f->c, size);
}

static void failing_free(void *user, void *ptr)
{
    byte_free(&((failing *)user)->c, ptr);
}

/* Collision settings on a linkage without shapes hold the settings only (a
 * few hundred bytes under collision), not the assembly tree's poses: until
 * 2026-12-05 the first filter made every later move recompute and keep them
 * (about 1.5 KB per joint under tree), as a shape does. Twins, one with a
 * world filter and collide_joined set before building, finalized and moved
 * the same way: the same tree bytes; the first shape then adds the poses. */
static void test_settings_without_shapes(void **state)
{
    aqs_linkage *A = test_new_linkage(), *B = test_new_linkage();
    const double size[3] = {0.1, 0.0, 0.0}, pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0};
    aqs_memory_stats ma, mb;
    double q[40];
    int32_t i;
    (void)state;
    assert_int_equal(aqs_body_set_collision_filter(B, AQS_WORLD, 2, 2), AQS_OK);
    assert_int_equal(aqs_linkage_set_collide_joined(B, 1), AQS_OK);
    build(A, 40);
    build(B, 40);
    assert_int_equal(aqs_linkage_finalize(A), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(B), AQS_OK);
    for (i = 0; i < 40; i++) q[i] = 0.01 * i;
    assert_int_equal(aqs_linkage_set_positions(A, q, 40), AQS_OK);
    assert_int_equal(aqs_linkage_set_positions(B, q, 40), AQS_OK);
    assert_int_equal(aqs_linkage_solve(A), AQS_OK);
    assert_int_equal(aqs_linkage_solve(B), AQS_OK);
    ma = memory(A);
    mb = memory(B);
    assert_int_equal(mb.tree, ma.tree);
    assert_int_equal(ma.collision, 0);
    assert_true(mb.collision > 0 && mb.collision < 1024);
    assert_int_equal(aqs_shape_add(B, 3, AQS_SHAPE_SPHERE, size, pos, quat, NULL), AQS_OK);
    mb = memory(B);
    assert_true(mb.tree > ma.tree); /* the poses, now that a shape follows the moves */
    aqs_linkage_destroy(A);
    aqs_linkage_destroy(B);
}

static void test_failed_allocation_counts_nothing(void **state)
{
    failing F;
    aqs_linkage *L = NULL;
    aqs_memory_stats before, after;
    (void)state;
    memset(&F, 0, sizeof F);
    assert_int_equal(aqs_linkage_create_with_allocator(failing_alloc, failing_free, &F, &L), AQS_OK);
    build(L, 50);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    before = check(L, &F.c);
    F.fail = 1;
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_ENOMEM);
    after = check(L, &F.c);
    assert_int_equal(after.bytes, before.bytes);
    assert_int_equal(after.dca, 0);
    assert_int_equal(after.factors, 0);
    F.fail = 0;
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1e-3), AQS_OK);
    assert_true(check(L, &F.c).factors > 0);
    aqs_linkage_destroy(L);
    assert_int_equal(F.c.now, 0);
}

static void test_bad_arguments(void **state)
{
    aqs_linkage *L = NULL;
    aqs_memory_stats m;
    struct {
        uint32_t size, blocks;
        uint64_t bytes;
    } small;
    (void)state;
    assert_int_equal(aqs_linkage_create(&L), AQS_OK);
    memset(&m, 0, sizeof m);
    m.size = sizeof m;
    assert_int_equal(aqs_linkage_get_memory(NULL, &m), AQS_EINVAL);
    assert_int_equal(aqs_linkage_get_memory(L, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_get_memory: stats is NULL");
    memset(&m, 0x5A, sizeof m);
    m.size = 4;
    assert_int_equal(aqs_linkage_get_memory(L, &m), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "stats->size = 4");
    assert_int_equal(m.blocks, 0x5A5A5A5Au); /* nothing written */
    /* an older, shorter struct: only what its size covers is written */
    memset(&small, 0x5A, sizeof small);
    small.size = 8;
    assert_int_equal(aqs_linkage_get_memory(L, (aqs_memory_stats *)(void *)&small), AQS_OK);
    assert_int_equal(small.size, 8);
    assert_int_equal(small.blocks, 1);
    assert_true(small.bytes == 0x5A5A5A5A5A5A5A5Aull);
    aqs_linkage_destroy(L);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counts_match_allocator),
        cmocka_unit_test(test_settings_without_shapes),
        cmocka_unit_test(test_failed_allocation_counts_nothing),
        cmocka_unit_test(test_bad_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
