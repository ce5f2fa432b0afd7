/* narrowphase.c -- penetration of placed shapes: exact from the core
 * distance for pairs with a sphere or capsule, libccd's MPR otherwise
 * (docs/collision.md). libccd is built for double precision on Debian; the
 * build fails otherwise (below). */
#include "narrowphase.h"

#include <math.h>
#include <string.h>

#include <ccd/ccd.h>

#include "aqs.h"

#ifndef CCD_DOUBLE
#error "libccd must be built with double precision (CCD_DOUBLE)"
#endif
/* A compile-time check that ccd_real_t is double: a negative array size otherwise. */
typedef char aqs_ccd_real_is_double[(sizeof(ccd_real_t) == sizeof(double)) ? 1 : -1];

void narrow_place(const shape_def *s, const pose *W, const pose *shape_in, placed_shape *out)
{
    out->s = s;
    pose_compose(W, shape_in, &out->world);
}

void narrow_centre(const placed_shape *p, double c[3])
{
    mat3_vec(p->world.R, p->s->centre, c);
    c[0] += p->world.p[0];
    c[1] += p->world.p[1];
    c[2] += p->world.p[2];
}

/* libccd callbacks: directions and points in the world frame. */
static void support_cb(const void *obj, const ccd_vec3_t *dir, ccd_vec3_t *vec)
{
    const placed_shape *p = obj;
    double d[3], local[3], w[3];
    mat3_tvec(p->world.R, dir->v, d);
    shape_support(p->s, d, local);
    mat3_vec(p->world.R, local, w);
    vec->v[0] = w[0] + p->world.p[0];
    vec->v[1] = w[1] + p->world.p[1];
    vec->v[2] = w[2] + p->world.p[2];
}

static void centre_cb(const void *obj, ccd_vec3_t *centre)
{
    double c[3];
    narrow_centre(obj, c);
    centre->v[0] = c[0];
    centre->v[1] = c[1];
    centre->v[2] = c[2];
}

/* The unit line of centres from a to b, +z if they coincide. */
static void centre_line(const placed_shape *a, const placed_shape *b, double n[3])
{
    double ca[3], cb[3], len;
    int i;
    narrow_centre(a, ca);
    narrow_centre(b, cb);
    for (i = 0; i < 3; i++) n[i] = cb[i] - ca[i];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (isfinite(len) && len > 0.0) {
        for (i = 0; i < 3; i++) n[i] /= len;
    } else {
        n[0] = n[1] = 0.0;
        n[2] = 1.0;
    }
}

/* MPR on any pair, with guards (libccd: NaN direction for face-touching
 * boxes, 0/0 at zero depth): depth in [0, inf), direction unit, point
 * finite. */
static int mpr_contact(const placed_shape *a, const placed_shape *b, double *depth, double normal[3],
                       double point[3])
{
    ccd_t ccd;
    ccd_real_t dep = 0.0;
    ccd_vec3_t dir, pos;
    double ca[3], cb[3], len;
    int i, ok;
    CCD_INIT(&ccd);
    ccd.support1 = support_cb;
    ccd.support2 = support_cb;
    ccd.center1 = centre_cb;
    ccd.center2 = centre_cb;
    ccd.max_iterations = 500;
    /* Portal refinement down to 1e-12 of the pair's size (default 1e-4, absolute). */
    ccd.mpr_tolerance = 1e-12 * (a->s->radius + b->s->radius);
    memset(&dir, 0, sizeof dir);
    memset(&pos, 0, sizeof pos);
    if (ccdMPRPenetration(a, b, &ccd, &dep, &dir, &pos) != 0) return 0;
    narrow_centre(a, ca);
    narrow_centre(b, cb);
    *depth = isfinite(dep) && dep > 0.0 ? dep : 0.0;
    len = sqrt(dir.v[0] * dir.v[0] + dir.v[1] * dir.v[1] + dir.v[2] * dir.v[2]);
    ok = isfinite(len) && len > 0.0;
    if (ok) {
        for (i = 0; i < 3; i++) normal[i] = dir.v[i] / len;
    } else {
        centre_line(a, b, normal);
    }
    if (isfinite(pos.v[0]) && isfinite(pos.v[1]) && isfinite(pos.v[2])) {
        for (i = 0; i < 3; i++) point[i] = pos.v[i];
    } else {
        for (i = 0; i < 3; i++) point[i] = 0.5 * (ca[i] + cb[i]);
    }
    return 1;
}

/* Spheres and capsules are a core (a point, a segment) inflated by their
 * radius, so their signed separation from another shape is the distance of
 * the cores minus the radii, and the penetration depth of a pair whose
 * cores are apart by d > 0 is exactly radius - d, along the line of the
 * closest points (the distance to a convex set grows at rate 1 along that
 * line and by at most 1 per unit step in any direction). MPR, on the other
 * hand, stops on a portal whose flatness test is below rounding when the
 * Minkowski difference is flat one way and curved the other (sphere on an
 * edge, parallel capsules): it then reports contacts across gaps of 1e-12
 * and depths off by a few 1e-9 (docs/collision.md). So every pair with a
 * sphere or capsule is decided here from the exact distance of the cores;
 * MPR is left the deep case where the core itself touches a box, cylinder or
 * hull. */

static double clamp(double x, double lo, double hi) { return x < lo ? lo : (x > hi ? hi : x); }

static int is_core(const shape_def *s) { return s->type == AQS_SHAPE_SPHERE || s->type == AQS_SHAPE_CAPSULE; }

/* The core segment p0-p1 of a sphere or capsule in the world (p0 == p1 for a sphere). */
static void core_world(const placed_shape *p, double p0[3], double p1[3])
{
    double h = p->s->type == AQS_SHAPE_CAPSULE ? p->s->size[1] : 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        p0[i] = p->world.p[i] - h * p->world.R[3 * i + 2];
        p1[i] = p->world.p[i] + h * p->world.R[3 * i + 2];
    }
}

/* A unit vector perpendicular to u (any if u is zero). */
static void perpendicular(const double u[3], double n[3])
{
    double e[3] = {0, 0, 0}, len;
    int k = fabs(u[0]) <= fabs(u[1]) ? (fabs(u[0]) <= fabs(u[2]) ? 0 : 2) : (fabs(u[1]) <= fabs(u[2]) ? 1 : 2);
    e[k] = 1.0;
    vec3_cross(u, e, n);
    len = sqrt(vec3_dot(n, n));
    if (len > 0.0) {
        n[0] /= len;
        n[1] /= len;
        n[2] /= len;
    } else {
        n[0] = n[1] = 0.0;
        n[2] = 1.0;
    }
}

/* Closest points qa, qb of segments a0-a1 and b0-b1 (either may be a point):
 * Ericson, Real-Time Collision Detection, 5.1.9. The clamp-then-reproject
 * order gives a closest pair for parallel segments too. */
static void segment_segment(const double a0[3], const double a1[3], const double b0[3], const double b1[3],
                            double qa[3], double qb[3])
{
    double d1[3], d2[3], r[3], a, e, f, c, b, denom, s = 0.0, t = 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        d1[i] = a1[i] - a0[i];
        d2[i] = b1[i] - b0[i];
        r[i] = a0[i] - b0[i];
    }
    a = vec3_dot(d1, d1);
    e = vec3_dot(d2, d2);
    f = vec3_dot(d2, r);
    if (a <= 0.0 && e <= 0.0) {
        s = t = 0.0;
    } else if (a <= 0.0) {
        t = clamp(f / e, 0.0, 1.0);
    } else {
        c = vec3_dot(d1, r);
        if (e <= 0.0) {
            s = clamp(-c / a, 0.0, 1.0);
        } else {
            b = vec3_dot(d1, d2);
            denom = a * e - b * b;
            s = denom > 0.0 ? clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
            t = (b * s + f) / e;
            if (t < 0.0) {
                t = 0.0;
                s = clamp(-c / a, 0.0, 1.0);
            } else if (t > 1.0) {
                t = 1.0;
                s = clamp((b - c) / a, 0.0, 1.0);
            }
        }
    }
    for (i = 0; i < 3; i++) {
        qa[i] = a0[i] + s * d1[i];
        qb[i] = b0[i] + t * d2[i];
    }
}

/* Sphere or capsule a against sphere or capsule b, entirely in closed form.
 * With cores at distance d < ra + rb the depth is ra + rb - d; when the cores
 * meet (d below 1e-9 of the radii, where the direction of the closest points
 * is rounding) the difference of the cores is flat, so the depth is
 * ra + rb along the normal of the plane of the two cores. */
static int core_core(const placed_shape *a, const placed_shape *b, double *depth, double normal[3],
                     double point[3])
{
    double a0[3], a1[3], b0[3], b1[3], qa[3], qb[3], v[3], ua[3], ub[3], w[3], d, lo, hi;
    double ra = a->s->size[0], rb = b->s->size[0], R = ra + rb;
    int i;
    core_world(a, a0, a1);
    core_world(b, b0, b1);
    segment_segment(a0, a1, b0, b1, qa, qb);
    for (i = 0; i < 3; i++) v[i] = qb[i] - qa[i];
    d = sqrt(vec3_dot(v, v));
    if (!(d < R)) return 0; /* touching or apart */
    *depth = R - d;
    if (d > 1e-9 * R) {
        for (i = 0; i < 3; i++) normal[i] = v[i] / d;
    } else {
        for (i = 0; i < 3; i++) {
            ua[i] = a1[i] - a0[i];
            ub[i] = b1[i] - b0[i];
        }
        vec3_cross(ua, ub, w);
        if (sqrt(vec3_dot(w, w)) > 1e-9 * sqrt(vec3_dot(ua, ua) * vec3_dot(ub, ub))) {
            d = sqrt(vec3_dot(w, w));
            for (i = 0; i < 3; i++) normal[i] = w[i] / d;
        } else {
            double cab[3], u[3];
            for (i = 0; i < 3; i++) {
                cab[i] = b->world.p[i] - a->world.p[i];
                u[i] = vec3_dot(ua, ua) >= vec3_dot(ub, ub) ? ua[i] : ub[i];
            }
            /* parallel cores or points: the centre line if it is off the cores' line */
            if (vec3_dot(u, u) > 0.0) {
                double k = vec3_dot(cab, u) / vec3_dot(u, u);
                for (i = 0; i < 3; i++) cab[i] -= k * u[i];
            }
            d = sqrt(vec3_dot(cab, cab));
            if (d > 1e-9 * R) {
                for (i = 0; i < 3; i++) normal[i] = cab[i] / d;
            } else {
                perpendicular(u, normal);
            }
        }
        /* moving b along +normal or -normal separates equally: point from a to b */
        if (vec3_dot(normal, v) < 0.0 ||
            (vec3_dot(normal, v) == 0.0 && vec3_dot(normal, b->world.p) < vec3_dot(normal, a->world.p)))
            for (i = 0; i < 3; i++) normal[i] = -normal[i];
        d = 0.0;
    }
    /* The point: the middle of the overlap of the two balls along the normal
     * line through qa (inside both shapes). */
    lo = fmax(-ra, d - rb);
    hi = fmin(ra, d + rb);
    for (i = 0; i < 3; i++) point[i] = qa[i] + 0.5 * (lo + hi) * normal[i];
    return 1;
}

/* Closest point y of a box or cylinder (shape frame) to x: both are products
 * of intervals and a disc, so the projection is done factor by factor. */
static void project_solid(const shape_def *s, const double x[3], double y[3])
{
    const double *z = s->size;
    if (s->type == AQS_SHAPE_BOX) {
        y[0] = clamp(x[0], -z[0], z[0]);
        y[1] = clamp(x[1], -z[1], z[1]);
        y[2] = clamp(x[2], -z[2], z[2]);
    } else {
        double rho = sqrt(x[0] * x[0] + x[1] * x[1]), k = rho > z[0] ? z[0] / rho : 1.0;
        y[0] = k * x[0];
        y[1] = k * x[1];
        y[2] = clamp(x[2], -z[1], z[1]);
    }
}

/* For a point x inside a box or cylinder: distance to its surface and the
 * outward normal of the nearest face (shape frame). */
static double inside_depth(const shape_def *s, const double x[3], double n[3])
{
    const double *z = s->size;
    double best;
    int i, k = 0;
    n[0] = n[1] = n[2] = 0.0;
    if (s->type == AQS_SHAPE_BOX) {
        best = z[0] - fabs(x[0]);
        for (i = 1; i < 3; i++)
            if (z[i] - fabs(x[i]) < best) {
                best = z[i] - fabs(x[i]);
                k = i;
            }
        n[k] = x[k] >= 0.0 ? 1.0 : -1.0;
    } else {
        double rho = sqrt(x[0] * x[0] + x[1] * x[1]);
        best = z[1] - fabs(x[2]);
        n[2] = x[2] >= 0.0 ? 1.0 : -1.0;
        if (z[0] - rho < best) {
            best = z[0] - rho;
            n[2] = 0.0;
            if (rho > 0.0) {
                n[0] = x[0] / rho;
                n[1] = x[1] / rho;
            } else {
                n[0] = 1.0;
            }
        }
    }
    return best;
}

/* Closest points x (on the segment e0-e1) and y (on the box or cylinder),
 * shape frame. phi(t) = |x(t) - y(x(t))|^2 / 2 is convex with derivative
 * (x - y) . (e1 - e0), so bisection on the sign of that derivative finds the
 * minimiser to rounding; the value there is then exact to rounding, because
 * phi is flat at its minimum. */
static void segment_solid(const shape_def *s, const double e0[3], const double e1[3], double x[3],
                          double y[3])
{
    double u[3], lo = 0.0, hi = 1.0, t, v[3], xl[3], yl[3];
    int i, it;
    for (i = 0; i < 3; i++) u[i] = e1[i] - e0[i];
    for (it = 0; it < 2; it++) { /* the two ends first */
        t = it ? 1.0 : 0.0;
        for (i = 0; i < 3; i++) x[i] = e0[i] + t * u[i];
        project_solid(s, x, y);
        for (i = 0; i < 3; i++) v[i] = x[i] - y[i];
        if (it == 0 ? vec3_dot(v, u) >= 0.0 : vec3_dot(v, u) <= 0.0) return;
    }
    for (it = 0; it < 80; it++) {
        t = 0.5 * (lo + hi);
        if (!(t > lo && t < hi)) break;
        for (i = 0; i < 3; i++) x[i] = e0[i] + t * u[i];
        project_solid(s, x, y);
        for (i = 0; i < 3; i++) v[i] = x[i] - y[i];
        if (vec3_dot(v, u) < 0.0) lo = t;
        else hi = t;
    }
    /* the better of the two ends of the last bracket */
    for (i = 0; i < 3; i++) xl[i] = e0[i] + lo * u[i];
    project_solid(s, xl, yl);
    for (i = 0; i < 3; i++) {
        x[i] = e0[i] + hi * u[i];
        v[i] = xl[i] - yl[i];
    }
    project_solid(s, x, y);
    {
        double w[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
        if (vec3_dot(v, v) < vec3_dot(w, w))
            for (i = 0; i < 3; i++) {
                x[i] = xl[i];
                y[i] = yl[i];
            }
    }
}

/* Closest point to the origin of the simplex w[0..n-1] (n <= 4), as the
 * barycentric weights lambda: the best, over the faces, of the projection
 * of the origin on the face's affine hull that falls inside the face. */
static double simplex_closest(const double w[4][3], int n, double lambda[4])
{
    double best = INFINITY;
    int mask, i, j;
    for (mask = 1; mask < (1 << n); mask++) {
        int idx[4] = {0, 0, 0, 0}, m = 0;
        double e[3][3], G[3][3], rhs[3], mu[3] = {0, 0, 0}, lam[4], v[3], det, d2;
        for (i = 0; i < n; i++)
            if (mask & (1 << i)) idx[m++] = i;
        for (j = 1; j < m; j++)
            for (i = 0; i < 3; i++) e[j - 1][i] = w[idx[j]][i] - w[idx[0]][i];
        for (i = 0; i < m - 1; i++) {
            rhs[i] = -vec3_dot(e[i], w[idx[0]]);
            for (j = 0; j < m - 1; j++) G[i][j] = vec3_dot(e[i], e[j]);
        }
        if (m == 2) {
            if (!(G[0][0] > 0.0)) continue;
            mu[0] = rhs[0] / G[0][0];
        } else if (m == 3) {
            det = G[0][0] * G[1][1] - G[0][1] * G[1][0];
            if (!(det > 1e-24 * G[0][0] * G[1][1])) continue;
            mu[0] = (rhs[0] * G[1][1] - G[0][1] * rhs[1]) / det;
            mu[1] = (G[0][0] * rhs[1] - rhs[0] * G[1][0]) / det;
        } else if (m == 4) {
            double c0[3], c1[3], c2[3];
            /* Cramer on the 3x3 Gram system */
            det = G[0][0] * (G[1][1] * G[2][2] - G[1][2] * G[2][1]) -
                  G[0][1] * (G[1][0] * G[2][2] - G[1][2] * G[2][0]) +
                  G[0][2] * (G[1][0] * G[2][1] - G[1][1] * G[2][0]);
            if (!(det > 1e-24 * G[0][0] * G[1][1] * G[2][2])) continue;
            for (i = 0; i < 3; i++) {
                c0[i] = G[i][0];
                c1[i] = G[i][1];
                c2[i] = G[i][2];
            }
            mu[0] = (rhs[0] * (c1[1] * c2[2] - c2[1] * c1[2]) - c1[0] * (rhs[1] * c2[2] - c2[1] * rhs[2]) +
                     c2[0] * (rhs[1] * c1[2] - c1[1] * rhs[2])) / det;
            mu[1] = (c0[0] * (rhs[1] * c2[2] - c2[1] * rhs[2]) - rhs[0] * (c0[1] * c2[2] - c2[1] * c0[2]) +
                     c2[0] * (c0[1] * rhs[2] - rhs[1] * c0[2])) / det;
            mu[2] = (c0[0] * (c1[1] * rhs[2] - rhs[1] * c1[2]) - c1[0] * (c0[1] * rhs[2] - rhs[1] * c0[2]) +
                     rhs[0] * (c0[1] * c1[2] - c1[1] * c0[2])) / det;
        }
        lam[0] = 1.0;
        for (j = 1; j < m; j++) {
            lam[j] = mu[j - 1];
            lam[0] -= mu[j - 1];
        }
        for (j = 0; j < m; j++)
            if (lam[j] < 0.0) break;
        if (j < m) continue;
        for (i = 0; i < 3; i++) {
            v[i] = w[idx[0]][i];
            for (j = 1; j < m; j++) v[i] += mu[j - 1] * e[j - 1][i];
        }
        d2 = vec3_dot(v, v);
        if (d2 < best) {
            best = d2;
            for (j = 0; j < 4; j++) lambda[j] = 0.0;
            for (j = 0; j < m; j++) lambda[idx[j]] = lam[j];
        }
    }
    return best;
}

/* Closest points x (segment e0-e1) and y (hull) by GJK on the difference
 * segment - hull, a polytope, so it ends when no support point improves;
 * allocation-free (libccd's GJK distance allocates). Shape frame. */
static void segment_hull(const shape_def *s, const double e0[3], const double e1[3], double x[3], double y[3])
{
    double w[4][3], wx[4][3], wy[4][3], lambda[4] = {1, 0, 0, 0}, v[3], dir[3], sx[3], sy[3], d2, prev = INFINITY;
    int n = 1, it, i, j;
    /* the start: the hull's support point towards e0 from its centre, a point
     * of its boundary, so that interior points change nothing (the first
     * input point did) */
    for (i = 0; i < 3; i++) dir[i] = e0[i] - s->centre[i];
    if (!(vec3_dot(dir, dir) > 0.0)) dir[0] = 1.0, dir[1] = dir[2] = 0.0;
    shape_support(s, dir, sy);
    for (i = 0; i < 3; i++) {
        wx[0][i] = e0[i];
        wy[0][i] = sy[i];
        w[0][i] = wx[0][i] - wy[0][i];
    }
    for (it = 0; it < 64; it++) {
        for (i = 0; i < 3; i++) v[i] = 0.0;
        for (j = 0; j < n; j++)
            for (i = 0; i < 3; i++) v[i] += lambda[j] * w[j][i];
        d2 = vec3_dot(v, v);
        if (!(d2 > 0.0) || !(d2 < prev)) break; /* touching, or no progress */
        prev = d2;
        /* support of the difference in -v: the segment's end against the hull's farthest point along v */
        for (i = 0; i < 3; i++) {
            sx[i] = vec3_dot(e0, v) <= vec3_dot(e1, v) ? e0[i] : e1[i];
            dir[i] = v[i];
        }
        shape_support(s, dir, sy);
        for (i = 0; i < 3; i++) {
            w[n][i] = sx[i] - sy[i];
            wx[n][i] = sx[i];
            wy[n][i] = sy[i];
        }
        /* stop when the new point does not get closer to the origin than v's plane (to rounding) */
        if (d2 - vec3_dot(v, w[n]) <= 1e-15 * d2) break;
        n++;
        simplex_closest(w, n, lambda);
        /* keep the face that holds the closest point */
        for (i = j = 0; i < n; i++)
            if (lambda[i] > 0.0) {
                memcpy(w[j], w[i], sizeof w[i]);
                memcpy(wx[j], wx[i], sizeof wx[i]);
                memcpy(wy[j], wy[i], sizeof wy[i]);
                lambda[j++] = lambda[i];
            }
        n = j;
        if (n == 4) break; /* the origin is inside: they intersect */
    }
    for (i = 0; i < 3; i++) {
        x[i] = y[i] = 0.0;
        for (j = 0; j < n; j++) {
            x[i] += lambda[j] * wx[j][i];
            y[i] += lambda[j] * wy[j][i];
        }
    }
    if (n == 4)
        for (i = 0; i < 3; i++) y[i] = x[i];
}

/* Sphere or capsule c against a box, cylinder or hull o: the normal from o
 * towards c. With the core at distance d from o, in closed form (depth
 * radius - d); when the core touches o (d below 1e-9 of the radius, where the
 * closest points' direction is rounding), a sphere's centre inside a box or
 * cylinder is still in closed form (radius + its depth below the nearest
 * face), and the rest goes to MPR. */
static int core_solid(const placed_shape *o, const placed_shape *c, double *depth, double normal[3],
                      double point[3])
{
    double c0[3], c1[3], e0[3], e1[3], x[3], y[3], v[3], nl[3], pl[3], d, r = c->s->size[0];
    int i, hull = o->s->type == AQS_SHAPE_HULL;
    core_world(c, c0, c1);
    for (i = 0; i < 3; i++) {
        c0[i] -= o->world.p[i];
        c1[i] -= o->world.p[i];
    }
    mat3_tvec(o->world.R, c0, e0);
    mat3_tvec(o->world.R, c1, e1);
    if (hull) {
        segment_hull(o->s, e0, e1, x, y);
    } else {
        segment_solid(o->s, e0, e1, x, y);
    }
    for (i = 0; i < 3; i++) v[i] = x[i] - y[i];
    d = sqrt(vec3_dot(v, v));
    if (!(d < r)) return 0; /* touching or apart */
    if (d > 1e-9 * r) {
        *depth = r - d;
        for (i = 0; i < 3; i++) {
            nl[i] = v[i] / d;
            /* the middle of the overlap along the normal line: from y - depth nl to y */
            pl[i] = y[i] - 0.5 * *depth * nl[i];
        }
        if (!hull) project_solid(o->s, pl, pl); /* stays inside o if o is thinner than the depth */
    } else if (!hull && e0[0] == e1[0] && e0[1] == e1[1] && e0[2] == e1[2]) {
        double below = inside_depth(o->s, e0, nl);
        *depth = d > 0.0 ? r - d : r + below; /* just outside: still the exact r - d */
        for (i = 0; i < 3; i++) pl[i] = e0[i] + 0.5 * (below - r) * nl[i];
        project_solid(o->s, pl, pl);
    } else {
        if (mpr_contact(o, c, depth, normal, point)) return 1;
        /* MPR found nothing although the core touches o: depth r on the centre line */
        *depth = r - d;
        centre_line(o, c, normal);
        for (i = 0; i < 3; i++) point[i] = 0.5 * (c0[i] + c1[i]) + o->world.p[i];
        return 1;
    }
    mat3_vec(o->world.R, nl, normal);
    mat3_vec(o->world.R, pl, point);
    for (i = 0; i < 3; i++) point[i] += o->world.p[i];
    return 1;
}

int narrow_contact(const placed_shape *a, const placed_shape *b, double *depth, double normal[3],
                   double point[3])
{
    int ca = is_core(a->s), cb = is_core(b->s), i, r;
    if (ca && cb) return core_core(a, b, depth, normal, point);
    if (cb) return core_solid(a, b, depth, normal, point);
    if (ca) {
        r = core_solid(b, a, depth, normal, point);
        if (r)
            for (i = 0; i < 3; i++) normal[i] = -normal[i];
        return r;
    }
    return mpr_contact(a, b, depth, normal, point);
}
