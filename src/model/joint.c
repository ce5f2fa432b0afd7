/* joint.c -- joint types. Conventions in aqs.h (aqs_joint_add) and MATH.md §1.4. */
#include "joint.h"

#include <math.h>
#include <string.h>

#include "check.h"

static const int nq_of[JOINT_TYPE_COUNT] = {1, 1, 4, 7, 0, 2, 2, 3};
static const int nv_of[JOINT_TYPE_COUNT] = {1, 1, 3, 6, 0, 2, 2, 3};
static const char *const names[JOINT_TYPE_COUNT] = {
    "revolute", "prismatic", "spherical", "free", "fixed", "universal", "cylindrical", "planar"};

enum { REVOLUTE, PRISMATIC, SPHERICAL, FREE, FIXED, UNIVERSAL, CYLINDRICAL, PLANAR };

int joint_nq(int32_t type) { return nq_of[type]; }
int joint_nv(int32_t type) { return nv_of[type]; }
const char *joint_type_name(int32_t type) { return names[type]; }

int joint_uses_axis(int32_t type)
{
    return type == REVOLUTE || type == PRISMATIC || type == UNIVERSAL || type == CYLINDRICAL ||
           type == PLANAR;
}

void joint_directions(const double a[3], double u[3], double v[3])
{
    int i, e = 0;
    double d, n;
    for (i = 1; i < 3; i++)
        if (fabs(a[i]) < fabs(a[e])) e = i;
    d = a[e];
    for (i = 0; i < 3; i++) u[i] = (i == e ? 1.0 : 0.0) - d * a[i];
    n = sqrt(vec3_dot(u, u));
    for (i = 0; i < 3; i++) u[i] /= n;
    vec3_cross(a, u, v);
}

void joint_zero_position(int32_t type, double *q)
{
    int i;
    for (i = 0; i < nq_of[type]; i++) q[i] = 0.0;
    if (type == SPHERICAL) q[0] = 1.0;
    if (type == FREE) q[3] = 1.0;
}

int joint_check_position(int32_t type, const double *q, double *out)
{
    int i, n = nq_of[type], qi = -1;
    for (i = 0; i < n; i++)
        if (!isfinite(q[i])) return i + 1;
    memcpy(out, q, sizeof(double) * (size_t)n);
    if (type == SPHERICAL) qi = 0;
    if (type == FREE) qi = 3;
    if (qi >= 0) {
        double norm;
        if (!check_quat_is_unit(q + qi, &norm)) return -1;
        for (i = 0; i < 4; i++) out[qi + i] = q[qi + i] / norm;
    }
    return 0;
}

int joint_align_rotation(const joint_def *j, double C[9])
{
    int i;
    if (!joint_uses_axis(j->type)) return 0;
    if (j->axis[2] == 1.0 && j->u[0] == 1.0 && j->v[1] == 1.0) return 0; /* unit vectors: the identity */
    for (i = 0; i < 3; i++) {
        C[3 * i] = j->u[i];
        C[3 * i + 1] = j->v[i];
        C[3 * i + 2] = j->axis[i];
    }
    return 1;
}

void joint_aligned(const joint_def *j, joint_def *out)
{
    int i;
    *out = *j;
    if (!joint_uses_axis(j->type)) return;
    for (i = 0; i < 3; i++) {
        out->axis[i] = i == 2 ? 1.0 : 0.0;
        out->u[i] = i == 0 ? 1.0 : 0.0;
        out->v[i] = i == 1 ? 1.0 : 0.0;
    }
}

void joint_child_pose_aligned(const joint_def *j, const double *q, pose *P)
{
    joint_def a;
    if (j->type == REVOLUTE) { /* a turn about z, its zz entry exactly 1 */
        const double c = cos(q[0]), s = sin(q[0]);
        pose_identity(P);
        P->R[0] = c, P->R[1] = -s, P->R[3] = s, P->R[4] = c;
        return;
    }
    joint_aligned(j, &a);
    joint_child_pose(&a, q, P);
}

void joint_subspace_aligned(const joint_def *j, const double *q, double *S)
{
    joint_def a;
    if (j->type == REVOLUTE || j->type == PRISMATIC) { /* [e_z; 0] or [0; e_z] */
        int i;
        for (i = 0; i < 6; i++) S[i] = 0.0;
        S[j->type == REVOLUTE ? 2 : 5] = 1.0;
        return;
    }
    joint_aligned(j, &a);
    joint_subspace(&a, q, S);
}

void joint_child_pose(const joint_def *j, const double *q, pose *P)
{
    int i;
    double Ru[9];
    pose_identity(P);
    switch (j->type) {
    case REVOLUTE:
        rot_axis_angle(j->axis, q[0], P->R);
        break;
    case PRISMATIC:
        for (i = 0; i < 3; i++) P->p[i] = q[0] * j->axis[i];
        break;
    case SPHERICAL:
        quat_to_rot(q, P->R);
        break;
    case FREE:
        pose_from_quat(q, q + 3, P);
        break;
    case FIXED:
        break;
    case UNIVERSAL: {
        double Ra[9];
        rot_axis_angle(j->axis, q[0], Ra);
        rot_axis_angle(j->u, q[1], Ru);
        mat3_mul(Ra, Ru, P->R);
        break;
    }
    case CYLINDRICAL:
        rot_axis_angle(j->axis, q[0], P->R);
        for (i = 0; i < 3; i++) P->p[i] = q[1] * j->axis[i];
        break;
    case PLANAR:
        rot_axis_angle(j->axis, q[2], P->R);
        for (i = 0; i < 3; i++) P->p[i] = q[0] * j->u[i] + q[1] * j->v[i];
        break;
    default:
        break;
    }
}

/* Column c of the 6 x n matrix S. */
static void set_column(double *S, int n, int c, const double ang[3], const double lin[3])
{
    int i;
    for (i = 0; i < 3; i++) {
        S[i * n + c] = ang ? ang[i] : 0.0;
        S[(i + 3) * n + c] = lin ? lin[i] : 0.0;
    }
}

void joint_subspace(const joint_def *j, const double *q, double *S)
{
    static const double e[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    int i;
    double R[9], t[3], t2[3];
    switch (j->type) {
    case REVOLUTE:
        set_column(S, 1, 0, j->axis, NULL);
        break;
    case PRISMATIC:
        set_column(S, 1, 0, NULL, j->axis);
        break;
    case SPHERICAL:
        for (i = 0; i < 3; i++) set_column(S, 3, i, e[i], NULL);
        break;
    case FREE:
        for (i = 0; i < 3; i++) {
            set_column(S, 6, i, e[i], NULL);
            set_column(S, 6, i + 3, NULL, e[i]);
        }
        break;
    case UNIVERSAL:
        /* omega_child = Rot(u, -q2) a q1' + u q2'. */
        rot_axis_angle(j->u, q[1], R);
        mat3_tvec(R, j->axis, t);
        set_column(S, 2, 0, t, NULL);
        set_column(S, 2, 1, j->u, NULL);
        break;
    case CYLINDRICAL:
        set_column(S, 2, 0, j->axis, NULL);
        set_column(S, 2, 1, NULL, j->axis);
        break;
    case PLANAR:
        /* v_child = R^T (u q1' + v q2'), omega = a q3'. */
        rot_axis_angle(j->axis, q[2], R);
        mat3_tvec(R, j->u, t);
        mat3_tvec(R, j->v, t2);
        set_column(S, 3, 0, NULL, t);
        set_column(S, 3, 1, NULL, t2);
        set_column(S, 3, 2, j->axis, NULL);
        break;
    default:
        break;
    }
}

static void rotate_quat_body(double *quat, const double w[3])
{
    double dq[4], out[4], n;
    int i;
    quat_from_rotvec(w, dq);
    quat_mul(quat, dq, out);
    n = quat_norm(out);
    for (i = 0; i < 4; i++) quat[i] = out[i] / n;
}

void joint_integrate(const joint_def *j, double *q, const double *qdd, double h)
{
    int i;
    double w[3];
    switch (j->type) {
    case SPHERICAL:
        for (i = 0; i < 3; i++) w[i] = h * qdd[i];
        rotate_quat_body(q, w);
        break;
    case FREE: {
        double R[9], dp[3], t[3];
        quat_to_rot(q + 3, R);
        for (i = 0; i < 3; i++) dp[i] = h * qdd[3 + i];
        mat3_vec(R, dp, t);
        for (i = 0; i < 3; i++) q[i] += t[i];
        for (i = 0; i < 3; i++) w[i] = h * qdd[i];
        rotate_quat_body(q + 3, w);
        break;
    }
    default:
        for (i = 0; i < nv_of[j->type]; i++) q[i] += h * qdd[i];
        break;
    }
}
