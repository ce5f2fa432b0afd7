/* narrowphase.c -- libccd MPR on placed shapes. libccd is built for double
 * precision on Debian; the build fails otherwise (below). */
#include "narrowphase.h"

#include <math.h>
#include <string.h>

#include <ccd/ccd.h>

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

int narrow_contact(const placed_shape *a, const placed_shape *b, double *depth, double normal[3],
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
    /* Guards (libccd: NaN direction for face-touching boxes, 0/0 at zero
     * depth): depth in [0, inf), direction unit, point finite. */
    narrow_centre(a, ca);
    narrow_centre(b, cb);
    *depth = isfinite(dep) && dep > 0.0 ? dep : 0.0;
    len = sqrt(dir.v[0] * dir.v[0] + dir.v[1] * dir.v[1] + dir.v[2] * dir.v[2]);
    ok = isfinite(len) && len > 0.0;
    if (!ok) { /* fall back to the centre line, then to z */
        for (i = 0; i < 3; i++) dir.v[i] = cb[i] - ca[i];
        len = sqrt(dir.v[0] * dir.v[0] + dir.v[1] * dir.v[1] + dir.v[2] * dir.v[2]);
        if (!(isfinite(len) && len > 0.0)) {
            dir.v[0] = dir.v[1] = 0.0;
            dir.v[2] = len = 1.0;
        }
    }
    for (i = 0; i < 3; i++) normal[i] = dir.v[i] / len;
    if (isfinite(pos.v[0]) && isfinite(pos.v[1]) && isfinite(pos.v[2])) {
        for (i = 0; i < 3; i++) point[i] = pos.v[i];
    } else {
        for (i = 0; i < 3; i++) point[i] = 0.5 * (ca[i] + cb[i]);
    }
    return 1;
}
