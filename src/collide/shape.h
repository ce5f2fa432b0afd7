/* shape.h -- convex shapes: validation, bounding spheres, support points. */
#ifndef AQS_SHAPE_H
#define AQS_SHAPE_H

#include <stdint.h>

#include "spatial.h"

typedef struct {
    int32_t type;   /* AQS_SHAPE_* */
    int32_t body;   /* body index or AQS_WORLD */
    double size[3]; /* see aqs.h */
    pose local;     /* shape frame in the body frame (world frame for obstacles) */
    double *pts;    /* hull: npts x 3 points in the shape frame */
    int32_t npts;
    double centre[3]; /* bounding sphere of the shape, shape frame */
    double radius;
} shape_def;

/* The scale collision geometry is computed at: sizes, hull extents and
 * coordinates, shape positions in [SHAPE_MIN, SHAPE_MAX] (magnitudes;
 * positions may be 0). Beyond it the squared distances of the narrow phase
 * underflow or overflow and queries come out wrong, not failed (a cube of
 * 1e200 against a sphere in it: no contact; of 1e-200: depth 0.5 for 0.3). */
#define SHAPE_MIN 1e-150
#define SHAPE_MAX 1e150
/* Check the sizes of a primitive type: 0, or 1 + the index of the first bad
 * entry (non-finite, or a used one outside [SHAPE_MIN, SHAPE_MAX]), or -1 for
 * an unknown type. */
int shape_check_size(int32_t type, const double size[3]);
/* Check hull points: 0, 1 + index of the first non-finite value or the
 * first beyond SHAPE_MAX, -1 for fewer than 4 points, -2 for coplanar points,
 * -3 for points less than SHAPE_MIN apart (all of them). */
int shape_check_hull(const double *pts, int32_t n);
/* Fill centre and radius from type, size and pts. */
void shape_bound(shape_def *s);
/* Support point of s in the unit-free direction d (shape frame). */
void shape_support(const shape_def *s, const double d[3], double out[3]);

#endif
