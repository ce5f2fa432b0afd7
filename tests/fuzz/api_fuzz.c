/* api_fuzz.c -- libFuzzer target: "a failed call changes nothing observable"
 * (aqs.h) on arbitrary call sequences with injected allocation failures.
 *
 * The input bytes decode into a DCA form (AQS_DCA_FORM_SQRT or _PHI, for
 * both linkages) and a sequence of API calls (bodies, joints,
 * finalize, positions, loads, settings, solve, step, refine, shapes,
 * filters, queries) made on two linkages: the subject, whose allocator fails
 * on the allocations the input chooses, and the twin (plain malloc), which
 * receives only the calls that succeeded on the subject (and the numerical
 * failures of solve, step and refine, the documented exception, which it
 * must repeat). After every call every observable getter must agree bit for
 * bit between the two. A mismatch aborts with the call and the getter named.
 * A solve, step or refine that does not fail for memory on the subject
 * although one of its allocations failed (the refinement's arrays: it
 * answers unrefined, as documented) ends the comparison for that input, and so does a solve or step
 * whose hand-over to the exact DCA could not allocate its storage (AQS_ENOMEM,
 * the previous results discarded, as documented).
 *
 * Built by `make fuzz` (build/fuzz/aqs_fuzz, clang -fsanitize=fuzzer,address,
 * undefined); `make check-fuzz` runs it briefly; docs/testing.md has the
 * longer run. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"

/* ------------------------------------------------------------ input */

typedef struct {
    const uint8_t *p;
    size_t n, i;
} input;

static unsigned byte(input *in) { return in->i < in->n ? in->p[in->i++] : 0u; }
static int done(const input *in) { return in->i >= in->n; }
static unsigned pick(input *in, unsigned n) { return byte(in) % n; }

/* Values the decoder draws from: mostly valid, some at the edges, a few
 * invalid (each call's own checks must reject those and change nothing). */
static const double scalars[] = {0.0, 1.0, -1.0, 0.5, 2.0, 1e-3, 10.0, 0.25, 1e6, -0.3, NAN, INFINITY};
static double scalar(input *in) { return scalars[pick(in, sizeof scalars / sizeof scalars[0])]; }
static void vec(input *in, double *v, int n)
{
    int i;
    for (i = 0; i < n; i++) v[i] = scalars[pick(in, 10)]; /* finite ones mostly */
    if (pick(in, 16) == 0) v[pick(in, (unsigned)n)] = scalar(in);
}
static const double quats[][4] = {{1, 0, 0, 0}, {0.7071067811865476, 0, 0, 0.7071067811865476},
                                  {0.5, 0.5, 0.5, 0.5}, {0, 1, 0, 0}, {1, 0.1, 0, 0}, {0, 0, 0, 0}};
static const double *quat(input *in) { return quats[pick(in, 6)]; }
static const double axes[][3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 0}};
static const double *axis(input *in) { return axes[pick(in, 5)]; }
/* An index: valid most of the time, else out of range or AQS_WORLD. */
static int32_t index_of(input *in, int32_t count)
{
    unsigned b = byte(in);
    if (b < 224 && count > 0) return (int32_t)(b % (unsigned)count);
    return b % 2 ? count : AQS_WORLD;
}

/* ------------------------------------------------------------ allocator */

typedef struct {
    long count;   /* allocations since the call started */
    long fail_at; /* 1-based within the call; 0: none */
    int persist;  /* fail every allocation from fail_at on */
    long failed;
} injector;

static void *inj_alloc(void *user, size_t size)
{
    injector *j = user;
    j->count++;
    if (j->fail_at > 0 && (j->count == j->fail_at || (j->persist && j->count > j->fail_at))) {
        j->failed++;
        return NULL;
    }
    return malloc(size);
}

static void inj_free(void *user, void *ptr)
{
    (void)user;
    free(ptr);
}

/* ------------------------------------------------------------ observation */

#define MAXB 10
#define MAXQ (7 * MAXB + 8)

typedef struct {
    int32_t st[24];
    int32_t sizes[4], tree[3], solver, shapes, cstats[4], layout[MAXB][4], autopath;
    double mean_handles, fallback, prediction;
    double q[MAXQ], qdd[MAXQ], f[6 * MAXB], poses[7 * MAXB];
    aqs_solve_stats stats;
    aqs_collision_stats cstats2;
    int32_t computed[MAXB];
    double inertial[MAXB][13];         /* mass, com, inertia as stored */
    double definition[MAXB][10];       /* pos, quat, axis */
    int32_t kinds[MAXB][3];            /* type, parent, child */
    size_t ncontacts;
    aqs_contact contacts[16];
} observation;

/* Every getter, each into a zeroed observation (NaN-filled outputs compare
 * as bytes). A getter's failure is observed as its status. */
static void observe(aqs_linkage *L, observation *o)
{
    int32_t nb = 0, nj = 0, nq = 0, nv = 0, j;
    int k = 0;
    memset(o, 0, sizeof *o);
    o->st[k++] = aqs_linkage_get_sizes(L, &nb, &nj, &nq, &nv);
    o->sizes[0] = nb, o->sizes[1] = nj, o->sizes[2] = nq, o->sizes[3] = nv;
    o->st[k++] = aqs_linkage_get_tree_stats(L, &o->tree[0], &o->tree[1], &o->mean_handles, &o->tree[2]);
    o->st[k++] = aqs_linkage_get_exact_solver(L, &o->solver);
    o->st[k++] = aqs_linkage_get_exact_fallback(L, &o->fallback);
    o->st[k++] = aqs_linkage_get_prediction(L, &o->prediction);
    o->st[k++] = aqs_linkage_get_auto(L, &o->autopath);
    o->st[k++] = aqs_linkage_get_shape_count(L, &o->shapes);
    o->st[k++] = aqs_linkage_get_collision_stats(L, &o->cstats[0], &o->cstats[1], &o->cstats[2], &o->cstats[3]);
    o->st[k++] = aqs_linkage_get_positions(L, o->q, MAXQ);
    o->st[k++] = aqs_linkage_get_accelerations(L, o->qdd, MAXQ);
    o->st[k++] = aqs_linkage_get_constraint_forces(L, o->f, 6 * MAXB);
    o->st[k++] = aqs_linkage_get_body_poses_world(L, o->poses, 7 * MAXB);
    o->stats.size = sizeof o->stats;
    o->st[k++] = aqs_linkage_get_stats(L, &o->stats);
    /* a lazy query (the same on both linkages; it updates the caches and the
       statistics, read after it) */
    o->st[k++] = aqs_linkage_collide(L, AQS_COLLIDE_LAZY, o->contacts, 16, &o->ncontacts);
    o->cstats2.size = sizeof o->cstats2;
    o->st[k++] = aqs_linkage_get_query_stats(L, &o->cstats2);
    for (j = 0; j < nb && j < MAXB; j++)
        o->st[k] |= aqs_body_get_inertial(L, j, &o->inertial[j][0], &o->inertial[j][1], &o->inertial[j][4]);
    k++;
    for (j = 0; j < nj && j < MAXB; j++)
        o->st[k] |= aqs_joint_get_definition(L, j, &o->kinds[j][0], &o->kinds[j][1], &o->kinds[j][2],
                                             &o->definition[j][0], &o->definition[j][3], &o->definition[j][7]);
    k++;
    for (j = 0; j < nj && j < MAXB; j++) {
        o->st[k] |= aqs_joint_get_layout(L, j, &o->layout[j][0], &o->layout[j][1], &o->layout[j][2],
                                         &o->layout[j][3]);
        o->st[k + 1] |= aqs_joint_get_computed(L, j, &o->computed[j]);
    }
}

static void compare(aqs_linkage *S, aqs_linkage *T, injector *inj, const char *call, long step)
{
    static observation a, b;
    inj->fail_at = 0; /* observing never fails */
    observe(S, &a);
    observe(T, &b);
    if (memcmp(&a, &b, sizeof a) != 0) {
        fprintf(stderr, "api_fuzz: after call %ld (%s) the subject and its twin differ\n", step, call);
        abort();
    }
}

/* ------------------------------------------------------------ calls */

/* The arguments of one call, decoded once and applied to both linkages. */
typedef struct {
    int op;
    int32_t i0, i1, i2;
    double d0, v0[3], v1[3], v2[9], q[MAXQ];
    const double *qt, *ax;
    size_t n;
} call;

enum {
    OP_BODY, OP_JOINT, OP_FINALIZE, OP_SOLVER, OP_BUILDER, OP_INERTIA, OP_POSITIONS, OP_POSITION,
    OP_GRAVITY, OP_FORCE, OP_CLEAR_FORCE, OP_CLEAR_FORCES, OP_JOINT_FORCE, OP_TOLERANCE, OP_CAP,
    OP_FALLBACK, OP_PREDICTION, OP_BOUND, OP_SOLVE, OP_STEP, OP_REFINE, OP_SHAPE, OP_HULL,
    OP_FILTER, OP_EXCLUDE, OP_JOINED, OP_COLLIDE, OP_ANY, OP_STIFFNESS, OP_AUTO, OP_COUNT
};

static const char *const op_names[OP_COUNT] = {
    "body_add", "joint_add", "finalize", "set_exact_solver", "set_tree_builder",
    "set_inertia_check", "set_positions", "joint_set_position", "set_gravity", "body_set_force",
    "body_clear_force", "clear_forces", "joint_set_force", "set_tolerance", "set_max_computed",
    "set_exact_fallback", "set_prediction", "set_joint_bound", "solve", "step", "refine",
    "shape_add", "shape_add_hull", "set_collision_filter", "exclude_pair", "set_collide_joined",
    "collide", "any_contact", "set_contact_stiffness", "set_auto"};

static void decode(input *in, aqs_linkage *S, call *c)
{
    int32_t nb = 0, nj = 0, nq = 0, nv = 0, k;
    aqs_linkage_get_sizes(S, &nb, &nj, &nq, &nv);
    memset(c, 0, sizeof *c);
    c->op = (int)pick(in, OP_COUNT);
    switch (c->op) {
    case OP_BODY:
        c->d0 = pick(in, 8) ? 1.0 + pick(in, 3) : scalar(in);
        vec(in, c->v0, 3);
        memset(c->v2, 0, sizeof c->v2);
        c->v2[0] = c->v2[4] = c->v2[8] = pick(in, 8) ? 0.1 : scalar(in);
        if (pick(in, 8) == 0) c->v2[1] = 0.05; /* not symmetric */
        break;
    case OP_JOINT:
        c->i0 = (int32_t)pick(in, 9); /* 8: not a type */
        c->i1 = pick(in, 3) ? nb - 2 : index_of(in, nb); /* parent: a chain mostly */
        c->i2 = pick(in, 4) ? nb - 1 : index_of(in, nb);
        if (c->i1 < -1) c->i1 = AQS_WORLD;
        if (c->i0 == AQS_JOINT_FREE && pick(in, 2)) c->i1 = AQS_WORLD;
        vec(in, c->v0, 3);
        c->qt = quat(in);
        c->ax = axis(in);
        break;
    case OP_SOLVER: case OP_BUILDER: case OP_INERTIA: case OP_BOUND: case OP_JOINED: case OP_AUTO:
        c->i0 = (int32_t)pick(in, 3);
        break;
    case OP_POSITIONS:
        c->n = (size_t)nq + (pick(in, 16) == 0);
        if (c->n > MAXQ) c->n = MAXQ;
        for (k = 0; k < (int32_t)c->n; k++) c->q[k] = pick(in, 2) ? scalars[pick(in, 5)] * 0.3 : 0.0;
        /* unit quaternions where the layout has them (spherical, free) */
        for (k = 0; k < nj && k < MAXB; k++) {
            int32_t off = 0, n = 0;
            aqs_joint_get_layout(S, k, &off, &n, NULL, NULL);
            if (n == 4 || n == 7) {
                double *qq = c->q + off + (n == 7 ? 3 : 0);
                memcpy(qq, quats[pick(in, 4)], 4 * sizeof(double));
            }
        }
        if (pick(in, 16) == 0 && c->n) c->q[pick(in, (unsigned)c->n)] = NAN;
        break;
    case OP_POSITION:
        c->i0 = index_of(in, nj);
        c->n = (size_t)pick(in, 8);
        if (c->i0 >= 0 && c->i0 < nj && pick(in, 8)) {
            int32_t n = 0;
            aqs_joint_get_layout(S, c->i0, NULL, &n, NULL, NULL);
            c->n = (size_t)n;
        }
        for (k = 0; k < (int32_t)c->n; k++) c->q[k] = scalars[pick(in, 6)] * 0.5;
        if (c->n == 4 || c->n == 7) memcpy(c->q + (c->n == 7 ? 3 : 0), quat(in), 4 * sizeof(double));
        break;
    case OP_GRAVITY: vec(in, c->v0, 3); break;
    case OP_FORCE:
        c->i0 = index_of(in, nb);
        vec(in, c->v0, 3);
        vec(in, c->v1, 3);
        c->i1 = (int32_t)pick(in, 4); /* bit 0: point NULL, bit 1: torque NULL */
        break;
    case OP_CLEAR_FORCE: c->i0 = index_of(in, nb); break;
    case OP_JOINT_FORCE:
        c->i0 = index_of(in, nj);
        c->i1 = (int32_t)pick(in, 8);
        if (c->i0 >= 0 && c->i0 < nj && pick(in, 8)) {
            int32_t n = 0;
            aqs_joint_get_layout(S, c->i0, NULL, NULL, NULL, &n);
            c->i1 = n;
        }
        for (k = 0; k < 8; k++) c->q[k] = scalars[pick(in, 10)];
        break;
    case OP_TOLERANCE:
        c->i0 = (int32_t)pick(in, 5);
        c->d0 = pick(in, 4) ? ldexp(1.0, -(int)pick(in, 20)) : scalar(in);
        break;
    case OP_CAP: c->i0 = (int32_t)pick(in, 5) - 1; break;
    case OP_FALLBACK: case OP_PREDICTION: case OP_REFINE: case OP_STIFFNESS:
        c->d0 = pick(in, 2) ? scalar(in) : ldexp(1.0, (int)pick(in, 24) - 12);
        if (c->op == OP_PREDICTION && pick(in, 2)) c->d0 = pick(in, 2) ? 0.0 : 1024.0;
        break;
    case OP_STEP: c->d0 = pick(in, 4) ? 0.01 * (1 + pick(in, 10)) : scalar(in); break;
    case OP_SHAPE: case OP_HULL:
        c->i0 = pick(in, 4) ? index_of(in, nb) : AQS_WORLD;
        c->i1 = (int32_t)pick(in, 6);
        vec(in, c->v0, 3);
        for (k = 0; k < 3; k++) c->v1[k] = 0.2 + 0.2 * pick(in, 4);
        if (pick(in, 16) == 0) c->v1[pick(in, 3)] = scalar(in);
        c->qt = quat(in);
        c->i2 = 4 + (int32_t)pick(in, 5); /* hull points */
        if (pick(in, 16) == 0) c->i2 = (int32_t)pick(in, 4);
        break;
    case OP_FILTER:
        c->i0 = index_of(in, nb);
        c->i1 = (int32_t)(1u << pick(in, 4));
        c->i2 = pick(in, 2) ? -1 : (int32_t)byte(in);
        break;
    case OP_EXCLUDE: c->i0 = index_of(in, nb); c->i1 = index_of(in, nb); break;
    case OP_COLLIDE: c->i0 = (int32_t)pick(in, 4); c->n = (size_t)pick(in, 6); break;
    default: break;
    }
}

static const double hull_pts[8 * 3] = {0, 0, 0, 0.3, 0, 0, 0, 0.3, 0, 0, 0, 0.3,
                                       0.3, 0.3, 0, 0.3, 0, 0.3, 0, 0.3, 0.3, 0.3, 0.3, 0.3};

static aqs_status apply(aqs_linkage *L, const call *c)
{
    switch (c->op) {
    case OP_BODY: return aqs_body_add(L, c->d0, c->v0, c->v2, NULL);
    case OP_JOINT: return aqs_joint_add(L, c->i0, c->i1, c->i2, c->v0, c->qt, c->ax, NULL);
    case OP_FINALIZE: return aqs_linkage_finalize(L);
    case OP_SOLVER: return aqs_linkage_set_exact_solver(L, c->i0);
    case OP_BUILDER: return aqs_linkage_set_tree_builder(L, c->i0);
    case OP_INERTIA: return aqs_linkage_set_inertia_check(L, c->i0);
    case OP_POSITIONS: return aqs_linkage_set_positions(L, c->q, c->n);
    case OP_POSITION: return aqs_joint_set_position(L, c->i0, c->q, (int32_t)c->n);
    case OP_GRAVITY: return aqs_linkage_set_gravity(L, c->v0);
    case OP_FORCE:
        return aqs_body_set_force(L, c->i0, c->v0, (c->i1 & 1) ? NULL : c->v1, (c->i1 & 2) ? NULL : c->v1);
    case OP_CLEAR_FORCE: return aqs_body_clear_force(L, c->i0);
    case OP_CLEAR_FORCES: return aqs_linkage_clear_forces(L);
    case OP_JOINT_FORCE: return aqs_joint_set_force(L, c->i0, c->q, c->i1);
    case OP_TOLERANCE: return aqs_linkage_set_tolerance(L, c->i0, c->d0);
    case OP_CAP: return aqs_linkage_set_max_computed(L, c->i0);
    case OP_FALLBACK: return aqs_linkage_set_exact_fallback(L, c->d0);
    case OP_PREDICTION: return aqs_linkage_set_prediction(L, c->d0);
    case OP_BOUND: return aqs_linkage_set_joint_bound(L, c->i0);
    case OP_SOLVE: return aqs_linkage_solve(L);
    case OP_STEP: return aqs_linkage_step(L, c->d0);
    case OP_REFINE: return aqs_linkage_refine(L, c->d0);
    case OP_SHAPE: return aqs_shape_add(L, c->i0, c->i1, c->v1, c->v0, c->qt, NULL);
    case OP_HULL: return aqs_shape_add_hull(L, c->i0, hull_pts, c->i2, c->v0, c->qt, NULL);
    case OP_FILTER: return aqs_body_set_collision_filter(L, c->i0, (uint32_t)c->i1, (uint32_t)c->i2);
    case OP_EXCLUDE: return aqs_collision_exclude_pair(L, c->i0, c->i1);
    case OP_JOINED: return aqs_linkage_set_collide_joined(L, c->i0);
    case OP_COLLIDE: {
        aqs_contact buf[8];
        size_t count = 0;
        return aqs_linkage_collide(L, c->i0, c->n ? buf : NULL, c->n, &count);
    }
    case OP_ANY: {
        int32_t hit = 0;
        return aqs_linkage_any_contact(L, &hit);
    }
    case OP_STIFFNESS: return aqs_linkage_set_contact_stiffness(L, c->d0);
    case OP_AUTO: return aqs_linkage_set_auto(L, c->i0);
    default: return AQS_OK;
    }
}

/* The subject's allocations that fail in the next call, from one byte:
 * mostly none, else the k-th, or every one from the k-th on. */
static void arm(input *in, injector *j)
{
    unsigned b = byte(in);
    j->count = 0;
    j->fail_at = b < 192 ? 0 : 1 + (long)(b & 15);
    j->persist = (b & 16) != 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    input in = {data, size, 0};
    injector inj = {0, 0, 0, 0};
    aqs_linkage *S = NULL, *T = NULL;
    long step = 0;
    /* the first byte: the start's size, and in its otherwise unused part the
       DCA form (both linkages; set before building, the only time it can be:
       the seeds under tests/fuzz/seeds keep the default square-root form) */
    const unsigned b0 = byte(&in);
    const int32_t form = (b0 / MAXB) % 2 ? AQS_DCA_FORM_PHI : AQS_DCA_FORM_SQRT;
    int32_t nb0 = 1 + (int32_t)(b0 % MAXB), k;
    if (aqs_linkage_create_with_allocator(inj_alloc, inj_free, &inj, &S) != AQS_OK) return 0;
    if (aqs_linkage_create(&T) != AQS_OK) {
        aqs_linkage_destroy(S);
        return 0;
    }
    if (aqs_linkage_set_dca_form(S, form) != AQS_OK || aqs_linkage_set_dca_form(T, form) != AQS_OK) abort();
    /* A valid start most inputs share: a tree of nb0 bodies (the first byte),
     * each joint's type and parent from one byte, then finalize. */
    for (k = 0; k < 2 * nb0 + 1; k++) {
        call c;
        aqs_status st;
        memset(&c, 0, sizeof c);
        if (k == 2 * nb0) {
            c.op = OP_FINALIZE;
        } else if (k % 2 == 0) {
            static const double com[3] = {0.5, 0, 0};
            c.op = OP_BODY;
            c.d0 = 1.0;
            memcpy(c.v0, com, sizeof com);
            c.v2[0] = c.v2[4] = c.v2[8] = 0.1;
        } else {
            static const int32_t types[8] = {AQS_JOINT_REVOLUTE, AQS_JOINT_REVOLUTE, AQS_JOINT_PRISMATIC,
                                             AQS_JOINT_SPHERICAL, AQS_JOINT_FIXED, AQS_JOINT_UNIVERSAL,
                                             AQS_JOINT_CYLINDRICAL, AQS_JOINT_PLANAR};
            unsigned b = byte(&in);
            c.op = OP_JOINT;
            c.i2 = k / 2;
            c.i1 = c.i2 == 0 ? AQS_WORLD : (int32_t)((b >> 3) % (unsigned)(c.i2 + 1)) - 1;
            c.i0 = c.i2 == 0 && (b & 64) ? AQS_JOINT_FREE : types[b & 7];
            c.v0[0] = c.i2 ? 1.0 : 0.0;
            c.qt = quats[0];
            c.ax = axes[(b >> 6) % 3];
        }
        arm(&in, &inj);
        st = apply(S, &c);
        inj.fail_at = 0;
        if (st == AQS_OK && apply(T, &c) != AQS_OK) abort();
        compare(S, T, &inj, op_names[c.op], step++);
    }
    while (!done(&in)) {
        call c;
        aqs_status st, st_twin;
        int twin;
        long failed;
        decode(&in, S, &c);
        arm(&in, &inj);
        failed = inj.failed;
        st = apply(S, &c);
        inj.fail_at = 0;
        /* A solve, step or refine that did not fail for memory although an
           allocation failed answered without the refinement whose arrays it
           could not allocate (documented: docs/api.md, "Memory"): its
           accelerations may differ from the twin's in the last digits, a step
           may move elsewhere (or, moved, find a singular articulated inertia
           where the twin does not), and so may everything after it. The
           comparison ends there (the subject is still destroyed, and
           leak-checked, below). */
        if (st != AQS_ENOMEM && inj.failed > failed && (c.op == OP_SOLVE || c.op == OP_STEP || c.op == OP_REFINE))
            break;
        /* So does an AQS_ENOMEM of a solve or step whose articulated-body
           attempt ran before the hand-over to the exact DCA failed to allocate
           the DCA's storage: the previous results are gone (documented, as
           with AQS_ENUMERIC), which the twin, whose allocation succeeds,
           cannot repeat. Any other failure must leave them readable. */
        if (st == AQS_ENOMEM && (c.op == OP_SOLVE || c.op == OP_STEP)) {
            static double qd[MAXQ];
            if (aqs_linkage_get_accelerations(S, qd, MAXQ) != AQS_OK && aqs_linkage_get_accelerations(T, qd, MAXQ) == AQS_OK)
                break;
        }
        /* Numerical failures of solve, step and refine are the documented
           exception: the twin must fail the same way. */
        twin = st == AQS_OK ||
               (st == AQS_ENUMERIC && (c.op == OP_SOLVE || c.op == OP_STEP || c.op == OP_REFINE)) ||
               (st == AQS_ESIZE && c.op == OP_COLLIDE); /* the query ran; capacity was short */
        if (twin) {
            st_twin = apply(T, &c);
            if (st_twin != st) {
                fprintf(stderr, "api_fuzz: call %ld (%s): subject %d, twin %d (%s)\n", step,
                        op_names[c.op], (int)st, (int)st_twin, aqs_linkage_last_error(T));
                abort();
            }
        }
        compare(S, T, &inj, op_names[c.op], step++);
    }
    aqs_linkage_destroy(S);
    aqs_linkage_destroy(T);
    return 0;
}
