/* spatial.h -- rigid poses, quaternions, 6-D motion/force transforms, inertias.
 * Spatial vectors are [angular; linear] (MATH.md §1). Matrices are row-major. */
#ifndef AQS_SPATIAL_H
#define AQS_SPATIAL_H

/* A frame's pose in a parent frame: orientation R (its axes written in the
 * parent, row-major 3x3) and origin p (written in the parent). */
typedef struct {
    double R[9];
    double p[3];
} pose;

void pose_identity(pose *P);
/* out = a * b (b given in a's frame). out may alias neither a nor b. */
void pose_compose(const pose *a, const pose *b, pose *out);
void pose_inverse(const pose *a, pose *out);
void pose_from_quat(const double pos[3], const double quat[4], pose *P);

/* Quaternions (w, x, y, z). */
void quat_to_rot(const double q[4], double R[9]);
void rot_to_quat(const double R[9], double q[4]);
void quat_mul(const double a[4], const double b[4], double out[4]);
/* Unit quaternion of the rotation vector w (angle |w| about w/|w|). */
void quat_from_rotvec(const double w[3], double q[4]);
double quat_norm(const double q[4]);
/* Rotation matrix of angle about the unit axis a. */
void rot_axis_angle(const double a[3], double angle, double R[9]);

/* 3-vectors and 3x3 matrices. */
void vec3_cross(const double a[3], const double b[3], double out[3]);
double vec3_dot(const double a[3], const double b[3]);
void mat3_mul(const double A[9], const double B[9], double out[9]);
void mat3_vec(const double A[9], const double v[3], double out[3]);
void mat3_tvec(const double A[9], const double v[3], double out[3]); /* A^T v */

/* Motion transform mapping coordinates in frame F to coordinates in its
 * parent G, where P is F's pose in G: X = [R 0; skew(p) R  R]. */
void spatial_to_parent(const pose *P, double X[36]);
/* Motion transform mapping parent (G) coordinates to F coordinates:
 * X = [R^T 0; -R^T skew(p)  R^T]. */
void spatial_from_parent(const pose *P, double X[36]);

/* Spatial inertia about the frame origin of a body with mass m, centre of
 * mass c and rotational inertia Ic about c (MATH.md §1.3). */
void spatial_inertia(double m, const double c[3], const double Ic[9], double I[36]);
/* I_G = X* I_F X*^T for the frame F with pose P in G (force transform). */
void spatial_inertia_to_parent(const pose *P, const double IF[36], double IG[36]);

/* Spheres (cx, cy, cz, r); r < 0: empty. */
/* Euclidean distance of two points. */
double vec3_dist(const double a[3], const double b[3]);
/* A sphere enclosing two spheres (the smallest), its centre on the segment
 * between theirs; the radius rounded up by a relative 1e-12 (the broadphase's
 * and the world bound's hierarchies). out may alias neither. */
void sphere_merge(const double *s1, const double *s2, double *out);

/* Structured actions of X = spatial_from_parent(P) (cheaper than 6x6 products). */
/* out = X v (motion vector from the parent frame into P's frame). */
void spatial_xform_motion(const pose *P, const double v[6], double out[6]);
/* out = X^T f (force vector from P's frame back into the parent frame). */
void spatial_xform_force_back(const pose *P, const double f[6], double out[6]);
/* out = B X^T for a 6x6 B (each row of B mapped by X). out may not alias B. */
void spatial_xform_rows(const pose *P, const double *B, double *out);
/* out = X S X^T for a symmetric 6x6 S. */
void spatial_xform_congruence(const pose *P, const double *S, double *out);
/* out = force vector f (given in the parent frame) in P's frame: [R^T (n - p x f); R^T f]. */
void spatial_force_from_parent(const pose *P, const double f[6], double out[6]);

#endif
