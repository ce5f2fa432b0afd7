/* shape.c -- convex shapes: validation, bounding spheres, support points. */
#include "shape.h"

#include <math.h>
#include <string.h>

#include "aqs.h"

int shape_check_size(int32_t type, const double size[3])
{
    int n, i;
    switch (type) {
    case AQS_SHAPE_SPHERE: n = 1; break;
    case AQS_SHAPE_CAPSULE: n = 2; break;
    case AQS_SHAPE_BOX: n = 3; break;
    case AQS_SHAPE_CYLINDER: n = 2; break;
    default: return -1;
    }
    for (i = 0; i < 3; i++)
        if (!isfinite(size[i])) return i + 1;
    for (i = 0; i < n; i++)
        if (!(size[i] >= SHAPE_MIN && size[i] <= SHAPE_MAX)) return i + 1;
    return 0;
}

/* Point i less point 0, over the scale sc (exact when sc is a power of 2). */
static void hull_diff(const double *p, int32_t i, double sc, double d[3])
{
    d[0] = (p[3 * i] - p[0]) / sc;
    d[1] = (p[3 * i + 1] - p[1]) / sc;
    d[2] = (p[3 * i + 2] - p[2]) / sc;
}

int shape_check_hull(const double *p, int32_t n)
{
    int32_t i, j, k, l;
    double ext = 0.0, best = 0.0, e1[3], nrm[3], far = 0.0, sc = 0.0;
    for (i = 0; i < 3 * n; i++)
        if (!(fabs(p[i]) <= SHAPE_MAX)) return (int)i + 1;
    if (n < 4) return -1;
    /* The differences from point 0 scaled by a power of 2 near their largest
     * entry, so that the squares below neither underflow nor overflow: the
     * test is the same at every scale (unscaled, a unit tetrahedron shrunk by
     * 1e-162 or grown by 1e155 was called coplanar). */
    for (i = 1; i < n; i++)
        for (j = 0; j < 3; j++) {
            const double a = fabs(p[3 * i + j] - p[j]);
            if (a > sc) sc = a;
        }
    if (!(sc >= SHAPE_MIN)) return sc > 0.0 ? -3 : -2;
    sc = ldexp(1.0, ilogb(sc));
    /* Extent: the largest distance from point 0. Then the farthest point
     * j, the point k farthest from the line 0-j, and the point l farthest
     * from the plane 0-j-k: coplanar if that distance is below 1e-9 ext. */
    j = 0;
    for (i = 1; i < n; i++) {
        double d[3], dd;
        hull_diff(p, i, sc, d);
        dd = sqrt(vec3_dot(d, d));
        if (dd > ext) { ext = dd; j = i; }
    }
    if (!(ext > 0.0)) return -2;
    hull_diff(p, j, sc, e1);
    for (i = 0; i < 3; i++) e1[i] /= ext;
    k = 0;
    for (i = 1; i < n; i++) {
        double d[3], c[3];
        hull_diff(p, i, sc, d);
        vec3_cross(e1, d, c);
        if (sqrt(vec3_dot(c, c)) > best) { best = sqrt(vec3_dot(c, c)); k = i; }
    }
    if (!(best > 1e-9 * ext)) return -2;
    {
        double dk[3], len;
        hull_diff(p, k, sc, dk);
        vec3_cross(e1, dk, nrm);
        len = sqrt(vec3_dot(nrm, nrm));
        for (i = 0; i < 3; i++) nrm[i] /= len;
    }
    for (l = 1; l < n; l++) {
        double d[3], h;
        hull_diff(p, l, sc, d);
        h = fabs(vec3_dot(nrm, d));
        if (h > far) far = h;
    }
    return far > 1e-9 * ext ? 0 : -2;
}

/* A hull's centre, MPR's interior point (narrowphase.c): the centroid of the
 * distinct support points in the 26 directions of a cube's faces, edges and
 * corners. Those are points of the hull's boundary that no strictly interior
 * input point can be, so the centre, and with it every query's answer, does
 * not depend on interior points (the centroid of all the points did: a box
 * given with 30 extra points in one corner moved a deep sphere contact's
 * depth by up to 1.07, found from outside, 2026-12-05). The centroid is
 * strictly inside when the points found span a volume (they nearly always
 * do: the two directions d and -d find opposite sides); else the centroid of
 * all the points, which is inside too. */
static void hull_centre(shape_def *s)
{
    const int32_t n = s->npts;
    int32_t found[26], nf = 0, i, j, k;
    double c[3] = {0.0, 0.0, 0.0}, vol = 0.0, ext = 0.0;
    for (i = -1; i <= 1; i++)
        for (j = -1; j <= 1; j++)
            for (k = -1; k <= 1; k++) {
                const double d[3] = {i, j, k};
                double best = -INFINITY;
                int32_t b = 0, p, q;
                if (i == 0 && j == 0 && k == 0) continue;
                for (p = 0; p < n; p++) {
                    const double x = vec3_dot(d, s->pts + 3 * p);
                    if (x > best) best = x, b = p;
                }
                for (q = 0; q < nf && found[q] != b; q++) {}
                if (q == nf) found[nf++] = b;
            }
    for (i = 0; i < nf; i++)
        for (j = 0; j < 3; j++) c[j] += s->pts[3 * found[i] + j] / nf;
    /* a volume among the points found: the largest |det| of three of their
     * differences from the first, against the cube of their extent */
    for (i = 1; i < nf; i++)
        for (j = 0; j < 3; j++) ext = fmax(ext, fabs(s->pts[3 * found[i] + j] - s->pts[3 * found[0] + j]));
    for (i = 1; i < nf && ext > 0.0; i++)
        for (j = i + 1; j < nf; j++)
            for (k = j + 1; k < nf; k++) {
                double a[3], b[3], e[3], x[3];
                int32_t r;
                for (r = 0; r < 3; r++) {
                    a[r] = (s->pts[3 * found[i] + r] - s->pts[3 * found[0] + r]) / ext;
                    b[r] = (s->pts[3 * found[j] + r] - s->pts[3 * found[0] + r]) / ext;
                    e[r] = (s->pts[3 * found[k] + r] - s->pts[3 * found[0] + r]) / ext;
                }
                vec3_cross(a, b, x);
                vol = fmax(vol, fabs(vec3_dot(x, e)));
            }
    if (vol > 1e-9) {
        memcpy(s->centre, c, sizeof c);
        return;
    }
    for (i = 0; i < n; i++)
        for (j = 0; j < 3; j++) s->centre[j] += s->pts[3 * i + j] / n;
}

void shape_bound(shape_def *s)
{
    const double *z = s->size;
    int32_t i;
    s->centre[0] = s->centre[1] = s->centre[2] = 0.0;
    switch (s->type) {
    case AQS_SHAPE_SPHERE: s->radius = z[0]; break;
    case AQS_SHAPE_CAPSULE: s->radius = z[0] + z[1]; break;
    case AQS_SHAPE_BOX: s->radius = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]); break;
    case AQS_SHAPE_CYLINDER: s->radius = sqrt(z[0] * z[0] + z[1] * z[1]); break;
    default: /* hull: an interior point from its extreme points (hull_centre), farthest point */
        hull_centre(s);
        s->radius = 0.0;
        for (i = 0; i < s->npts; i++) {
            double d[3] = {s->pts[3 * i] - s->centre[0], s->pts[3 * i + 1] - s->centre[1],
                           s->pts[3 * i + 2] - s->centre[2]};
            double r = sqrt(vec3_dot(d, d));
            if (r > s->radius) s->radius = r;
        }
        break;
    }
}

static double sgn(double x) { return x >= 0.0 ? 1.0 : -1.0; }

void shape_support(const shape_def *s, const double d[3], double out[3])
{
    const double *z = s->size;
    double len = sqrt(vec3_dot(d, d)), rho;
    int32_t i, best;
    switch (s->type) {
    case AQS_SHAPE_SPHERE:
    case AQS_SHAPE_CAPSULE:
        if (len > 0.0) {
            out[0] = z[0] * d[0] / len;
            out[1] = z[0] * d[1] / len;
            out[2] = z[0] * d[2] / len;
        } else {
            out[0] = out[1] = out[2] = 0.0;
            out[2] = z[0];
        }
        if (s->type == AQS_SHAPE_CAPSULE) out[2] += sgn(d[2]) * z[1];
        break;
    case AQS_SHAPE_BOX:
        out[0] = sgn(d[0]) * z[0];
        out[1] = sgn(d[1]) * z[1];
        out[2] = sgn(d[2]) * z[2];
        break;
    case AQS_SHAPE_CYLINDER:
        rho = sqrt(d[0] * d[0] + d[1] * d[1]);
        if (rho > 0.0) {
            out[0] = z[0] * d[0] / rho;
            out[1] = z[0] * d[1] / rho;
        } else {
            out[0] = z[0];
            out[1] = 0.0;
        }
        out[2] = sgn(d[2]) * z[1];
        break;
    default:
        best = 0;
        {
            double bd = vec3_dot(s->pts, d);
            for (i = 1; i < s->npts; i++) {
                double v = vec3_dot(s->pts + 3 * i, d);
                if (v > bd) { bd = v; best = i; }
            }
        }
        out[0] = s->pts[3 * best];
        out[1] = s->pts[3 * best + 1];
        out[2] = s->pts[3 * best + 2];
        break;
    }
}
