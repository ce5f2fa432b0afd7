/* narrowphase.h -- penetration of two placed convex shapes: exact from the
 * distance of the cores for pairs with a sphere or capsule, libccd's MPR
 * otherwise, with guards that turn libccd's degenerate results into defined
 * ones. */
#ifndef AQS_NARROWPHASE_H
#define AQS_NARROWPHASE_H

#include "shape.h"

typedef struct {
    const shape_def *s;
    pose world; /* the shape frame in the world */
} placed_shape;

/* World pose of shape s whose body's rigid group frame is at W (shape_in
 * is the shape frame in that group frame). */
void narrow_place(const shape_def *s, const pose *W, const pose *shape_in, placed_shape *out);
/* World centre of the shape's bounding sphere. */
void narrow_centre(const placed_shape *p, double c[3]);
/* 1 if a and b intersect (depth >= 0, unit normal from a towards b: moving
 * b by depth * normal separates them, point in the world), 0 if not. Every
 * output is finite. */
int narrow_contact(const placed_shape *a, const placed_shape *b, double *depth, double normal[3],
                   double point[3]);

#endif
