/*
 * urdf.c -- write a linkage as URDF through the public read-back API
 * (aqs_body_get_inertial, aqs_joint_get_definition). Layout: urdf.h.
 */
#include "urdf.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>

static aqs_status fail(char *message, size_t size, aqs_status status, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 4, 5)))
#endif
    ;

static aqs_status fail(char *message, size_t size, aqs_status status, const char *fmt, ...)
{
    if (message && size) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(message, size, fmt, ap);
        va_end(ap);
    }
    return status;
}

static double wrap(double angle)
{
    const double pi = 3.14159265358979323846;
    if (angle > pi) return angle - 2 * pi;
    if (angle < -pi) return angle + 2 * pi;
    return angle;
}

/* From the half-angle sums (as the Python quat_to_rpy, which explains them):
 * accurate to a few ulp in the quaternion written back, also next to the
 * gimbal lock, where reading the rotation matrix would not be. */
void bench_quat_to_rpy(const double q[4], double rpy[3])
{
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double plus = hypot(w + y, z - x), minus = hypot(w - y, z + x);
    const double total = 2.0 * atan2(z + x, w - y), difference = 2.0 * atan2(z - x, w + y);
    rpy[1] = 2.0 * atan2(plus - minus, plus + minus);
    rpy[0] = wrap(0.5 * (total - difference));
    rpy[2] = wrap(0.5 * (total + difference));
}

/* %.17g of v, with -0 printed as 0 (as the Python writer does). */
static void put(FILE *f, double v) { fprintf(f, "%.17g", v + 0.0); }

static void put3(FILE *f, const double v[3])
{
    put(f, v[0]);
    fputc(' ', f);
    put(f, v[1]);
    fputc(' ', f);
    put(f, v[2]);
}

static const char *urdf_type(int32_t type)
{
    switch (type) {
    case AQS_JOINT_REVOLUTE: return "continuous";
    case AQS_JOINT_PRISMATIC: return "prismatic";
    case AQS_JOINT_FREE: return "floating";
    case AQS_JOINT_FIXED: return "fixed";
    case AQS_JOINT_PLANAR: return "planar";
    default: return NULL;
    }
}

static aqs_status write_links(const aqs_linkage *L, FILE *f, int32_t bodies, char *message,
                              size_t size)
{
    int32_t b;
    fputs("  <link name=\"world\"/>\n", f);
    for (b = 0; b < bodies; b++) {
        double mass, com[3], I[9];
        const aqs_status st = aqs_body_get_inertial(L, b, &mass, com, I);
        if (st != AQS_OK)
            return fail(message, size, st, "body %d: %s", (int)b, aqs_linkage_last_error(L));
        fprintf(f, "  <link name=\"link_%d\">\n    <inertial>\n      <origin xyz=\"", (int)b);
        put3(f, com);
        fputs("\" rpy=\"0 0 0\"/>\n      <mass value=\"", f);
        put(f, mass);
        fputs("\"/>\n      <inertia ixx=\"", f);
        put(f, I[0]);
        fputs("\" ixy=\"", f);
        put(f, I[1]);
        fputs("\" ixz=\"", f);
        put(f, I[2]);
        fputs("\" iyy=\"", f);
        put(f, I[4]);
        fputs("\" iyz=\"", f);
        put(f, I[5]);
        fputs("\" izz=\"", f);
        put(f, I[8]);
        fputs("\"/>\n    </inertial>\n  </link>\n", f);
    }
    return AQS_OK;
}

static aqs_status write_joints(const aqs_linkage *L, FILE *f, int32_t joints, char *message,
                               size_t size)
{
    int32_t j;
    for (j = 0; j < joints; j++) {
        double pos[3], quat[4], axis[3], rpy[3];
        int32_t type, parent, child;
        const char *kind;
        const aqs_status st =
            aqs_joint_get_definition(L, j, &type, &parent, &child, pos, quat, axis);
        if (st != AQS_OK)
            return fail(message, size, st, "joint %d: %s", (int)j, aqs_linkage_last_error(L));
        kind = urdf_type(type);
        if (!kind)
            return fail(message, size, AQS_EINVAL,
                        "joint %d has type %d, which URDF cannot express (only revolute, "
                        "prismatic, free, fixed and planar)", (int)j, (int)type);
        bench_quat_to_rpy(quat, rpy);
        fprintf(f, "  <joint name=\"joint_%d\" type=\"%s\">\n    <origin xyz=\"", (int)j, kind);
        put3(f, pos);
        fputs("\" rpy=\"", f);
        put3(f, rpy);
        if (parent == AQS_WORLD)
            fputs("\"/>\n    <parent link=\"world\"/>\n", f);
        else
            fprintf(f, "\"/>\n    <parent link=\"link_%d\"/>\n", (int)parent);
        fprintf(f, "    <child link=\"link_%d\"/>\n", (int)child);
        if (type == AQS_JOINT_REVOLUTE || type == AQS_JOINT_PRISMATIC || type == AQS_JOINT_PLANAR) {
            fputs("    <axis xyz=\"", f);
            put3(f, axis);
            fputs("\"/>\n", f);
        }
        if (type == AQS_JOINT_PRISMATIC)
            fputs("    <limit lower=\"-1e300\" upper=\"1e300\" effort=\"1e300\" velocity=\"1e300\"/>\n", f);
        fputs("  </joint>\n", f);
    }
    return AQS_OK;
}

aqs_status bench_export_urdf(const aqs_linkage *L, const char *path, const char *robot_name,
                             char *message, size_t size)
{
    int32_t bodies = 0, joints = 0;
    aqs_status st;
    FILE *f;
    if (!L || !path) return fail(message, size, AQS_EINVAL, "linkage or path is NULL");
    if (!robot_name) robot_name = "aqs";
    if ((st = aqs_linkage_get_sizes(L, &bodies, &joints, NULL, NULL)) != AQS_OK)
        return fail(message, size, st, "%s", aqs_linkage_last_error(L));
    f = fopen(path, "w");
    if (!f) return fail(message, size, AQS_EINVAL, "cannot open %s for writing", path);
    fprintf(f, "<?xml version='1.0' encoding='utf-8'?>\n<robot name=\"%s\">\n", robot_name);
    st = write_links(L, f, bodies, message, size);
    if (st == AQS_OK) st = write_joints(L, f, joints, message, size);
    if (st == AQS_OK) fputs("</robot>\n", f);
    if (ferror(f) && st == AQS_OK)
        st = fail(message, size, AQS_EINVAL, "write error on %s", path);
    if (fclose(f) != 0 && st == AQS_OK)
        st = fail(message, size, AQS_EINVAL, "write error on %s", path);
    if (st != AQS_OK) remove(path);
    return st;
}
