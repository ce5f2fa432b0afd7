/* test_shape.c -- src/collide/shape.c: size and hull validation, support points
 * against brute force over sampled surface points, bounding spheres
 * enclosing every support point. */
#include "testutil.h"

#include <math.h>
#include <string.h>

#include "shape.h"

static void make(shape_def *s, int32_t type, double a, double b, double c)
{
    memset(s, 0, sizeof *s);
    s->type = type;
    s->size[0] = a;
    s->size[1] = b;
    s->size[2] = c;
    shape_bound(s);
}

/* A point of the shape's surface from three uniforms (closed forms). */
static void surface_point(const shape_def *s, double u, double v, double w, double x[3])
{
    const double *z = s->size, tp = 6.283185307179586;
    double th = tp * u, ph = acos(2.0 * v - 1.0);
    double dir[3] = {sin(ph) * cos(th), sin(ph) * sin(th), cos(ph)};
    int i;
    switch (s->type) {
    case AQS_SHAPE_SPHERE:
        for (i = 0; i < 3; i++) x[i] = z[0] * dir[i];
        break;
    case AQS_SHAPE_CAPSULE:
        for (i = 0; i < 3; i++) x[i] = z[0] * dir[i];
        x[2] += (2.0 * w - 1.0) * z[1];
        break;
    case AQS_SHAPE_BOX:
        x[0] = (2.0 * u - 1.0) * z[0];
        x[1] = (2.0 * v - 1.0) * z[1];
        x[2] = (2.0 * w - 1.0) * z[2];
        x[(int)(3.0 * w) % 3] = (v < 0.5 ? -1.0 : 1.0) * z[(int)(3.0 * w) % 3];
        break;
    default: /* cylinder: rim circle at a random height, or a cap disc point */
        x[0] = z[0] * cos(th) * (w < 0.5 ? 1.0 : sqrt(v));
        x[1] = z[0] * sin(th) * (w < 0.5 ? 1.0 : sqrt(v));
        x[2] = w < 0.5 ? (2.0 * v - 1.0) * z[1] : (w < 0.75 ? -z[1] : z[1]);
        break;
    }
}

static void test_support_is_extreme(void **state)
{
    uint64_t st = 3;
    const int32_t types[4] = {AQS_SHAPE_SPHERE, AQS_SHAPE_CAPSULE, AQS_SHAPE_BOX, AQS_SHAPE_CYLINDER};
    int t, k, m;
    for (t = 0; t < 4; t++) {
        shape_def s;
        make(&s, types[t], 0.4, 0.9, 0.25);
        for (k = 0; k < 200; k++) {
            double d[3], sp[3], best = -1e300, sd, r;
            for (m = 0; m < 3; m++) d[m] = test_uniform(&st, -1, 1);
            if (k == 0) d[0] = d[1] = 0.0; /* along the axis: the tie-breaks */
            shape_support(&s, d, sp);
            sd = d[0] * sp[0] + d[1] * sp[1] + d[2] * sp[2];
            for (m = 0; m < 2000; m++) {
                double x[3];
                surface_point(&s, test_uniform(&st, 0, 1), test_uniform(&st, 0, 1), test_uniform(&st, 0, 1), x);
                best = fmax(best, d[0] * x[0] + d[1] * x[1] + d[2] * x[2]);
            }
            /* No sampled point beats the support point (1e-12: rounding). */
            assert_true(best <= sd + 1e-12);
            /* The support point is within the bounding sphere. */
            r = sqrt(sp[0] * sp[0] + sp[1] * sp[1] + sp[2] * sp[2]);
            assert_true(r <= s.radius * (1.0 + 1e-12));
        }
        /* A zero direction still gives a point of the shape. */
        {
            double zero[3] = {0, 0, 0}, sp[3];
            shape_support(&s, zero, sp);
            assert_true(sqrt(sp[0] * sp[0] + sp[1] * sp[1] + sp[2] * sp[2]) <= s.radius * (1.0 + 1e-12));
        }
    }
}

static void test_hull_support_and_bound(void **state)
{
    uint64_t st = 4;
    double pts[60];
    shape_def s;
    int k, m;
    for (k = 0; k < 60; k++) pts[k] = test_uniform(&st, -1, 1);
    memset(&s, 0, sizeof s);
    s.type = AQS_SHAPE_HULL;
    s.pts = pts;
    s.npts = 20;
    assert_int_equal(shape_check_hull(pts, 20), 0);
    shape_bound(&s);
    for (k = 0; k < 20; k++) {
        double d[3] = {pts[3 * k] - s.centre[0], pts[3 * k + 1] - s.centre[1], pts[3 * k + 2] - s.centre[2]};
        assert_true(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) <= s.radius);
    }
    for (k = 0; k < 100; k++) {
        double d[3] = {test_uniform(&st, -1, 1), test_uniform(&st, -1, 1), test_uniform(&st, -1, 1)}, sp[3];
        double best = -1e300;
        shape_support(&s, d, sp);
        for (m = 0; m < 20; m++) best = fmax(best, d[0] * pts[3 * m] + d[1] * pts[3 * m + 1] + d[2] * pts[3 * m + 2]);
        assert_true(d[0] * sp[0] + d[1] * sp[1] + d[2] * sp[2] == best);
    }
}

static void test_validation(void **state)
{
    const double good[3] = {1, 2, 3}, nan3[3] = {1, NAN, 3}, neg[3] = {1, -2, 3};
    const double cube[24] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1};
    double flat[24], line[12] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3}, bad[24];
    int k;
    assert_int_equal(shape_check_size(AQS_SHAPE_BOX, good), 0);
    assert_int_equal(shape_check_size(AQS_SHAPE_BOX, nan3), 2);
    assert_int_equal(shape_check_size(AQS_SHAPE_BOX, neg), 2);
    assert_int_equal(shape_check_size(AQS_SHAPE_SPHERE, neg), 0);  /* size[1] unused, finite */
    assert_int_equal(shape_check_size(AQS_SHAPE_SPHERE, nan3), 2); /* unused but not finite */
    assert_int_equal(shape_check_size(AQS_SHAPE_CAPSULE, neg), 2);
    assert_int_equal(shape_check_size(AQS_SHAPE_HULL, good), -1);
    assert_int_equal(shape_check_size(9, good), -1);
    assert_int_equal(shape_check_hull(cube, 8), 0);
    assert_int_equal(shape_check_hull(cube, 3), -1);
    memcpy(flat, cube, sizeof flat);
    for (k = 0; k < 8; k++) flat[3 * k + 2] = 0.5 + 1e-12 * (k % 2); /* coplanar within 1e-9 */
    assert_int_equal(shape_check_hull(flat, 8), -2);
    flat[2] = 0.5 + 1e-6; /* out of the plane by 1e-6 of the extent: a thin but valid hull */
    assert_int_equal(shape_check_hull(flat, 8), 0);
    assert_int_equal(shape_check_hull(line, 4), -2);
    memset(bad, 0, sizeof bad);
    assert_int_equal(shape_check_hull(bad, 8), -2); /* all points equal */
    memcpy(bad, cube, sizeof bad);
    bad[13] = INFINITY;
    assert_int_equal(shape_check_hull(bad, 8), 14);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_support_is_extreme),
        cmocka_unit_test(test_hull_support_and_bound),
        cmocka_unit_test(test_validation),
    };
    return cmocka_run_group_tests_name("shape", tests, NULL, NULL);
}
