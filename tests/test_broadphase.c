/* test_broadphase.c -- the tree query (lazy and full) against brute force.
 *
 * Random linkages of 60, 400 and 2,000 bodies (revolute, prismatic,
 * spherical, universal, fixed and free joints; 0 to 2 random shapes per body
 * of every type; a few obstacles; random collision groups, masks and pair
 * exclusions) are stepped 200 times by random adaptive and exact steps,
 * with occasional position resets. After each step:
 *  - the lazy tree query, the full tree query and the library's brute-force
 *    all-pairs query must return exactly the same shape pairs, with depths,
 *    normals and points equal to 1e-9 (they place the shapes by the same
 *    operations, so they agree to rounding; any refit or skip bug shows up
 *    as a missing or extra pair);
 *  - on the smallest linkage, an independent brute force written here
 *    (world poses from aqs_linkage_get_body_poses_world, filters re-derived
 *    from the model: same rigid group, joined bodies, groups and masks,
 *    exclusions; libccd on every pair) must find the same pairs (a pair
 *    shallower than 1e-9 may be missing on one side: the poses differ by
 *    rounding), and the same depths to 1e-5 for sphere and capsule pairs
 *    (MPR's estimate moves by up to ~1e-6 under rounding-level changes of
 *    deep off-centre overlaps, and jumps between face planes for polytopes,
 *    so polytope depths are compared only in the bitwise-placed comparisons
 *    above and in test_narrowphase.c).
 * On the 2,000-body linkage the brute-force comparison runs every 20th
 * step (its cost is quadratic); lazy against full runs every step.
 * lazy_persistent() (below) does the same with the lazy caches carried
 * across moves: two identical copies, lazy queries only on one, full and
 * brute force only on the other; it also checks what the lazy query refits
 * after adaptive and exact steps and single-joint moves. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "collide.h"
#include "linkage.h"
#include "narrowphase.h"

#define MAXSH 3

typedef struct {
    int32_t n;           /* bodies */
    int32_t *parent;     /* per body: parent body or AQS_WORLD */
    int32_t *jtype;      /* per body: its joint's type */
    int32_t *comp;       /* per body: the body its rigid group is named by (-1: the world) */
    int32_t nshapes;
    shape_def *shapes;   /* as the test sees them (body, type, size, local pose, pts) */
    double *hullpts;
    uint32_t *group, *mask;
    int32_t *excl;       /* pairs (a, b) */
    int32_t nexcl;
    int joined;
} scene;

static const double hull_pts[] = {0.3, 0, 0, -0.2, 0.25, 0, -0.2, -0.25, 0.1, 0, 0, 0.35, 0.05, 0.05, -0.3};

static aqs_linkage *build(scene *S, int32_t n, uint64_t seed, int joined)
{
    uint64_t st = seed;
    aqs_linkage *L = test_new_linkage();
    int32_t b, k;
    S->n = n;
    S->parent = calloc((size_t)n, sizeof(int32_t));
    S->jtype = calloc((size_t)n, sizeof(int32_t));
    S->comp = calloc((size_t)n, sizeof(int32_t));
    S->shapes = calloc((size_t)n * MAXSH + 8, sizeof(shape_def));
    S->group = calloc((size_t)n, sizeof(uint32_t));
    S->mask = calloc((size_t)n, sizeof(uint32_t));
    S->excl = calloc((size_t)n * 2, sizeof(int32_t));
    S->nshapes = 0;
    S->nexcl = 0;
    S->joined = joined;
    assert_int_equal(aqs_linkage_set_inertia_check(L, 0), AQS_OK);
    for (b = 0; b < n; b++) {
        double pos[3], q[4], ax[3];
        int32_t t, p;
        double u = test_uniform(&st, 0, 1);
        test_add_body(L, 1.0, 0.1, 0, 0, 0.1);
        p = b < 3 ? AQS_WORLD : (int32_t)(test_uniform(&st, 0, 1) * b);
        if (b > 3 && test_uniform(&st, 0, 1) < 0.7) p = b - 1; /* mostly chains */
        if (p == AQS_WORLD) t = b == 2 ? AQS_JOINT_FREE : AQS_JOINT_REVOLUTE;
        else if (u < 0.45) t = AQS_JOINT_REVOLUTE;
        else if (u < 0.6) t = AQS_JOINT_SPHERICAL;
        else if (u < 0.72) t = AQS_JOINT_UNIVERSAL;
        else if (u < 0.84) t = AQS_JOINT_PRISMATIC;
        else t = AQS_JOINT_FIXED;
        for (k = 0; k < 3; k++) pos[k] = test_uniform(&st, -0.8, 0.8);
        if (p == AQS_WORLD) pos[0] = 4.0 * b;
        test_random_quat(&st, q);
        for (k = 0; k < 3; k++) ax[k] = test_uniform(&st, -1, 1);
        assert_int_equal(aqs_joint_add(L, t, p, b, pos, q, ax, NULL), AQS_OK);
        S->parent[b] = p;
        S->jtype[b] = t;
        S->comp[b] = t == AQS_JOINT_FIXED ? S->comp[p] : b;
        /* shapes */
        for (k = (int32_t)(test_uniform(&st, 0, 1) * 2.4); k > 0; k--) {
            shape_def *s = &S->shapes[S->nshapes];
            double sz[3], sp[3], sq[4];
            int32_t type = (int32_t)(test_uniform(&st, 0, 1) * 5), id, j;
            for (j = 0; j < 3; j++) {
                sz[j] = test_uniform(&st, 0.05, 0.25);
                sp[j] = test_uniform(&st, -0.3, 0.3);
            }
            test_random_quat(&st, sq);
            if (type == AQS_SHAPE_HULL)
                assert_int_equal(aqs_shape_add_hull(L, b, hull_pts, 5, sp, sq, &id), AQS_OK);
            else
                assert_int_equal(aqs_shape_add(L, b, type, sz, sp, sq, &id), AQS_OK);
            assert_int_equal(id, S->nshapes);
            memset(s, 0, sizeof *s);
            s->type = type;
            s->body = b;
            memcpy(s->size, sz, sizeof sz);
            if (type == AQS_SHAPE_HULL) {
                s->pts = (double *)hull_pts;
                s->npts = 5;
            }
            test_quat_matrix(sq, s->local.R);
            memcpy(s->local.p, sp, sizeof sp);
            shape_bound(s);
            S->nshapes++;
        }
        S->group[b] = 1u;
        S->mask[b] = 0xFFFFFFFFu;
        if (test_uniform(&st, 0, 1) < 0.1) {
            S->group[b] = 1u << (int)(test_uniform(&st, 0, 1) * 3);
            S->mask[b] = (uint32_t)(test_uniform(&st, 0, 1) * 8);
            assert_int_equal(aqs_body_set_collision_filter(L, b, S->group[b], S->mask[b]), AQS_OK);
        }
        if (b > 0 && test_uniform(&st, 0, 1) < 0.05) {
            int32_t o = (int32_t)(test_uniform(&st, 0, 1) * b);
            S->excl[2 * S->nexcl] = o;
            S->excl[2 * S->nexcl + 1] = b;
            S->nexcl++;
            assert_int_equal(aqs_collision_exclude_pair(L, b, o), AQS_OK);
        }
    }
    /* Obstacles: a few boxes and spheres along the bases. */
    for (k = 0; k < 6; k++) {
        shape_def *s = &S->shapes[S->nshapes];
        double sz[3] = {1.0, 0.3, 1.5}, sp[3] = {2.0 * k, -0.8, 0.0}, sq[4] = {1, 0, 0, 0};
        int32_t type = k % 2 ? AQS_SHAPE_SPHERE : AQS_SHAPE_BOX;
        assert_int_equal(aqs_shape_add(L, AQS_WORLD, type, sz, sp, sq, NULL), AQS_OK);
        memset(s, 0, sizeof *s);
        s->type = type;
        s->body = AQS_WORLD;
        memcpy(s->size, sz, sizeof sz);
        test_quat_matrix(sq, s->local.R);
        memcpy(s->local.p, sp, sizeof sp);
        shape_bound(s);
        S->nshapes++;
    }
    assert_int_equal(aqs_linkage_set_collide_joined(L, joined), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    {
        double g[3] = {0, -9.81, 0};
        assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    }
    for (b = 0; b < n; b += 7) {
        double f[3] = {test_uniform(&st, -5, 5), test_uniform(&st, -5, 5), test_uniform(&st, -5, 5)};
        assert_int_equal(aqs_body_set_force(L, b, f, NULL, NULL), AQS_OK);
    }
    return L;
}

static void free_scene(scene *S)
{
    free(S->parent);
    free(S->jtype);
    free(S->comp);
    free(S->shapes);
    free(S->group);
    free(S->mask);
    free(S->excl);
}

static int cmp_contact(const void *x, const void *y)
{
    const aqs_contact *a = x, *b = y;
    if (a->shape_a != b->shape_a) return a->shape_a < b->shape_a ? -1 : 1;
    if (a->shape_b != b->shape_b) return a->shape_b < b->shape_b ? -1 : 1;
    return 0;
}

/* Query with mode into a fresh sorted array; returns the count. */
static size_t query(aqs_linkage *L, int32_t mode, aqs_contact **out)
{
    size_t count = 0, again = 0;
    aqs_status st = aqs_linkage_collide(L, mode, NULL, 0, &count);
    assert_true(st == AQS_OK || st == AQS_ESIZE);
    *out = calloc(count + 1, sizeof(aqs_contact));
    assert_int_equal(aqs_linkage_collide(L, mode, *out, count, &again), AQS_OK);
    assert_int_equal(again, count);
    qsort(*out, count, sizeof(aqs_contact), cmp_contact);
    return count;
}

static void same_contacts(const aqs_contact *a, size_t na, const aqs_contact *b, size_t nb)
{
    size_t i;
    assert_int_equal(na, nb);
    for (i = 0; i < na; i++) {
        const double va[7] = {a[i].depth, a[i].nx, a[i].ny, a[i].nz, a[i].px, a[i].py, a[i].pz};
        const double vb[7] = {b[i].depth, b[i].nx, b[i].ny, b[i].nz, b[i].px, b[i].py, b[i].pz};
        assert_int_equal(a[i].shape_a, b[i].shape_a);
        assert_int_equal(a[i].shape_b, b[i].shape_b);
        assert_int_equal(a[i].body_a, b[i].body_a);
        assert_int_equal(a[i].body_b, b[i].body_b);
        assert_true(test_max_abs_diff(va, vb, 7) <= 1e-9);
    }
}

/* The test's own brute force: public world poses, its own filters. */
static int allowed(const scene *S, int32_t i, int32_t j)
{
    int32_t a = S->shapes[i].body, b = S->shapes[j].body, k;
    uint32_t ga = a < 0 ? 1u : S->group[a], ma = a < 0 ? 0xFFFFFFFFu : S->mask[a];
    uint32_t gb = b < 0 ? 1u : S->group[b], mb = b < 0 ? 0xFFFFFFFFu : S->mask[b];
    int32_t ca = a < 0 ? -1 : S->comp[a], cb = b < 0 ? -1 : S->comp[b];
    if (ca == cb) return 0;
    if (!(ga & mb) || !(gb & ma)) return 0;
    if (!S->joined && a >= 0 && b >= 0 && (S->parent[a] == b || S->parent[b] == a)) return 0;
    for (k = 0; k < S->nexcl; k++)
        if ((S->excl[2 * k] == a && S->excl[2 * k + 1] == b) || (S->excl[2 * k] == b && S->excl[2 * k + 1] == a))
            return 0;
    return 1;
}

static void place_world(const scene *S, const double *poses, int32_t i, placed_shape *p)
{
    const shape_def *s = &S->shapes[i];
    pose body;
    p->s = s;
    if (s->body < 0) {
        p->world = s->local;
        return;
    }
    test_quat_matrix(poses + 7 * s->body + 3, body.R);
    memcpy(body.p, poses + 7 * s->body, 3 * sizeof(double));
    test_mat3_mul(body.R, s->local.R, p->world.R);
    {
        int k;
        for (k = 0; k < 3; k++)
            p->world.p[k] = body.p[k] + body.R[3 * k] * s->local.p[0] + body.R[3 * k + 1] * s->local.p[1] +
                            body.R[3 * k + 2] * s->local.p[2];
    }
}

static void independent_check(const scene *S, aqs_linkage *L, const aqs_contact *lib, size_t nlib)
{
    double *poses = calloc((size_t)S->n * 7, sizeof(double));
    placed_shape *pl = calloc((size_t)S->nshapes, sizeof(placed_shape));
    char *matched = calloc(nlib + 1, 1);
    int32_t i, j;
    size_t found = 0, k;
    assert_int_equal(aqs_linkage_get_body_poses_world(L, poses, (size_t)S->n * 7), AQS_OK);
    for (i = 0; i < S->nshapes; i++) place_world(S, poses, i, &pl[i]);
    for (i = 0; i < S->nshapes; i++)
        for (j = i + 1; j < S->nshapes; j++) {
            double d, n[3], p[3];
            int32_t a = i, b = j;
            if (!allowed(S, i, j)) continue;
            if (S->shapes[i].body < 0) { a = j; b = i; }
            if (!narrow_contact(&pl[a], &pl[b], &d, n, p)) continue;
            /* find it in the library's list */
            for (k = 0; k < nlib; k++)
                if (lib[k].shape_a == a && lib[k].shape_b == b) break;
            if (k == nlib) {
                if (d > 1e-9) {
                    print_error("pair %d %d (depth %g) missing from the library's contacts\n", (int)a, (int)b, d);
                    fail();
                }
                continue;
            }
            found++;
            matched[k] = 1;
            /* MPR's depth moves with rounding: continuously (to ~1e-6 measured)
             * for smooth pairs, in jumps between the planes of adjacent faces
             * for polytopes (docs/collision.md). Depths are compared for
             * sphere and capsule pairs only. */
            if (S->shapes[a].type <= AQS_SHAPE_CAPSULE && S->shapes[b].type <= AQS_SHAPE_CAPSULE &&
                fabs(lib[k].depth - d) > 1e-5) {
                print_error("pair %d %d: depth %.17g here, %.17g in the library\n", (int)a, (int)b, d,
                            lib[k].depth);
                fail();
            }
        }
    /* Every library contact deeper than 1e-9 was found here. */
    for (k = 0; k < nlib; k++) assert_true(matched[k] || lib[k].depth <= 1e-9);
    assert_true(found <= nlib);
    free(matched);
    free(poses);
    free(pl);
}

/* Scale dt so that the largest joint increment dt^2 |qdd| is about h. */
static double step_dt(aqs_linkage *L, double h)
{
    int32_t nv;
    double *qdd, m = 0.0;
    int32_t i;
    assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, NULL, &nv), AQS_OK);
    qdd = calloc((size_t)nv, sizeof(double));
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_linkage_get_accelerations(L, qdd, (size_t)nv), AQS_OK);
    for (i = 0; i < nv; i++) m = fmax(m, fabs(qdd[i]));
    free(qdd);
    return m > 0.0 ? sqrt(h / m) : 1.0;
}

static void differential(int32_t n, uint64_t seed, int joined, int brute_every, int independent)
{
    scene S;
    aqs_linkage *L = build(&S, n, seed, joined);
    uint64_t st = seed * 7 + 1;
    int step, total_contacts = 0, skipped = 0;
    for (step = 0; step <= 200; step++) {
        aqs_contact *lazy, *full, *bf;
        size_t nl, nf, nb;
        int32_t refit, vt, nt, sk;
        if (step > 0) {
            double u = test_uniform(&st, 0, 1);
            if (u < 0.5) {
                assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1.0 / 512), AQS_OK);
            } else {
                assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
            }
            if (u > 0.97) { /* a bulk position reset to small random angles */
                int32_t nq, j;
                double *q;
                assert_int_equal(aqs_linkage_get_sizes(L, NULL, NULL, &nq, NULL), AQS_OK);
                q = calloc((size_t)nq, sizeof(double));
                assert_int_equal(aqs_linkage_get_positions(L, q, (size_t)nq), AQS_OK);
                for (j = 0; j < S.n; j++) {
                    int32_t off, jn;
                    assert_int_equal(aqs_joint_get_layout(L, j, &off, &jn, NULL, NULL), AQS_OK);
                    if (jn == 1) q[off] += test_uniform(&st, -0.3, 0.3);
                }
                assert_int_equal(aqs_linkage_set_positions(L, q, (size_t)nq), AQS_OK);
                free(q);
            } else if (u > 0.94) { /* one joint moved by hand */
                int32_t j = (int32_t)(test_uniform(&st, 0, 1) * S.n), off, jn;
                if (S.jtype[j] == AQS_JOINT_REVOLUTE) {
                    double q = test_uniform(&st, -1, 1);
                    assert_int_equal(aqs_joint_get_layout(L, j, &off, &jn, NULL, NULL), AQS_OK);
                    assert_int_equal(aqs_joint_set_position(L, j, &q, 1), AQS_OK);
                }
            } else {
                assert_int_equal(aqs_linkage_step(L, step_dt(L, 0.02)), AQS_OK);
            }
            /* skip the query now and then: moves accumulate between queries */
            if (test_uniform(&st, 0, 1) < 0.2) continue;
        }
        nl = query(L, AQS_COLLIDE_LAZY, &lazy);
        assert_int_equal(aqs_linkage_get_collision_stats(L, &refit, &vt, &nt, &sk), AQS_OK);
        skipped += sk;
        nf = query(L, AQS_COLLIDE_FULL, &full);
        same_contacts(lazy, nl, full, nf);
        if (step % brute_every == 0) {
            nb = query(L, AQS_COLLIDE_BRUTE, &bf);
            same_contacts(lazy, nl, bf, nb);
            if (independent) independent_check(&S, L, bf, nb);
            free(bf);
        }
        {
            int32_t hit = -1;
            assert_int_equal(aqs_linkage_any_contact(L, &hit), AQS_OK);
            assert_int_equal(hit, nl > 0);
        }
        total_contacts += (int)nl;
        free(lazy);
        free(full);
    }
    /* The scenes are dense enough to test something, and the lazy queries did skip. */
    print_message("%d bodies: %d contacts over the queries, %d subassemblies skipped\n", (int)n, total_contacts, skipped);
    assert_true(total_contacts > 200);
    assert_true(skipped > 0);
    aqs_linkage_destroy(L);
    free_scene(&S);
}

static void test_differential_60(void **state)
{
    differential(60, 101, 0, 1, 1);
    differential(60, 102, 1, 1, 1);
}

static void test_differential_400(void **state) { differential(400, 103, 0, 1, 0); }

static void test_differential_2000(void **state) { differential(2000, 104, 0, 20, 0); }

/* ------------------------------------------------------------------------
 * Lazy caches carried across moves.
 *
 * In differential() above the full query runs on the same linkage right
 * after each lazy one, and it refits and re-caches every node: the lazy
 * query there always starts from caches a full traversal just rebuilt. Here
 * two copies of one random linkage (same build, same seeds) are stepped by
 * the same calls, so their positions are equal bit for bit (asserted each
 * step: no query changes positions). Copy 1 runs only lazy queries, one
 * aqs_linkage_collide call per queried step, so its caches and marks carry
 * over from step to step and the contacts it returns come from the very
 * query that refitted the moved nodes; copy 2 runs only full and brute-force
 * queries. About 1 step in 10 is not queried on either copy, so moves also
 * accumulate between lazy queries. Contacts must be the same pairs with
 * depths, normals and points equal to 1e-9 (same_contacts: both copies place
 * shapes by the same operations on the same bits, so they agree to rounding).
 * On copy 1, after each queried step following a queried step:
 *  - adaptive step: nodes_refit == nodes_processed of the step's solve
 *    (docs/collision.md: the marks are the processed nodes; the previous
 *    query cleared all marks, and refit counts every marked internal node);
 *  - exact step: nodes_refit == every internal node;
 *  - aqs_joint_set_position: nodes_refit == the joint's node and its
 *    ancestors.
 * Against vacuity: contacts occur, the contact set changes between queries,
 * some adaptive steps are local (processed < internal nodes), and cached
 * contacts are replayed (nodes cached with contacts and not moved at the
 * time of a lazy query, read from the internal state). */

#define LAZY_CAP 65536 /* contacts per query: far above what these scenes reach */

/* One query in a single call into buf (LAZY_CAP contacts), sorted: for the
 * lazy copy a second call would be a pure replay. */
static size_t query_once(aqs_linkage *L, int32_t mode, aqs_contact *buf)
{
    size_t count = 0;
    assert_int_equal(aqs_linkage_collide(L, mode, buf, LAZY_CAP, &count), AQS_OK);
    qsort(buf, count, sizeof(aqs_contact), cmp_contact);
    return count;
}

/* Nodes whose cached contacts the next lazy query replays. */
static int32_t replayable(const aqs_linkage *L)
{
    const collision *c = L->col;
    int32_t n, k = 0;
    if (!c || !c->built) return 0;
    for (n = 0; n < L->t.nnodes; n++)
        if (L->t.nodes[n].joint >= 0 && c->cached[n] && !c->moved[n] && c->ncont[n] > 0) k++;
    return k;
}

/* Internal nodes on the path from joint j's node to the root. */
static int32_t path_to_root(const aqs_linkage *L, int32_t j)
{
    int32_t n = L->t.node_of_eff[L->m.eff_of_joint[j]], k = 0;
    for (; n >= 0; n = L->t.nodes[n].parent) k++;
    return k;
}

static int same_pairs(const aqs_contact *a, size_t na, const aqs_contact *b, size_t nb)
{
    size_t i;
    if (na != nb) return 0;
    for (i = 0; i < na; i++)
        if (a[i].shape_a != b[i].shape_a || a[i].shape_b != b[i].shape_b) return 0;
    return 1;
}

static void lazy_persistent(int32_t n, uint64_t seed, int joined, int steps, int brute_every)
{
    scene S1, S2;
    aqs_linkage *L1 = build(&S1, n, seed, joined), *L2 = build(&S2, n, seed, joined);
    aqs_contact *lazy = calloc(LAZY_CAP, sizeof(aqs_contact)), *prev = calloc(LAZY_CAP, sizeof(aqs_contact));
    aqs_contact *other = calloc(LAZY_CAP, sizeof(aqs_contact));
    uint64_t st = seed * 13 + 5;
    int32_t nq, internal = -1, refit, sk, step;
    double *q1, *q2;
    size_t nprev = 0;
    int prev_queried = 0, with_contacts = 0, changes = 0, local = 0, adaptive_checked = 0, replays = 0;
    long skipped = 0;
    /* adaptive steps as such (step_dt solves L1 once more than L2, which
     * would feed the automatic path different histories) */
    assert_int_equal(aqs_linkage_set_auto(L1, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L2, 0), AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L1, NULL, NULL, &nq, NULL), AQS_OK);
    q1 = calloc((size_t)nq + 1, sizeof(double));
    q2 = calloc((size_t)nq + 1, sizeof(double));
    for (step = 0; step <= steps; step++) {
        /* kind: 0 first query, 1 adaptive step, 2 exact step, 3 one joint set */
        int kind = 0, query_now = 1;
        int32_t moved_joint = -1;
        aqs_solve_stats ss;
        size_t nl, nf, nb;
        if (step > 0) {
            double u = test_uniform(&st, 0, 1);
            if (step % 25 == 0) { /* new loads on a few bodies, the same on both copies */
                int32_t k;
                for (k = 0; k < 5; k++) {
                    int32_t b = (int32_t)(test_uniform(&st, 0, 1) * n);
                    double f[3] = {test_uniform(&st, -8, 8), test_uniform(&st, -8, 8), test_uniform(&st, -8, 8)};
                    assert_int_equal(aqs_body_set_force(L1, b, f, NULL, NULL), AQS_OK);
                    assert_int_equal(aqs_body_set_force(L2, b, f, NULL, NULL), AQS_OK);
                }
            }
            if (u < 0.92) {
                /* adaptive steps from nearly global (1/512: ~98% of the nodes
                 * processed on the 2,000-body scene) to local (1/2: ~15%) */
                double eps = u < 0.24 ? 1.0 / 512 : u < 0.48 ? 1.0 / 8 : u < 0.72 ? 0.5 : 0.0, dt;
                kind = eps > 0.0 ? 1 : 2;
                assert_int_equal(aqs_linkage_set_tolerance(L1, AQS_METRIC_REL_JOINT, eps), AQS_OK);
                assert_int_equal(aqs_linkage_set_tolerance(L2, AQS_METRIC_REL_JOINT, eps), AQS_OK);
                /* dt from copy 1's solve (a solve starts from scratch: the step's
                 * own solve on copy 2 is the same; positions are compared below) */
                dt = step_dt(L1, 0.02);
                assert_int_equal(aqs_linkage_step(L1, dt), AQS_OK);
                assert_int_equal(aqs_linkage_step(L2, dt), AQS_OK);
            } else {
                int32_t j = (int32_t)(test_uniform(&st, 0, 1) * n);
                double qj = test_uniform(&st, -1, 1);
                if (S1.jtype[j] == AQS_JOINT_REVOLUTE) {
                    kind = 3;
                    moved_joint = j;
                    assert_int_equal(aqs_joint_set_position(L1, j, &qj, 1), AQS_OK);
                    assert_int_equal(aqs_joint_set_position(L2, j, &qj, 1), AQS_OK);
                }
            }
            query_now = test_uniform(&st, 0, 1) >= 0.1;
        }
        assert_int_equal(aqs_linkage_get_positions(L1, q1, (size_t)nq), AQS_OK);
        assert_int_equal(aqs_linkage_get_positions(L2, q2, (size_t)nq), AQS_OK);
        assert_memory_equal(q1, q2, (size_t)nq * sizeof(double));
        if (!query_now) {
            prev_queried = 0;
            continue;
        }
        /* copy 1: the lazy query only */
        replays += replayable(L1);
        nl = query_once(L1, AQS_COLLIDE_LAZY, lazy);
        assert_int_equal(aqs_linkage_get_collision_stats(L1, &refit, NULL, NULL, &sk), AQS_OK);
        skipped += sk;
        /* copy 2: full (it refits every internal node) and brute force */
        nf = query_once(L2, AQS_COLLIDE_FULL, other);
        if (internal < 0) assert_int_equal(aqs_linkage_get_collision_stats(L2, &internal, NULL, NULL, NULL), AQS_OK);
        same_contacts(lazy, nl, other, nf);
        if (step % brute_every == 0) {
            nb = query_once(L2, AQS_COLLIDE_BRUTE, other);
            same_contacts(lazy, nl, other, nb);
        }
        /* what the lazy query refitted */
        if (prev_queried && kind == 1) {
            memset(&ss, 0, sizeof ss);
            ss.size = sizeof ss;
            assert_int_equal(aqs_linkage_get_stats(L1, &ss), AQS_OK);
            if (refit != ss.nodes_processed) {
                print_error("step %d: lazy query refitted %d nodes, the adaptive step processed %d\n", step,
                            (int)refit, (int)ss.nodes_processed);
                fail();
            }
            adaptive_checked++;
            if (ss.nodes_processed < internal) local++;
        } else if (prev_queried && kind == 2) {
            assert_int_equal(refit, internal);
        } else if (prev_queried && kind == 3) {
            assert_int_equal(refit, path_to_root(L1, moved_joint));
        } else if (prev_queried && step > 0) { /* nothing moved (a non-revolute joint was drawn) */
            assert_int_equal(refit, 0);
        }
        if (nl > 0) with_contacts++;
        if (step > 0 && !same_pairs(lazy, nl, prev, nprev)) changes++;
        memcpy(prev, lazy, nl * sizeof(aqs_contact));
        nprev = nl;
        prev_queried = 1;
    }
    print_message("%d bodies, lazy-only copy: %d queries with contacts, %d contact-set changes, "
                  "%d adaptive refits checked (%d local), %d cached nodes replayed, %ld skipped\n",
                  (int)n, with_contacts, changes, adaptive_checked, local, replays, skipped);
    assert_true(internal > 0);
    assert_true(with_contacts > 0);
    assert_true(changes > 0);
    assert_true(adaptive_checked > 0);
    assert_true(local > 0);
    assert_true(replays > 0);
    assert_true(skipped > 0);
    free(q1);
    free(q2);
    free(lazy);
    free(prev);
    free(other);
    aqs_linkage_destroy(L1);
    aqs_linkage_destroy(L2);
    free_scene(&S1);
    free_scene(&S2);
}

static void test_lazy_persistent_60(void **state)
{
    lazy_persistent(60, 201, 0, 200, 1);
    lazy_persistent(60, 202, 1, 200, 1);
}

static void test_lazy_persistent_400(void **state) { lazy_persistent(400, 203, 0, 200, 1); }

/* 100 steps, brute force every 10th: the 200 steps of the smaller scenes
 * would take ~10 s here (a lazy query costs ~150,000 sphere tests on this
 * tangled scene, a full one as much). */
static void test_lazy_persistent_2000(void **state) { lazy_persistent(2000, 204, 0, 100, 10); }

/* A local move: no gravity, one load on one body, REL_JOINT 1/64. After each
 * adaptive step the lazy query refits exactly the processed nodes (the
 * marks left by the step; the previous query cleared all), a small part of
 * the tree (measured: 88 of 1,662 internal nodes; asserted < 1/4), and
 * returns what brute force returns (brute force refits the moved nodes but
 * leaves the caches alone, so the lazy caches still persist here). An exact
 * step then refits every internal node. */
static void test_adaptive_refit_is_local(void **state)
{
    scene S;
    aqs_linkage *L = build(&S, 2000, 205, 0);
    aqs_contact *lazy = calloc(LAZY_CAP, sizeof(aqs_contact)), *bf = calloc(LAZY_CAP, sizeof(aqs_contact));
    const double zero[3] = {0, 0, 0}, f[3] = {0, 3, 1};
    int32_t internal = -1, refit, sk, k;
    aqs_solve_stats ss;
    size_t nl, nb;
    assert_int_equal(aqs_linkage_set_gravity(L, zero), AQS_OK);
    assert_int_equal(aqs_linkage_clear_forces(L), AQS_OK);
    assert_int_equal(aqs_body_set_force(L, 1500, f, NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1.0 / 64), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L, 0), AQS_OK); /* adaptive steps: their refits are under test */
    (void)query_once(L, AQS_COLLIDE_FULL, lazy);
    assert_int_equal(aqs_linkage_get_collision_stats(L, &internal, NULL, NULL, NULL), AQS_OK);
    assert_true(internal > 1000);
    (void)query_once(L, AQS_COLLIDE_LAZY, lazy);
    for (k = 0; k < 5; k++) {
        assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
        memset(&ss, 0, sizeof ss);
        ss.size = sizeof ss;
        assert_int_equal(aqs_linkage_get_stats(L, &ss), AQS_OK);
        nl = query_once(L, AQS_COLLIDE_LAZY, lazy);
        assert_int_equal(aqs_linkage_get_collision_stats(L, &refit, NULL, NULL, &sk), AQS_OK);
        assert_true(ss.nodes_processed > 0);
        assert_int_equal(refit, ss.nodes_processed);
        assert_true(4 * refit < internal);
        if (k == 0) print_message("local move: %d of %d internal nodes refitted\n", (int)refit, (int)internal);
        assert_true(sk > 0);
        nb = query_once(L, AQS_COLLIDE_BRUTE, bf);
        assert_true(nl > 0);
        same_contacts(lazy, nl, bf, nb);
    }
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 0.0), AQS_OK);
    assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    nl = query_once(L, AQS_COLLIDE_LAZY, lazy);
    assert_int_equal(aqs_linkage_get_collision_stats(L, &refit, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(refit, internal);
    nb = query_once(L, AQS_COLLIDE_BRUTE, bf);
    same_contacts(lazy, nl, bf, nb);
    free(lazy);
    free(bf);
    aqs_linkage_destroy(L);
    free_scene(&S);
}

/* A query right after another, with nothing moved, refits nothing. */
static void test_idle_query_refits_nothing(void **state)
{
    scene S;
    aqs_linkage *L = build(&S, 200, 105, 0);
    aqs_contact *c;
    int32_t refit = -1, vt, nt, sk;
    size_t n1 = query(L, AQS_COLLIDE_LAZY, &c);
    free(c);
    assert_int_equal(query(L, AQS_COLLIDE_LAZY, &c), n1);
    free(c);
    assert_int_equal(aqs_linkage_get_collision_stats(L, &refit, &vt, &nt, &sk), AQS_OK);
    assert_int_equal(refit, 0);
    assert_true(sk > 0);
    aqs_linkage_destroy(L);
    free_scene(&S);
}

/* More contacts than the cache of contact pairs holds (4 per shape + 1024):
 * the lazy query must still agree with brute force while it overflows and
 * forgets its caches. 12 bodies with 12 spheres of radius 2 each, all
 * overlapping: about 9,500 contacts for 144 shapes. */
static void test_cache_overflow(void **state)
{
    aqs_linkage *L = test_new_linkage();
    const double q1[4] = {1, 0, 0, 0}, zax[3] = {0, 0, 1}, g[3] = {0, -9.81, 0};
    int32_t b, k, step;
    uint64_t st = 9;
    for (b = 0; b < 12; b++) {
        double pos[3] = {b ? 0.3 : 0.0, 0, 0};
        test_add_body(L, 1.0, 0.2, 0, 0, 0.1);
        assert_int_equal(aqs_joint_add(L, AQS_JOINT_REVOLUTE, b - 1, b, pos, q1, zax, NULL), AQS_OK);
        for (k = 0; k < 12; k++) {
            double sz[3] = {2.0, 0, 0}, at[3] = {test_uniform(&st, -0.2, 0.2), test_uniform(&st, -0.2, 0.2), 0};
            assert_int_equal(aqs_shape_add(L, b, AQS_SHAPE_SPHERE, sz, at, q1, NULL), AQS_OK);
        }
    }
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, 1.0 / 64), AQS_OK);
    for (step = 0; step < 6; step++) {
        aqs_contact *lazy, *bf;
        size_t nl = query(L, AQS_COLLIDE_LAZY, &lazy), nb = query(L, AQS_COLLIDE_BRUTE, &bf);
        assert_true(nl > 4 * 144 + 1024);
        same_contacts(lazy, nl, bf, nb);
        free(lazy);
        free(bf);
        assert_int_equal(aqs_linkage_step(L, 0.01), AQS_OK);
    }
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------------------------
 * Certificates (docs/collision.md, "Certificates"): a moved node whose
 * children moved apart by less than its margin since its cross pair was
 * certified re-tests only its near list. */

/* Internal nodes certified now. */
static int32_t certified(const aqs_linkage *L)
{
    const collision *c = L->col;
    int32_t n, k = 0;
    for (n = 0; n < L->t.nnodes; n++) k += c->cert[n];
    return k;
}

/* (a) A long run of small adaptive steps: two copies stepped alike, lazy
 * queries only on copy 1 (its certificates carry over), full and brute
 * force on copy 2. Every step the contacts are the same; certificates are
 * reused far more often than made and the lazy query's sphere tests are far
 * below the full query's; some expire on the way (made after the first
 * query) and their near lists hold the contacts (near pairs re-tested). */
static void certificates_small_steps(int32_t n, uint64_t seed, double h, int steps)
{
    scene S1, S2;
    aqs_linkage *L1 = build(&S1, n, seed, 0), *L2 = build(&S2, n, seed, 0);
    aqs_contact *lazy = calloc(LAZY_CAP, sizeof(aqs_contact)), *other = calloc(LAZY_CAP, sizeof(aqs_contact));
    long vt_lazy = 0, vt_full = 0, reused = 0, made_later = 0, near = 0, contacts = 0;
    int32_t step, vt;
    /* adaptive steps as such (step_dt solves L1 once more than L2, which
     * would feed the automatic path different histories) */
    assert_int_equal(aqs_linkage_set_auto(L1, 0), AQS_OK);
    assert_int_equal(aqs_linkage_set_auto(L2, 0), AQS_OK);
    for (step = 0; step <= steps; step++) {
        size_t nl, nf, nb;
        if (step > 0) {
            double dt = step_dt(L1, h);
            assert_int_equal(aqs_linkage_set_tolerance(L1, AQS_METRIC_REL_JOINT, 1.0 / 8), AQS_OK);
            assert_int_equal(aqs_linkage_set_tolerance(L2, AQS_METRIC_REL_JOINT, 1.0 / 8), AQS_OK);
            assert_int_equal(aqs_linkage_step(L1, dt), AQS_OK);
            assert_int_equal(aqs_linkage_step(L2, dt), AQS_OK);
        }
        nl = query_once(L1, AQS_COLLIDE_LAZY, lazy);
        assert_int_equal(aqs_linkage_get_collision_stats(L1, NULL, &vt, NULL, NULL), AQS_OK);
        if (step > 0) {
            vt_lazy += vt;
            reused += L1->col->certs_reused;
            made_later += L1->col->certs_made;
            near += L1->col->near_tests;
        }
        nf = query_once(L2, AQS_COLLIDE_FULL, other);
        assert_int_equal(aqs_linkage_get_collision_stats(L2, NULL, &vt, NULL, NULL), AQS_OK);
        if (step > 0) vt_full += vt;
        same_contacts(lazy, nl, other, nf);
        nb = query_once(L2, AQS_COLLIDE_BRUTE, other);
        same_contacts(lazy, nl, other, nb);
        contacts += (long)nl;
    }
    print_message("%d bodies, %d steps of %g: %ld contacts, certificates reused %ld, made after the "
                  "first query %ld, near pairs re-tested %ld, sphere tests lazy %ld / full %ld\n",
                  (int)n, steps, h, contacts, reused, made_later, near, vt_lazy, vt_full);
    assert_true(contacts > steps);
    assert_true(reused > 10 * made_later);
    assert_true(made_later > 0);
    assert_true(near > 0);
    assert_true(10 * vt_lazy < vt_full);
    free(lazy);
    free(other);
    aqs_linkage_destroy(L1);
    aqs_linkage_destroy(L2);
    free_scene(&S1);
    free_scene(&S2);
}

static void test_certificates_small_steps(void **state)
{
    certificates_small_steps(400, 301, 1e-4, 150);
    certificates_small_steps(2000, 302, 1e-4, 40);
}

/* A chain of 8 bodies 1 apart along x, a sphere of radius 0.3 on each,
 * revolute joints about z: contact-free when straight. */
static aqs_linkage *straight_chain(void)
{
    aqs_linkage *L = test_new_linkage();
    const double q1[4] = {1, 0, 0, 0}, sz[3] = {0.3, 0, 0}, at[3] = {0, 0, 0};
    int32_t b;
    for (b = 0; b < 8; b++) {
        (void)test_add_joint(L, AQS_JOINT_REVOLUTE, b - 1, test_add_body(L, 1.0, 0.2, 0, 0, 0.1),
                             b ? 1.0 : 0.0, 0, 0, 0, 0, 1);
        assert_int_equal(aqs_shape_add(L, b, AQS_SHAPE_SPHERE, sz, at, q1, NULL), AQS_OK);
    }
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    return L;
}

/* Lazy query into buf (sorted), compared with brute force. */
static size_t lazy_equals_brute(aqs_linkage *L, aqs_contact *buf, aqs_contact *bf)
{
    size_t nl = query_once(L, AQS_COLLIDE_LAZY, buf);
    int32_t made = L->col->certs_made, reused = L->col->certs_reused, near = L->col->near_tests;
    size_t nb = query_once(L, AQS_COLLIDE_BRUTE, bf);
    same_contacts(buf, nl, bf, nb);
    L->col->certs_made = made; /* the caller reads the lazy query's */
    L->col->certs_reused = reused;
    L->col->near_tests = near;
    return nl;
}

static int has_pair(const aqs_contact *c, size_t n, int32_t a, int32_t b)
{
    size_t k;
    for (k = 0; k < n; k++)
        if (c[k].body_a == a && c[k].body_b == b) return 1;
    return 0;
}

/* Small moves of joint 4 (certificates reused) and wiggles of the small
 * joints around it, then (b) a jump of joint 4 by 3 rad folding bodies 5..7
 * back onto 3..1: the certificates above it are invalidated and the new
 * contacts found; (c) a filter change and a FULL query drop every
 * certificate; the lazy query equals brute force throughout. */
static void test_certificates_jump_filters_full(void **state)
{
    aqs_linkage *L = straight_chain();
    aqs_contact *buf = calloc(64, sizeof(aqs_contact)), *bf = calloc(64, sizeof(aqs_contact));
    int32_t k, reused = 0;
    size_t nl;
    double q;
    assert_int_equal(lazy_equals_brute(L, buf, bf), 0);
    for (k = 1; k <= 5; k++) {
        q = 0.002 * k;
        assert_int_equal(aqs_joint_set_position(L, 4, &q, 1), AQS_OK);
        assert_int_equal(lazy_equals_brute(L, buf, bf), 0);
        reused += L->col->certs_reused;
        assert_int_equal(L->col->certs_made, 0);
    }
    assert_true(reused > 0);
    /* (b) the jump */
    q = 3.0;
    assert_int_equal(aqs_joint_set_position(L, 4, &q, 1), AQS_OK);
    nl = lazy_equals_brute(L, buf, bf);
    assert_true(L->col->certs_made > 0);
    assert_true(has_pair(buf, nl, 1, 7) && has_pair(buf, nl, 2, 6) && has_pair(buf, nl, 3, 5));
    /* small moves again: the new certificates are reused, contacts found */
    for (k = 1; k <= 3; k++) {
        q = 3.0 + 0.001 * k;
        assert_int_equal(aqs_joint_set_position(L, 4, &q, 1), AQS_OK);
        assert_int_equal(lazy_equals_brute(L, buf, bf), nl);
        assert_true(L->col->certs_reused > 0);
        assert_true(L->col->near_tests >= 3);
    }
    /* (c) filters: body 5 collides with nothing, then with everything again.
     * Each change forgets the certificates (their near lists were filtered). */
    assert_true(certified(L) > 0);
    assert_int_equal(aqs_body_set_collision_filter(L, 5, 1u, 0u), AQS_OK);
    assert_int_equal(certified(L), 0);
    assert_int_equal(lazy_equals_brute(L, buf, bf), nl - 1);
    assert_true(certified(L) > 0);
    q = 3.0 + 0.004;
    assert_int_equal(aqs_joint_set_position(L, 4, &q, 1), AQS_OK);
    assert_int_equal(lazy_equals_brute(L, buf, bf), nl - 1); /* certificates without (3, 5) */
    assert_true(L->col->certs_reused > 0);
    assert_int_equal(aqs_body_set_collision_filter(L, 5, 1u, 0xFFFFFFFFu), AQS_OK);
    assert_int_equal(certified(L), 0);
    assert_int_equal(lazy_equals_brute(L, buf, bf), nl);
    assert_true(has_pair(buf, nl, 3, 5));
    assert_int_equal(aqs_collision_exclude_pair(L, 3, 5), AQS_OK);
    assert_int_equal(certified(L), 0);
    assert_int_equal(lazy_equals_brute(L, buf, bf), nl - 1);
    /* FULL: a query from scratch, which drops the certificates */
    assert_true(certified(L) > 0);
    assert_int_equal(query_once(L, AQS_COLLIDE_FULL, bf), nl - 1);
    assert_int_equal(L->col->certs_reused, 0);
    assert_int_equal(L->col->certs_made, 0);
    assert_int_equal(certified(L), 0);
    q = 3.0 + 0.005;
    assert_int_equal(aqs_joint_set_position(L, 4, &q, 1), AQS_OK);
    assert_int_equal(lazy_equals_brute(L, buf, bf), nl - 1);
    assert_int_equal(L->col->certs_reused, 0);
    assert_true(L->col->certs_made > 0);
    free(buf);
    free(bf);
    aqs_linkage_destroy(L);
}

/* (d) The near-list pool full: on a random 400-body scene whose certificates
 * need over 300 near pairs, the pool is cut to 3/4 of that (its buffers keep
 * their size): certifications that do not fit are not made, and lists that do not
 * fit in half the pool are dropped at compaction. The lazy query still
 * equals brute force at every step; certificates are made and reused where
 * they fit, never all of them. */
static void test_certificates_pool_full(void **state)
{
    scene S;
    aqs_linkage *L = build(&S, 400, 303, 0);
    aqs_contact *lazy = calloc(LAZY_CAP, sizeof(aqs_contact)), *bf = calloc(LAZY_CAP, sizeof(aqs_contact));
    long reused = 0, made = 0;
    int32_t step, all, need, cap;
    (void)query_once(L, AQS_COLLIDE_LAZY, lazy);
    all = certified(L);
    need = L->col->np.used;
    assert_true(need > 300);
    cap = L->col->np.cap = need * 3 / 4;
    L->col->np.used = 0;
    memset(L->col->cert, 0, (size_t)L->t.nnodes);
    for (step = 0; step < 60; step++) {
        size_t nl, nb;
        int32_t n, live = 0;
        assert_int_equal(aqs_linkage_set_tolerance(L, AQS_METRIC_REL_JOINT, step % 10 == 0 ? 0.0 : 1.0 / 8),
                         AQS_OK);
        assert_int_equal(aqs_linkage_step(L, step_dt(L, step % 10 == 0 ? 0.02 : 1e-4)), AQS_OK);
        nl = query_once(L, AQS_COLLIDE_LAZY, lazy);
        reused += L->col->certs_reused;
        made += L->col->certs_made;
        for (n = 0; n < L->t.nnodes; n++)
            if (L->col->cert[n]) live += L->col->ncnt[n];
        assert_true(live <= L->col->np.used && L->col->np.used <= cap / 2);
        assert_true(certified(L) < all);
        nb = query_once(L, AQS_COLLIDE_BRUTE, bf);
        same_contacts(lazy, nl, bf, nb);
    }
    print_message("near-list pool of %d pairs (%d needed): certificates made %ld, reused %ld\n", (int)cap,
                  (int)need, made, reused);
    assert_true(made > 0);
    assert_true(reused > 0);
    free(lazy);
    free(bf);
    aqs_linkage_destroy(L);
    free_scene(&S);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_differential_60),
        cmocka_unit_test(test_differential_400),
        cmocka_unit_test(test_differential_2000),
        cmocka_unit_test(test_lazy_persistent_60),
        cmocka_unit_test(test_lazy_persistent_400),
        cmocka_unit_test(test_lazy_persistent_2000),
        cmocka_unit_test(test_adaptive_refit_is_local),
        cmocka_unit_test(test_idle_query_refits_nothing),
        cmocka_unit_test(test_cache_overflow),
        cmocka_unit_test(test_certificates_small_steps),
        cmocka_unit_test(test_certificates_jump_filters_full),
        cmocka_unit_test(test_certificates_pool_full),
    };
    return cmocka_run_group_tests_name("broadphase", tests, NULL, NULL);
}
