/* test_narrowphase.c -- the narrow phase (src/collide/narrowphase.c) against closed
 * forms: sphere-sphere, sphere-box, capsule-capsule, box-box face / edge /
 * corner, cylinder and hull, under random rigid motions of the pair; touching
 * and separated by 1e-12 (also in rotated placements: sphere on a box or hull
 * edge, on a cylinder's side, parallel capsules, test_separated_1e12_rotated);
 * shallow penetrations of 1e-12..1e-10 of the size in those placements with
 * the exact depth (test_shallow_rotated); degenerate cores; size ratios of
 * 1e4; degenerate cases (identical shapes, touching faces) give finite,
 * defined answers. The configurations put the minimum-translation direction
 * on the line of the shapes' centres, where MPR's depth is exact; off that
 * line MPR's depth is an approximation (docs/collision.md). Pairs with a
 * sphere or capsule are computed from the exact distance of its core, not by
 * MPR, except when the core itself touches a box, cylinder or hull.
 *
 * Tolerances of expect_contact (shared by MPR and core pairs): MPR refines
 * the portal to 1e-12 of the pair's size, so depths and normals are checked
 * to 1e-9 of the size (rounding of the random rigid motions included, about
 * 1e-15 per operation). Normals: 1e-9 between flat faces; on a curved
 * surface of radius r a direction error e costs only r e^2 / 2 of depth, so
 * a portal tolerance tau leaves normals known to about sqrt(2 tau / r),
 * 1.4e-6 here: checked to 1e-5. Contact points must lie inside both shapes
 * (closed-form inside tests), inflated by the same tolerance. The core pairs
 * are held to much tighter bounds in test_shallow_rotated (see there). */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "narrowphase.h"

#define PI 3.14159265358979323846

static void make(shape_def *s, int32_t type, double a, double b, double c)
{
    memset(s, 0, sizeof *s);
    s->type = type;
    s->size[0] = a;
    s->size[1] = b;
    s->size[2] = c;
    shape_bound(s);
}

/* The box of half-extents (hx, hy, hz) as the hull of its 8 corners (pts: 24 doubles). */
static void box_hull(shape_def *hull, double *pts, double hx, double hy, double hz)
{
    int i;
    for (i = 0; i < 8; i++) {
        pts[3 * i] = i & 1 ? hx : -hx;
        pts[3 * i + 1] = i & 2 ? hy : -hy;
        pts[3 * i + 2] = i & 4 ? hz : -hz;
    }
    memset(hull, 0, sizeof *hull);
    hull->type = AQS_SHAPE_HULL;
    hull->pts = pts;
    hull->npts = 8;
    shape_bound(hull);
}

/* A rigid motion of the whole pair: world = M * local. */
typedef struct {
    double R[9], p[3];
} motion;

static void random_motion(uint64_t *st, motion *M, double spread)
{
    double q[4];
    test_random_quat(st, q);
    test_quat_matrix(q, M->R);
    M->p[0] = test_uniform(st, -spread, spread);
    M->p[1] = test_uniform(st, -spread, spread);
    M->p[2] = test_uniform(st, -spread, spread);
}

static void identity_motion(motion *M)
{
    memset(M, 0, sizeof *M);
    M->R[0] = M->R[4] = M->R[8] = 1.0;
}

static void apply_dir(const motion *M, const double v[3], double out[3])
{
    int i;
    for (i = 0; i < 3; i++) out[i] = M->R[3 * i] * v[0] + M->R[3 * i + 1] * v[1] + M->R[3 * i + 2] * v[2];
}

/* Place s with local rotation Rl (NULL: identity) and position pl, then move by M. */
static void place(placed_shape *ps, const shape_def *s, const motion *M, const double *Rl,
                  double x, double y, double z)
{
    static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double pl[3] = {x, y, z}, w[3];
    ps->s = s;
    test_mat3_mul(M->R, Rl ? Rl : I, ps->world.R);
    apply_dir(M, pl, w);
    ps->world.p[0] = w[0] + M->p[0];
    ps->world.p[1] = w[1] + M->p[1];
    ps->world.p[2] = w[2] + M->p[2];
}

/* Closed-form distance outside a shape (<= 0 inside), shape frame. */
static double outside(const placed_shape *ps, const double x[3])
{
    const shape_def *s = ps->s;
    double d[3], l[3], e, r;
    int i;
    for (i = 0; i < 3; i++) d[i] = x[i] - ps->world.p[i];
    for (i = 0; i < 3; i++) l[i] = ps->world.R[i] * d[0] + ps->world.R[3 + i] * d[1] + ps->world.R[6 + i] * d[2];
    switch (s->type) {
    case AQS_SHAPE_SPHERE: return sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]) - s->size[0];
    case AQS_SHAPE_CAPSULE:
        e = fmax(-s->size[1], fmin(s->size[1], l[2]));
        return sqrt(l[0] * l[0] + l[1] * l[1] + (l[2] - e) * (l[2] - e)) - s->size[0];
    case AQS_SHAPE_BOX:
        r = -1e300;
        for (i = 0; i < 3; i++) r = fmax(r, fabs(l[i]) - s->size[i]);
        return r;
    case AQS_SHAPE_CYLINDER:
        return fmax(sqrt(l[0] * l[0] + l[1] * l[1]) - s->size[0], fabs(l[2]) - s->size[1]);
    default: return -1.0; /* hulls: not checked */
    }
}

/* Contact of a and b must exist with the given depth and normal (normal_local
 * given before the motion M) and a point inside both shapes. */
static void expect_contact(const placed_shape *a, const placed_shape *b, const motion *M,
                           double depth, const double normal_local[3])
{
    double dep, n[3], p[3], nw[3], scale = a->s->radius + b->s->radius, tol = 1e-9 * scale;
    int flat = (a->s->type == AQS_SHAPE_BOX || a->s->type == AQS_SHAPE_HULL) &&
               (b->s->type == AQS_SHAPE_BOX || b->s->type == AQS_SHAPE_HULL);
    assert_int_equal(narrow_contact(a, b, &dep, n, p), 1);
    apply_dir(M, normal_local, nw);
    if (fabs(dep - depth) > tol || test_max_abs_diff(n, nw, 3) > (flat ? 1e-9 : 1e-5)) {
        print_error("depth %.17g (want %.17g), normal %g %g %g (want %g %g %g)\n", dep, depth, n[0],
                    n[1], n[2], nw[0], nw[1], nw[2]);
        fail();
    }
    assert_true(outside(a, p) <= tol);
    assert_true(outside(b, p) <= tol);
}

static void expect_none(const placed_shape *a, const placed_shape *b)
{
    double dep = -1, n[3], p[3];
    assert_int_equal(narrow_contact(a, b, &dep, n, p), 0);
}

static const double X[3] = {1, 0, 0}, Y[3] = {0, 1, 0}, Z[3] = {0, 0, 1};

static void test_sphere_sphere(void **state)
{
    uint64_t st = 11;
    shape_def s1, s2;
    placed_shape a, b;
    motion M;
    int k;
    make(&s1, AQS_SHAPE_SPHERE, 1.0, 0, 0);
    make(&s2, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    for (k = 0; k < 50; k++) {
        double d = test_uniform(&st, 0.6, 1.49);
        random_motion(&st, &M, 10.0);
        place(&a, &s1, &M, NULL, 0, 0, 0);
        place(&b, &s2, &M, NULL, d, 0, 0);
        expect_contact(&a, &b, &M, 1.5 - d, X);
        place(&b, &s2, &M, NULL, 1.5 + 1e-9 + d, 0, 0);
        expect_none(&a, &b);
    }
}

static void test_sphere_box(void **state)
{
    uint64_t st = 12;
    shape_def bx, sp;
    placed_shape a, b;
    motion M;
    int k;
    make(&bx, AQS_SHAPE_BOX, 1.0, 2.0, 3.0);
    make(&sp, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    for (k = 0; k < 50; k++) {
        double delta = test_uniform(&st, 1e-6, 0.4);
        random_motion(&st, &M, 10.0);
        place(&a, &bx, &M, NULL, 0, 0, 0);
        place(&b, &sp, &M, NULL, 0, 2.5 - delta, 0); /* on the +y face */
        expect_contact(&a, &b, &M, delta, Y);
        place(&b, &sp, &M, NULL, 0, 0, -(3.5 - delta)); /* under the -z face */
        {
            const double mz[3] = {0, 0, -1};
            expect_contact(&a, &b, &M, delta, mz);
        }
        place(&b, &sp, &M, NULL, 1.5 + 1e-9, 0, 0);
        expect_none(&a, &b);
    }
}

static void test_capsule_capsule(void **state)
{
    uint64_t st = 13;
    shape_def c1, c2;
    placed_shape a, b;
    motion M;
    double Rx[9];
    const double xaxis[3] = {1, 0, 0};
    int k;
    make(&c1, AQS_SHAPE_CAPSULE, 0.3, 1.0, 0);
    make(&c2, AQS_SHAPE_CAPSULE, 0.2, 2.0, 0);
    test_rodrigues(xaxis, (0.5 * PI), Rx); /* c2 along y: crossed */
    for (k = 0; k < 50; k++) {
        double d = test_uniform(&st, 0.3, 0.499);
        random_motion(&st, &M, 10.0);
        place(&a, &c1, &M, NULL, 0, 0, 0);
        place(&b, &c2, &M, NULL, d, 0, 0); /* parallel, side by side */
        expect_contact(&a, &b, &M, 0.5 - d, X);
        place(&b, &c2, &M, Rx, d, 0, 0); /* crossed */
        expect_contact(&a, &b, &M, 0.5 - d, X);
        place(&b, &c2, &M, NULL, 0, 0, 3.0 + d); /* end to end along z */
        expect_contact(&a, &b, &M, 0.5 - d, Z);
        place(&b, &c2, &M, Rx, 0.5 + 1e-9, 0, 0);
        expect_none(&a, &b);
    }
}

static void test_box_box(void **state)
{
    uint64_t st = 14;
    shape_def b1, b2;
    placed_shape a, b;
    motion M;
    double Redge[9], Rcorner[9];
    const double zaxis[3] = {0, 0, 1};
    /* Rotation taking the cube diagonal (1,1,1)/sqrt3 onto -x: axis d x (-x), angle acos(-1/sqrt3). */
    const double axis[3] = {0, -1, 1};
    int k;
    make(&b1, AQS_SHAPE_BOX, 1.0, 1.5, 2.0);
    make(&b2, AQS_SHAPE_BOX, 0.5, 0.5, 0.5);
    test_rodrigues(zaxis, (0.25 * PI), Redge);
    test_rodrigues(axis, acos(-1.0 / sqrt(3.0)), Rcorner);
    for (k = 0; k < 50; k++) {
        double delta = test_uniform(&st, 1e-6, 0.2);
        random_motion(&st, &M, 10.0);
        place(&a, &b1, &M, NULL, 0, 0, 0);
        place(&b, &b2, &M, NULL, 1.5 - delta, 0.1, -0.2); /* face on face */
        expect_contact(&a, &b, &M, delta, X);
        place(&b, &b2, &M, Redge, 1.0 + 0.5 * sqrt(2.0) - delta, 0, 0); /* edge on face */
        expect_contact(&a, &b, &M, delta, X);
        place(&b, &b2, &M, Rcorner, 1.0 + 0.5 * sqrt(3.0) - delta, 0, 0); /* corner on face */
        expect_contact(&a, &b, &M, delta, X);
        place(&b, &b2, &M, Rcorner, 1.0 + 0.5 * sqrt(3.0) + 1e-9, 0, 0);
        expect_none(&a, &b);
    }
}

static void test_cylinder_and_hull(void **state)
{
    uint64_t st = 15;
    shape_def cy, sp, hull, box;
    placed_shape a, b, h, c;
    motion M;
    double pts[24];
    int k;
    make(&cy, AQS_SHAPE_CYLINDER, 1.0, 2.0, 0);
    make(&sp, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    make(&box, AQS_SHAPE_BOX, 0.5, 0.7, 0.9);
    box_hull(&hull, pts, 0.5, 0.7, 0.9); /* the box as a hull of its corners */
    assert_true(fabs(hull.radius - box.radius) < 1e-15);
    for (k = 0; k < 50; k++) {
        double delta = test_uniform(&st, 1e-6, 0.4), depth, n1[3], n2[3], p1[3], p2[3], d2;
        random_motion(&st, &M, 10.0);
        place(&a, &cy, &M, NULL, 0, 0, 0);
        place(&b, &sp, &M, NULL, 1.5 - delta, 0, 0); /* side */
        expect_contact(&a, &b, &M, delta, X);
        place(&b, &sp, &M, NULL, 0, 0, 2.5 - delta); /* cap */
        expect_contact(&a, &b, &M, delta, Z);
        /* hull == box, against the cylinder at a random offset */
        place(&h, &hull, &M, NULL, 1.2, 0.3, 0.5);
        place(&c, &box, &M, NULL, 1.2, 0.3, 0.5);
        assert_int_equal(narrow_contact(&a, &h, &depth, n1, p1), 1);
        assert_int_equal(narrow_contact(&a, &c, &d2, n2, p2), 1);
        assert_true(fabs(depth - d2) < 1e-12 && test_max_abs_diff(n1, n2, 3) < 1e-12);
    }
}

static void test_touching_and_separated(void **state)
{
    uint64_t st = 16;
    shape_def s1, s2, b1;
    placed_shape a, b;
    motion I;
    double dep, n[3], p[3];
    int k, r;
    identity_motion(&I);
    make(&s1, AQS_SHAPE_SPHERE, 1.0, 0, 0);
    make(&s2, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    make(&b1, AQS_SHAPE_BOX, 1.0, 1.0, 1.0);
    /* Separated by 1e-12: no contact. Penetrating by 1e-9: depth 1e-9 to 1e-15. */
    place(&a, &s1, &I, NULL, 0, 0, 0);
    place(&b, &s2, &I, NULL, 1.5 + 1e-12, 0, 0);
    expect_none(&a, &b);
    place(&b, &s2, &I, NULL, 1.5 - 1e-9, 0, 0);
    assert_int_equal(narrow_contact(&a, &b, &dep, n, p), 1);
    assert_true(fabs(dep - 1e-9) < 1e-15);
    place(&a, &b1, &I, NULL, 0, 0, 0);
    place(&b, &b1, &I, NULL, 2.0 + 1e-12, 0.3, 0);
    expect_none(&a, &b);
    place(&b, &b1, &I, NULL, 2.0 - 1e-9, 0.3, 0);
    assert_int_equal(narrow_contact(&a, &b, &dep, n, p), 1);
    assert_true(fabs(dep - 1e-9) < 1e-15);
    /* Exactly touching (faces, edges, corners, spheres), under random
     * motions: whatever libccd decides, the answer is finite, the depth is
     * at most rounding, the normal unit. */
    for (k = 0; k < 400; k++) {
        motion M;
        double off[3] = {2.0, 0, 0};
        int j;
        random_motion(&st, &M, 10.0);
        if (k % 4 == 1) off[1] = 2.0;
        if (k % 4 == 2) off[1] = off[2] = 2.0;
        if (k % 4 == 3) off[1] = test_uniform(&st, -1.0, 1.0);
        place(&a, &b1, &M, NULL, 0, 0, 0);
        place(&b, &b1, &M, NULL, off[0], off[1], off[2]);
        r = narrow_contact(&a, &b, &dep, n, p);
        if (r) {
            assert_true(isfinite(dep) && dep >= 0.0 && dep < 1e-12);
            assert_true(fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-12);
            for (j = 0; j < 3; j++) assert_true(isfinite(p[j]));
        }
        place(&a, &s1, &M, NULL, 0, 0, 0);
        place(&b, &s2, &M, NULL, 1.5, 0, 0);
        r = narrow_contact(&a, &b, &dep, n, p);
        if (r) assert_true(isfinite(dep) && dep >= 0.0 && dep < 1e-12 && isfinite(n[0] + n[1] + n[2] + p[0] + p[1] + p[2]));
    }
}

static void test_identical_shapes(void **state)
{
    uint64_t st = 17;
    const int32_t types[4] = {AQS_SHAPE_SPHERE, AQS_SHAPE_CAPSULE, AQS_SHAPE_BOX, AQS_SHAPE_CYLINDER};
    int k, t;
    for (t = 0; t < 4; t++) {
        shape_def s;
        make(&s, types[t], 0.7, 0.4, 0.9);
        for (k = 0; k < 20; k++) {
            placed_shape a, b;
            motion M;
            double dep, n[3], p[3];
            random_motion(&st, &M, 5.0);
            place(&a, &s, &M, NULL, 0, 0, 0);
            place(&b, &s, &M, NULL, 0, 0, 0);
            assert_int_equal(narrow_contact(&a, &b, &dep, n, p), 1);
            if (!(isfinite(dep) && dep > 0.0 && dep <= 2.0 * s.radius * (1.0 + 1e-12))) {
                print_error("type %d: depth %.17g, bound radius %g\n", (int)types[t], dep, s.radius);
                fail();
            }
            assert_true(fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-12);
            assert_true(isfinite(p[0] + p[1] + p[2]));
            if (types[t] == AQS_SHAPE_SPHERE) assert_true(fabs(dep - 1.4) < 1e-9);
        }
    }
}

static void test_size_ratio_1e4(void **state)
{
    uint64_t st = 18;
    shape_def big, small, bigbox, smallbox;
    placed_shape a, b;
    motion M;
    int k;
    make(&big, AQS_SHAPE_SPHERE, 1e4, 0, 0);
    make(&small, AQS_SHAPE_SPHERE, 1.0, 0, 0);
    make(&bigbox, AQS_SHAPE_BOX, 1e4, 1e4, 1e4);
    make(&smallbox, AQS_SHAPE_BOX, 1.0, 1.0, 1.0);
    for (k = 0; k < 30; k++) {
        double delta = test_uniform(&st, 1e-3, 0.5);
        random_motion(&st, &M, 100.0);
        place(&a, &big, &M, NULL, 0, 0, 0);
        place(&b, &small, &M, NULL, 0, 0, 1e4 + 1.0 - delta);
        expect_contact(&a, &b, &M, delta, Z);
        place(&a, &bigbox, &M, NULL, 0, 0, 0);
        place(&b, &smallbox, &M, NULL, 3.0, -7.0, 1e4 + 1.0 - delta);
        expect_contact(&a, &b, &M, delta, Z);
        place(&b, &smallbox, &M, NULL, 3.0, -7.0, 1e4 + 1.0 + 1e-6);
        expect_none(&a, &b);
    }
}

/* Separated by 1e-12 under random rigid motions (a random rotation and a
 * translation of up to 10) and in rotated relative placements. The gap is
 * exact in the local frame: the sphere centre is r + 1e-12 from the box's
 * face, edge or corner (or the cylinder's side) along its outward normal;
 * for the capsules the closest points of the two segments are known in
 * closed form and r1 + r2 + 1e-12 apart.
 *
 * Acceptance: the rule of the identity-placement cases of
 * test_touching_and_separated, no contact at all. Justification: the motion
 * moves the placements by a few ulps of coordinates of at most ~15, about
 * 1e-14, a hundredth of the gap, so the shapes stay strictly apart. MPR alone
 * broke this rule where the Minkowski difference is flat one way and curved
 * the other (sphere on a box or hull edge, on a cylinder's side; parallel
 * capsules): spurious contacts in 17-28% of the motions (docs/collision.md).
 * Every pair with a sphere or capsule is now decided from the exact distance
 * of its core (src/collide/narrowphase.c), and those configurations are here too. */
static void test_separated_1e12_rotated(void **state)
{
    uint64_t st = 19;
    const double g = 1e-12, s2 = sqrt(2.0), s3 = sqrt(3.0);
    const double xaxis[3] = {1, 0, 0}, yaxis[3] = {0, 1, 0};
    shape_def bx, sp, c1, c2, cy, hull;
    placed_shape a, b;
    motion M;
    double Rx[9], pts[24];
    int k;
    make(&bx, AQS_SHAPE_BOX, 1.0, 2.0, 3.0);
    make(&sp, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    make(&c1, AQS_SHAPE_CAPSULE, 0.3, 1.0, 0); /* segment z in [-1, 1] */
    make(&c2, AQS_SHAPE_CAPSULE, 0.2, 2.0, 0); /* segment z in [-2, 2] */
    make(&cy, AQS_SHAPE_CYLINDER, 1.0, 2.0, 0);
    box_hull(&hull, pts, 1.0, 2.0, 3.0); /* the box as a hull of its corners */
    test_rodrigues(xaxis, 0.5 * PI, Rx); /* c2 along y */
    for (k = 0; k < 200; k++) {
        double th = test_uniform(&st, 0.1, PI - 0.1), phi = test_uniform(&st, 0.0, 0.8), d = 0.5 + g;
        double Rth[9], Rphi[9];
        random_motion(&st, &M, 10.0);
        /* sphere - box */
        place(&a, &bx, &M, NULL, 0, 0, 0);
        place(&b, &sp, &M, NULL, 0.3, 2.0 + d, -0.7); /* off-centre on the +y face */
        expect_none(&a, &b);
        place(&b, &sp, &M, NULL, 1.0 + d / s3, 2.0 + d / s3, 3.0 + d / s3); /* the (+, +, +) corner */
        expect_none(&a, &b);
        place(&b, &sp, &M, NULL, 1.0 + d / s2, 2.0 + d / s2, 0.4); /* the (+x, +y) edge */
        expect_none(&a, &b);
        place(&a, &hull, &M, NULL, 0, 0, 0); /* the same edge of the box as a hull */
        expect_none(&a, &b);
        /* sphere and capsule c1 (axis z) beside the cylinder's side */
        place(&a, &cy, &M, NULL, 0, 0, 0);
        place(&b, &sp, &M, NULL, 1.0 + d, 0, 0.3);
        expect_none(&a, &b);
        place(&b, &c1, &M, NULL, 1.3 + g, 0, 0.3);
        expect_none(&a, &b);
        /* capsule - capsule */
        place(&a, &c1, &M, NULL, 0, 0, 0);
        place(&b, &c2, &M, Rx, d, 0, 0); /* crossed */
        expect_none(&a, &b);
        /* skew: c2's axis (0, -sin th, cos th) through (d, 0, 0); closest points: the centres */
        test_rodrigues(xaxis, th, Rth);
        place(&b, &c2, &M, Rth, d, 0, 0);
        expect_none(&a, &b);
        place(&b, &c2, &M, NULL, 0, 0, 1.0 + d + 2.0); /* end to end along z */
        expect_none(&a, &b);
        place(&b, &c2, &M, Rx, 0, 0, 1.0 + d); /* c1's end against c2's side */
        expect_none(&a, &b);
        /* tilted end to end: c2's axis u = (sin phi, 0, cos phi), its lower end at
         * (0, 0, 1) + d u, its centre 2 further along u; closest points: the two ends */
        test_rodrigues(yaxis, phi, Rphi);
        place(&b, &c2, &M, Rphi, (d + 2.0) * sin(phi), 0, 1.0 + (d + 2.0) * cos(phi));
        expect_none(&a, &b);
        place(&b, &c2, &M, NULL, d, 0, 0.3); /* parallel, side by side */
        expect_none(&a, &b);
    }
}

/* A contact whose depth, normal and point are known to rounding: the exact
 * distance of the cores. */
static void expect_exact(const placed_shape *a, const placed_shape *b, const motion *M, double depth,
                         const double normal_local[3])
{
    double dep, n[3], p[3], nw[3], scale = a->s->radius + b->s->radius;
    assert_int_equal(narrow_contact(a, b, &dep, n, p), 1);
    apply_dir(M, normal_local, nw);
    if (fabs(dep - depth) > 1e-13 * scale || test_max_abs_diff(n, nw, 3) > 1e-12) {
        print_error("depth %.17g (want %.17g, error %.3g of the size), normal %.17g %.17g %.17g (want %.17g %.17g %.17g)\n",
                    dep, depth, fabs(dep - depth) / scale, n[0], n[1], n[2], nw[0], nw[1], nw[2]);
        fail();
    }
    assert_true(outside(a, p) <= 1e-13 * scale);
    assert_true(outside(b, p) <= 1e-13 * scale);
}

/* Shallow penetrations (1e-12, 1e-11 and 1e-10 of the pair's size) under
 * the rotated placements of test_separated_1e12_rotated where MPR failed:
 * sphere on a box edge (also as a hull), on a cylinder's side, parallel
 * capsules, a capsule beside a cylinder. MPR found the 1e-12 ones in only
 * 22-55% of the motions and was off by up to 4.5e-9 in depth; the core
 * distance must find every one with the exact depth.
 *
 * Tolerance: depth to 1e-13 of the pair's size (4e-13 here), normal to
 * 1e-12, point inside both shapes to 1e-13 of the size. Justification: the
 * placements are exact up to the rounding of coordinates of at most ~15,
 * ~2e-15 each, and the core distance is a few operations on them (measured
 * over 20,000 motions per case: depth errors <= 3.2e-15); the normal is the
 * direction of the closest points, ~0.5 apart, so its rounding is ~1e-14. */
static void test_shallow_rotated(void **state)
{
    uint64_t st = 20;
    const double s2 = sqrt(2.0), fr[3] = {1e-12, 1e-11, 1e-10};
    const double xy[3] = {1.0 / sqrt(2.0), 1.0 / sqrt(2.0), 0};
    shape_def bx, sp, c1, c2, cy, hull;
    placed_shape a, b;
    motion M;
    double pts[24];
    int k, f;
    make(&bx, AQS_SHAPE_BOX, 1.0, 2.0, 3.0);
    make(&sp, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    make(&c1, AQS_SHAPE_CAPSULE, 0.3, 1.0, 0);
    make(&c2, AQS_SHAPE_CAPSULE, 0.2, 2.0, 0);
    make(&cy, AQS_SHAPE_CYLINDER, 1.0, 2.0, 0);
    box_hull(&hull, pts, 1.0, 2.0, 3.0); /* the box as a hull of its corners */
    for (k = 0; k < 200; k++) {
        random_motion(&st, &M, 10.0);
        for (f = 0; f < 3; f++) {
            double pen = fr[f] * (bx.radius + sp.radius), d = 0.5 - pen;
            /* sphere on the (+x, +y) edge: the normal from the box to the sphere is (1, 1, 0) / sqrt 2 */
            place(&a, &bx, &M, NULL, 0, 0, 0);
            place(&b, &sp, &M, NULL, 1.0 + d / s2, 2.0 + d / s2, 0.4);
            expect_exact(&a, &b, &M, pen, xy);
            /* sphere first: the same contact seen from the other side */
            {
                const double yx[3] = {-xy[0], -xy[1], 0};
                expect_exact(&b, &a, &M, pen, yx);
            }
            place(&a, &hull, &M, NULL, 0, 0, 0);
            expect_exact(&a, &b, &M, pen, xy);
            /* sphere and capsule beside the cylinder */
            pen = fr[f] * (cy.radius + sp.radius);
            place(&a, &cy, &M, NULL, 0, 0, 0);
            place(&b, &sp, &M, NULL, 1.5 - pen, 0, 0.3);
            expect_exact(&a, &b, &M, pen, X);
            pen = fr[f] * (cy.radius + c1.radius);
            place(&b, &c1, &M, NULL, 1.3 - pen, 0, 0.3);
            expect_exact(&a, &b, &M, pen, X);
            /* parallel capsules side by side */
            pen = fr[f] * (c1.radius + c2.radius);
            place(&a, &c1, &M, NULL, 0, 0, 0);
            place(&b, &c2, &M, NULL, 0.5 - pen, 0, 0.3);
            expect_exact(&a, &b, &M, pen, X);
        }
    }
}

/* Degenerate inputs of the core distance: coincident centres and cores,
 * cores that cross or touch, a sphere centred on a face, edge or corner of
 * a box or on a cylinder's axis, a capsule whose core is almost a point or
 * passes through a box. Every answer finite, a unit normal, and the depth
 * in closed form where it is known. */
static void check_finite(const placed_shape *a, const placed_shape *b, double want)
{
    double dep = -1, n[3], p[3];
    assert_int_equal(narrow_contact(a, b, &dep, n, p), 1);
    assert_true(isfinite(dep) && dep >= 0.0);
    assert_true(fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) < 1e-12);
    assert_true(isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]));
    if (want >= 0.0 && !(fabs(dep - want) <= 1e-12)) {
        print_error("depth %.17g, want %.17g\n", dep, want);
        fail();
    }
}

static void test_core_degenerate(void **state)
{
    uint64_t st = 21;
    const double xaxis[3] = {1, 0, 0};
    shape_def s1, s2, c1, c2, cdot, bx, cy;
    placed_shape a, b;
    motion M;
    double Rx[9], dep, n[3], p[3], w[3];
    int k;
    make(&s1, AQS_SHAPE_SPHERE, 1.0, 0, 0);
    make(&s2, AQS_SHAPE_SPHERE, 0.5, 0, 0);
    make(&c1, AQS_SHAPE_CAPSULE, 0.3, 1.0, 0);
    make(&c2, AQS_SHAPE_CAPSULE, 0.2, 2.0, 0);
    make(&cdot, AQS_SHAPE_CAPSULE, 0.2, 1e-300, 0);
    make(&bx, AQS_SHAPE_BOX, 1.0, 2.0, 3.0);
    make(&cy, AQS_SHAPE_CYLINDER, 1.0, 2.0, 0);
    test_rodrigues(xaxis, 0.5 * PI, Rx);
    for (k = 0; k < 50; k++) {
        random_motion(&st, &M, 10.0);
        place(&a, &s1, &M, NULL, 0, 0, 0);
        place(&b, &s2, &M, NULL, 0, 0, 0); /* concentric */
        check_finite(&a, &b, 1.5);
        place(&b, &c1, &M, NULL, 0, 0, 0); /* sphere at a capsule's centre */
        check_finite(&a, &b, 1.3);
        place(&a, &c1, &M, NULL, 0, 0, 0);
        place(&b, &c1, &M, NULL, 0, 0, 0); /* coincident capsules */
        check_finite(&a, &b, 0.6);
        place(&b, &c2, &M, NULL, 0, 0, 0.5); /* parallel cores overlapping */
        check_finite(&a, &b, 0.5);
        place(&b, &c2, &M, Rx, 0, 0, 0.3); /* cores crossing: the normal across both */
        assert_int_equal(narrow_contact(&a, &b, &dep, n, p), 1);
        apply_dir(&M, X, w);
        assert_true(fabs(dep - 0.5) < 1e-12 && fabs(fabs(vec3_dot(n, w)) - 1.0) < 1e-12);
        place(&b, &c2, &M, Rx, 0, 0, 1.0); /* c1's end on c2's core */
        check_finite(&a, &b, 0.5);
        place(&b, &cdot, &M, NULL, 0.1, 0, 0.5); /* a capsule that is almost a sphere */
        check_finite(&a, &b, 0.5 - 0.1);
        /* a sphere centred inside a box: its radius plus its depth below the nearest face */
        place(&a, &bx, &M, NULL, 0, 0, 0);
        place(&b, &s2, &M, NULL, 0, 0, 0);
        check_finite(&a, &b, 0.5 + 1.0);
        place(&b, &s2, &M, NULL, 1.0, 0.5, 0.5); /* on the +x face */
        check_finite(&a, &b, -1.0);
        place(&b, &s2, &M, NULL, 1.0, 2.0, 0.5); /* on an edge */
        check_finite(&a, &b, -1.0);
        place(&b, &s2, &M, NULL, 1.0, 2.0, 3.0); /* on a corner */
        check_finite(&a, &b, -1.0);
        place(&b, &cdot, &M, NULL, 0.9, 0.5, 0.5); /* an almost-point capsule core inside */
        check_finite(&a, &b, -1.0);
        place(&b, &c2, &M, Rx, 0.5, 0, 0); /* a capsule core through the box: MPR */
        check_finite(&a, &b, -1.0);
        place(&b, &cdot, &M, NULL, 1.0, 2.0, 3.0 + 0.1); /* above the corner: exact */
        check_finite(&a, &b, 0.1);
        place(&a, &cy, &M, NULL, 0, 0, 0);
        place(&b, &s2, &M, NULL, 0, 0, 0); /* on the cylinder's axis */
        check_finite(&a, &b, 0.5 + 1.0);
        place(&b, &s2, &M, NULL, 0, 0, 1.9);
        check_finite(&a, &b, 0.5 + 0.1);
        place(&b, &c1, &M, NULL, 0, 0, 0.5); /* a capsule core along the axis: MPR */
        check_finite(&a, &b, -1.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_sphere),
        cmocka_unit_test(test_sphere_box),
        cmocka_unit_test(test_capsule_capsule),
        cmocka_unit_test(test_box_box),
        cmocka_unit_test(test_cylinder_and_hull),
        cmocka_unit_test(test_touching_and_separated),
        cmocka_unit_test(test_separated_1e12_rotated),
        cmocka_unit_test(test_shallow_rotated),
        cmocka_unit_test(test_core_degenerate),
        cmocka_unit_test(test_identical_shapes),
        cmocka_unit_test(test_size_ratio_1e4),
    };
    return cmocka_run_group_tests_name("narrowphase", tests, NULL, NULL);
}
