/* shape.c -- convex shapes: validation, bounding spheres, support points. */
#include "shape.h"

#include <math.h>

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
        if (!(size[i] > 0.0)) return i + 1;
    return 0;
}

int shape_check_hull(const double *p, int32_t n)
{
    int32_t i, j, k, l;
    double ext = 0.0, best = 0.0, e1[3], nrm[3], far = 0.0;
    for (i = 0; i < 3 * n; i++)
        if (!isfinite(p[i])) return (int)i + 1;
    if (n < 4) return -1;
    /* Extent: the largest distance from point 0. Then the farthest point
     * j, the point k farthest from the line 0-j, and the point l farthest
     * from the plane 0-j-k: coplanar if that distance is below 1e-9 ext. */
    j = 0;
    for (i = 1; i < n; i++) {
        double d[3] = {p[3 * i] - p[0], p[3 * i + 1] - p[1], p[3 * i + 2] - p[2]};
        double dd = sqrt(vec3_dot(d, d));
        if (dd > ext) { ext = dd; j = i; }
    }
    if (!(ext > 0.0)) return -2;
    for (i = 0; i < 3; i++) e1[i] = (p[3 * j + i] - p[i]) / ext;
    k = 0;
    for (i = 1; i < n; i++) {
        double d[3] = {p[3 * i] - p[0], p[3 * i + 1] - p[1], p[3 * i + 2] - p[2]}, c[3];
        vec3_cross(e1, d, c);
        if (sqrt(vec3_dot(c, c)) > best) { best = sqrt(vec3_dot(c, c)); k = i; }
    }
    if (!(best > 1e-9 * ext)) return -2;
    {
        double dk[3] = {p[3 * k] - p[0], p[3 * k + 1] - p[1], p[3 * k + 2] - p[2]}, len;
        vec3_cross(e1, dk, nrm);
        len = sqrt(vec3_dot(nrm, nrm));
        for (i = 0; i < 3; i++) nrm[i] /= len;
    }
    for (l = 1; l < n; l++) {
        double d[3] = {p[3 * l] - p[0], p[3 * l + 1] - p[1], p[3 * l + 2] - p[2]};
        double h = fabs(vec3_dot(nrm, d));
        if (h > far) far = h;
    }
    return far > 1e-9 * ext ? 0 : -2;
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
    default: /* hull: centroid of the points, farthest point */
        for (i = 0; i < s->npts; i++) {
            s->centre[0] += s->pts[3 * i] / s->npts;
            s->centre[1] += s->pts[3 * i + 1] / s->npts;
            s->centre[2] += s->pts[3 * i + 2] / s->npts;
        }
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
