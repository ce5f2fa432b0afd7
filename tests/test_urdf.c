/* test_urdf.c -- src/api/names.c (body and joint names, joint limits) and
 * src/api/urdf.c (the URDF loader).
 *
 * References: the numbers written in the URDF documents themselves, and
 * rotations built here by Rodrigues' formula (tests/support), not by the
 * loader's rpy code. Errors: every message names the link or joint and the
 * value; a failed load leaves the linkage empty and usable again; the
 * counting allocator finds no leak and a failing allocator reaches every
 * out-of-memory path of the loader. */
#define _POSIX_C_SOURCE 200809L /* mkstemp, fdopen */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "aqs.h"
#include "testutil.h"

/* ------------------------------------------------------------------ names */

static void test_names(void **state)
{
    counting_state cs = {0};
    aqs_linkage *L;
    const char *name = NULL;
    int32_t i = 7;
    char longname[5000];
    (void)state;
    assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
    test_add_body(L, 1, 0, 0, 0, 0.1);
    test_add_body(L, 1, 0, 0, 0, 0.1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, AQS_WORLD, 0, 0, 0, 0, 0, 0, 1);
    test_add_joint(L, AQS_JOINT_REVOLUTE, 0, 1, 1, 0, 0, 0, 0, 1);
    /* unnamed: "" and not found */
    assert_int_equal(aqs_body_get_name(L, 1, &name), AQS_OK);
    assert_string_equal(name, "");
    assert_int_equal(aqs_body_find(L, "arm", &i), AQS_ERANGE);
    assert_int_equal(i, -1);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_body_find: no body is named 'arm'");
    assert_int_equal(aqs_body_set_name(L, 1, "arm"), AQS_OK);
    assert_int_equal(aqs_body_set_name(L, 0, "base"), AQS_OK);
    assert_int_equal(aqs_joint_set_name(L, 1, "elbow"), AQS_OK);
    assert_int_equal(aqs_body_find(L, "arm", &i), AQS_OK);
    assert_int_equal(i, 1);
    assert_int_equal(aqs_joint_find(L, "elbow", &i), AQS_OK);
    assert_int_equal(i, 1);
    assert_int_equal(aqs_joint_find(L, "arm", &i), AQS_ERANGE); /* names per kind */
    /* rename; duplicates allowed, the lowest index is found */
    assert_int_equal(aqs_body_set_name(L, 1, "base"), AQS_OK);
    assert_int_equal(aqs_body_find(L, "base", &i), AQS_OK);
    assert_int_equal(i, 0);
    assert_int_equal(aqs_body_get_name(L, 1, &name), AQS_OK);
    assert_string_equal(name, "base");
    assert_int_equal(aqs_body_find(L, "arm", &i), AQS_ERANGE);
    /* errors change nothing */
    assert_int_equal(aqs_body_set_name(L, 2, "x"), AQS_ERANGE);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_body_set_name: body = 2 is out of range [0, 2)");
    assert_int_equal(aqs_joint_set_name(L, -1, "x"), AQS_ERANGE);
    assert_int_equal(aqs_joint_set_name(L, 0, ""), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "name is empty (joint 0)");
    assert_int_equal(aqs_body_set_name(L, 0, NULL), AQS_EINVAL);
    memset(longname, 'a', sizeof longname - 1);
    longname[sizeof longname - 1] = 0;
    assert_int_equal(aqs_body_set_name(L, 0, longname), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "4999 bytes");
    assert_int_equal(aqs_body_get_name(L, 0, NULL), AQS_EINVAL);
    assert_int_equal(aqs_joint_get_name(L, 2, &name), AQS_ERANGE);
    assert_int_equal(aqs_body_find(L, NULL, &i), AQS_EINVAL);
    assert_int_equal(aqs_body_find(L, "base", NULL), AQS_EINVAL);
    assert_int_equal(aqs_body_find(NULL, "base", &i), AQS_EINVAL);
    assert_int_equal(aqs_body_get_name(L, 0, &name), AQS_OK);
    assert_string_equal(name, "base");
    /* names survive finalize, can be set afterwards, and appear in finalize's messages */
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_joint_set_name(L, 0, "shoulder"), AQS_OK);
    assert_int_equal(aqs_joint_get_name(L, 0, &name), AQS_OK);
    assert_string_equal(name, "shoulder");
    aqs_linkage_destroy(L);
    assert_int_equal(cs.live, 0);
}

static void test_names_oom(void **state)
{
    long k;
    (void)state;
    for (k = 1; k < 40; k++) {
        counting_state cs = {0};
        aqs_linkage *L;
        aqs_status st = AQS_OK;
        int32_t b, n;
        assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
        cs.fail_at = cs.count + k;
        for (n = 0; n < 20 && st == AQS_OK; n++) {
            double com[3] = {0, 0, 0}, I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            char name[16];
            st = aqs_body_add(L, 1, com, I, &b);
            snprintf(name, sizeof name, "b%d", (int)n);
            if (st == AQS_OK) st = aqs_body_set_name(L, b, name);
        }
        if (st != AQS_OK) {
            const char *got;
            assert_int_equal(st, AQS_ENOMEM);
            /* what was named before the failure still is */
            if (n > 1) {
                assert_int_equal(aqs_body_get_name(L, 0, &got), AQS_OK);
                assert_string_equal(got, "b0");
            }
        }
        aqs_linkage_destroy(L);
        assert_int_equal(cs.live, 0);
    }
}

static void test_limits(void **state)
{
    aqs_linkage *L = test_new_linkage();
    double lo, hi, eff, vel;
    (void)state;
    test_add_body(L, 1, 0, 0, 0, 0.1);
    test_add_joint(L, AQS_JOINT_PRISMATIC, AQS_WORLD, 0, 0, 0, 0, 1, 0, 0);
    assert_int_equal(aqs_joint_get_limits(L, 0, &lo, &hi, &eff, &vel), AQS_OK);
    assert_true(lo == -INFINITY && hi == INFINITY && eff == INFINITY && vel == INFINITY);
    assert_int_equal(aqs_joint_set_limits(L, 0, -0.2, 0.2, 150, 3.15), AQS_OK);
    assert_int_equal(aqs_joint_get_limits(L, 0, &lo, &hi, NULL, NULL), AQS_OK);
    assert_true(lo == -0.2 && hi == 0.2);
    assert_int_equal(aqs_joint_set_limits(L, 0, 0.3, 0.2, 1, 1), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "lower = 0.3, upper = 0.2");
    assert_int_equal(aqs_joint_set_limits(L, 0, NAN, 0.2, 1, 1), AQS_EINVAL);
    assert_int_equal(aqs_joint_set_limits(L, 0, INFINITY, INFINITY, 1, 1), AQS_EINVAL);
    assert_int_equal(aqs_joint_set_limits(L, 0, 0, 1, -1, 1), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "effort = -1");
    assert_int_equal(aqs_joint_set_limits(L, 0, 0, 1, 1, NAN), AQS_EINVAL);
    assert_int_equal(aqs_joint_set_limits(L, 1, 0, 1, 1, 1), AQS_ERANGE);
    assert_int_equal(aqs_joint_get_limits(L, 1, NULL, NULL, NULL, NULL), AQS_ERANGE);
    assert_int_equal(aqs_joint_get_limits(L, 0, NULL, NULL, &eff, &vel), AQS_OK);
    assert_true(eff == 150 && vel == 3.15); /* the failed calls changed nothing */
    /* Not enforced: a force along the prismatic joint slides it past its limit. */
    {
        double f[3] = {1, 0, 0}, q;
        assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
        assert_int_equal(aqs_body_set_force(L, 0, f, NULL, NULL), AQS_OK);
        assert_int_equal(aqs_linkage_step(L, 1.0), AQS_OK);
        assert_int_equal(aqs_joint_get_position(L, 0, &q, 1), AQS_OK);
        assert_true(q > 0.2);
    }
    aqs_linkage_destroy(L);
}

/* ------------------------------------------------------------------- URDF */

/* A URDF as CAD exporters write it: a massive root link, massless frames
 * and a point mass welded by fixed joints, offset and turned inertial
 * frames, limits, and what aqs does not model. */
static const char cad_arm[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "<robot name=\"cad_arm\">\n"
    "  <material name=\"grey\"><color rgba=\"0.5 0.5 0.5 1\"/></material>\n"
    "  <link name=\"base_link\">\n"
    "    <inertial><origin xyz=\"0 0 0.05\"/><mass value=\"5.0\"/>\n"
    "      <inertia ixx=\"0.02\" ixy=\"0\" ixz=\"0\" iyy=\"0.02\" iyz=\"0\" izz=\"0.03\"/></inertial>\n"
    "    <collision><origin xyz=\"0 0 0.05\" rpy=\"0 0 0.3\"/><geometry><box size=\"0.2 0.4 0.1\"/></geometry></collision>\n"
    "  </link>\n"
    "  <link name=\"shoulder_frame\"/>\n"
    "  <link name=\"upper_arm\">\n"
    "    <inertial><origin xyz=\"0.45 0.02 0\" rpy=\"0.3 -0.2 0.5\"/><mass value=\"2.0\"/>\n"
    "      <inertia ixx=\"0.004\" ixy=\"0.0001\" ixz=\"0\" iyy=\"0.17\" iyz=\"0\" izz=\"0.168\"/></inertial>\n"
    "    <collision><geometry><cylinder radius=\"0.05\" length=\"0.9\"/></geometry></collision>\n"
    "    <collision><geometry><mesh filename=\"package://cad_arm/upper.stl\"/></geometry></collision>\n"
    "  </link>\n"
    "  <link name=\"sensor\">\n"
    "    <inertial><origin xyz=\"0.1 0.05 0\"/><mass value=\"0.01\"/>\n"
    "      <inertia ixx=\"0\" ixy=\"0\" ixz=\"0\" iyy=\"0\" iyz=\"0\" izz=\"0\"/></inertial>\n"
    "    <collision><geometry><sphere radius=\"0.02\"/></geometry></collision>\n"
    "  </link>\n"
    "  <link name=\"slider\">\n"
    "    <inertial><mass value=\"0.5\"/>\n"
    "      <inertia ixx=\"0.001\" ixy=\"0\" ixz=\"0\" iyy=\"0.001\" iyz=\"0\" izz=\"0.001\"/></inertial>\n"
    "    <collision><geometry><capsule radius=\"0.01\" length=\"0.1\"/></geometry></collision>\n"
    "  </link>\n"
    "  <joint name=\"base_to_shoulder_frame\" type=\"fixed\">\n"
    "    <origin xyz=\"0 0 0.1\" rpy=\"0 0 0.25\"/>\n"
    "    <parent link=\"base_link\"/><child link=\"shoulder_frame\"/>\n"
    "  </joint>\n"
    "  <joint name=\"shoulder\" type=\"revolute\">\n"
    "    <origin xyz=\"0 0 0\" rpy=\"0.1 0.2 0.3\"/>\n"
    "    <parent link=\"shoulder_frame\"/><child link=\"upper_arm\"/>\n"
    "    <axis xyz=\"0 0 2\"/>\n"
    "    <limit lower=\"-3.14\" upper=\"3.14\" effort=\"150\" velocity=\"3.15\"/>\n"
    "    <dynamics damping=\"0.5\" friction=\"0.1\"/>\n"
    "  </joint>\n"
    "  <joint name=\"sensor_mount\" type=\"fixed\">\n"
    "    <origin xyz=\"0.9 0 0\"/><parent link=\"upper_arm\"/><child link=\"sensor\"/>\n"
    "  </joint>\n"
    "  <joint name=\"slide\" type=\"prismatic\">\n"
    "    <origin xyz=\"0.5 0 0\"/><parent link=\"upper_arm\"/><child link=\"slider\"/>\n"
    "    <axis xyz=\"1 0 0\"/><limit lower=\"-0.2\" upper=\"0.2\" effort=\"10\" velocity=\"0.5\"/>\n"
    "    <mimic joint=\"shoulder\" multiplier=\"0.1\"/>\n"
    "  </joint>\n"
    "  <transmission name=\"shoulder_trans\"><type>SimpleTransmission</type></transmission>\n"
    "  <gazebo reference=\"upper_arm\"><material>Gazebo/Grey</material></gazebo>\n"
    "</robot>\n";

static aqs_linkage *load(const char *text, int32_t root, int32_t collision, aqs_status expect)
{
    aqs_linkage *L = test_new_linkage();
    aqs_urdf_options o;
    aqs_status st;
    aqs_urdf_options_init(&o);
    o.root = root;
    o.collision = collision;
    st = aqs_linkage_load_urdf_buffer(L, text, strlen(text), "test.urdf", &o);
    if (st != expect) {
        print_error("load: status %d, expected %d: %s\n", (int)st, (int)expect,
                    aqs_linkage_last_error(L));
        fail();
    }
    return L;
}

static void rpy_reference(double r, double p, double y, double R[9])
{
    static const double x[3] = {1, 0, 0}, ya[3] = {0, 1, 0}, z[3] = {0, 0, 1};
    double Rx[9], Ry[9], Rz[9], T[9];
    test_rodrigues(x, r, Rx);
    test_rodrigues(ya, p, Ry);
    test_rodrigues(z, y, Rz);
    test_mat3_mul(Rz, Ry, T);
    test_mat3_mul(T, Rx, R);
}

static void test_load_cad_arm(void **state)
{
    static const char *const bodies[5] = {"base_link", "shoulder_frame", "upper_arm", "sensor", "slider"};
    static const char *const joints[5] = {"world_to_base_link", "base_to_shoulder_frame", "shoulder",
                                          "sensor_mount", "slide"};
    aqs_linkage *L;
    int32_t nb, nj, nq, nv, k, type, parent, child, shapes;
    double mass, com[3], I[9], pos[3], quat[4], axis[3], R[9], Rq[9], lo, hi, eff, vel;
    const char *name, *w;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    L = load(cad_arm, AQS_URDF_ROOT_FIXED, 1, AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, &nq, &nv), AQS_OK);
    assert_int_equal(nb, 5);
    assert_int_equal(nj, 5);
    assert_int_equal(nv, 2);
    for (k = 0; k < 5; k++) {
        assert_int_equal(aqs_body_get_name(L, k, &name), AQS_OK);
        assert_string_equal(name, bodies[k]);
        assert_int_equal(aqs_joint_get_name(L, k, &name), AQS_OK);
        assert_string_equal(name, joints[k]);
        assert_int_equal(aqs_joint_find(L, joints[k], &type), AQS_OK);
        assert_int_equal(type, k);
    }
    /* joint 0: the massive root welded to the world */
    assert_int_equal(aqs_joint_get_definition(L, 0, &type, &parent, &child, NULL, NULL, NULL), AQS_OK);
    assert_true(type == AQS_JOINT_FIXED && parent == AQS_WORLD && child == 0);
    /* the shoulder: origin and rpy of the file, axis normalized */
    assert_int_equal(aqs_joint_get_definition(L, 2, &type, &parent, &child, pos, quat, axis), AQS_OK);
    assert_true(type == AQS_JOINT_REVOLUTE && parent == 1 && child == 2);
    rpy_reference(0.1, 0.2, 0.3, R);
    test_quat_matrix(quat, Rq);
    assert_true(test_max_abs_diff(R, Rq, 9) < 1e-15);
    assert_true(axis[0] == 0 && axis[1] == 0 && axis[2] == 1);
    /* upper_arm's inertia: R I R^T of the file's numbers, com at its xyz */
    assert_int_equal(aqs_body_get_inertial(L, 2, &mass, com, I), AQS_OK);
    {
        double Ifile[9] = {0.004, 0.0001, 0, 0.0001, 0.17, 0, 0, 0, 0.168}, T[9], RT[9], expect[9];
        int a, b;
        rpy_reference(0.3, -0.2, 0.5, R);
        for (a = 0; a < 3; a++)
            for (b = 0; b < 3; b++) RT[3 * a + b] = R[3 * b + a];
        test_mat3_mul(R, Ifile, T);
        test_mat3_mul(T, RT, expect);
        assert_true(mass == 2.0 && com[0] == 0.45 && com[1] == 0.02 && com[2] == 0);
        assert_true(test_max_abs_diff(I, expect, 9) < 1e-16);
    }
    /* the point mass: as written (welded to upper_arm, so finalize accepted it) */
    assert_int_equal(aqs_body_get_inertial(L, 3, &mass, com, I), AQS_OK);
    assert_true(mass == 0.01 && com[0] == 0.1 && com[1] == 0.05 && I[0] == 0 && I[4] == 0);
    /* limits */
    assert_int_equal(aqs_joint_get_limits(L, 2, &lo, &hi, &eff, &vel), AQS_OK);
    assert_true(lo == -3.14 && hi == 3.14 && eff == 150 && vel == 3.15);
    assert_int_equal(aqs_joint_get_limits(L, 4, &lo, &hi, &eff, &vel), AQS_OK);
    assert_true(lo == -0.2 && hi == 0.2 && eff == 10 && vel == 0.5);
    assert_int_equal(aqs_joint_get_limits(L, 3, &lo, &hi, NULL, NULL), AQS_OK);
    assert_true(lo == -INFINITY && hi == INFINITY);
    /* collision: box, cylinder, sphere, capsule; the mesh is reported */
    assert_int_equal(aqs_linkage_get_shape_count(L, &shapes), AQS_OK);
    assert_int_equal(shapes, 4);
    w = aqs_linkage_load_warnings(L);
    test_assert_contains(w, "test.urdf: <mimic> is not modelled (the joints move independently): joints 'slide' (1)");
    test_assert_contains(w, "<transmission> is not modelled: 'shoulder_trans' (1)");
    test_assert_contains(w, "<gazebo> (simulator settings) is not modelled: references 'upper_arm' (1)");
    test_assert_contains(w, "<dynamics> (damping, friction) is not modelled");
    test_assert_contains(w, "<collision> meshes are not loaded (aqs loads box, sphere, cylinder, capsule): links 'upper_arm' (1)");
    assert_null(strstr(w, "material")); /* visual only: not reported */
    assert_true(w[strlen(w) - 1] != '\n');
    aqs_linkage_destroy(L);

    /* Without collision: no shapes, and the same linkage otherwise. */
    L = load(cad_arm, AQS_URDF_ROOT_FIXED, 0, AQS_OK);
    assert_int_equal(aqs_linkage_get_shape_count(L, &shapes), AQS_OK);
    assert_int_equal(shapes, 0);
    aqs_linkage_destroy(L);

    /* Floating: the massive root gets a free joint. */
    L = load(cad_arm, AQS_URDF_ROOT_FREE, 0, AQS_OK);
    assert_int_equal(aqs_joint_get_definition(L, 0, &type, &parent, &child, NULL, NULL, NULL), AQS_OK);
    assert_true(type == AQS_JOINT_FREE && parent == AQS_WORLD && child == 0);
    aqs_linkage_destroy(L);
}

/* The gravity torque of a one-joint arm loaded from URDF equals the one
 * computed from the file's numbers: tau = (p_com - p_axis) x (m g) . a. */
static void test_load_solves_like_the_file(void **state)
{
    static const char doc[] =
        "<robot name='r'><link name='world'/>"
        "<link name='a'><inertial><origin xyz='0.3 0.1 0'/><mass value='2'/>"
        "<inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial></link>"
        "<link name='tip'><inertial><origin xyz='0.2 0 0'/><mass value='0.01'/>"
        "<inertia ixx='0' ixy='0' ixz='0' iyy='0' iyz='0' izz='0'/></inertial></link>"
        "<joint name='j' type='continuous'><origin xyz='0 0 1' rpy='1.5707963267948966 0 0'/>"
        "<parent link='world'/><child link='a'/><axis xyz='0 0 1'/></joint>"
        "<joint name='w' type='fixed'><origin xyz='0.5 0 0'/><parent link='a'/><child link='tip'/></joint>"
        "</robot>";
    aqs_linkage *L;
    double g[3] = {0, 0, -9.81}, qdd, izz_total, tau;
    int32_t nb;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    L = load(doc, AQS_URDF_ROOT_FIXED, 0, AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(nb, 2); /* the massless root is the world */
    assert_int_equal(aqs_linkage_set_gravity(L, g), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    assert_int_equal(aqs_joint_get_acceleration(L, 0, &qdd, 1), AQS_OK);
    /* joint frame: x along world x, z (the axis) along world -y, y along world z.
     * Coms in the joint frame: a (0.3, 0.1, 0), tip (0.7, 0, 0). Gravity in
     * the joint frame is (0, -9.81, 0). Torque about z: sum m (x g_y - y g_x). */
    tau = 2 * (0.3 * -9.81) + 0.01 * (0.7 * -9.81);
    izz_total = 0.1 + 2 * (0.3 * 0.3 + 0.1 * 0.1) + 0.01 * 0.7 * 0.7;
    assert_true(fabs(qdd - tau / izz_total) <= 1e-13 * fabs(tau / izz_total));
    aqs_linkage_destroy(L);
}

/* Shapes where the file puts them: an obstacle probe sphere (radius 0.01)
 * just outside / just inside each face the file describes, by the
 * independent rotation of the collision origin. */
static void test_collision_placement(void **state)
{
    static const char doc[] =
        "<robot name='r'><link name='world'/>"
        "<link name='a'><inertial><mass value='1'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial>"
        "<collision><origin xyz='0.5 0 0' rpy='0 0 0.3'/><geometry><box size='0.2 0.4 0.1'/></geometry></collision>"
        "<collision><origin xyz='-0.5 0 0' rpy='0.4 0 0'/><geometry><capsule radius='0.02' length='0.1'/></geometry></collision>"
        "<collision><origin xyz='0 0.8 0'/><geometry><cylinder radius='0.03' length='0.3'/></geometry></collision>"
        "</link><joint name='j' type='continuous'><parent link='world'/><child link='a'/></joint></robot>";
    /* shape centre, rotation (axis z, x), local direction, distance of the face */
    static const struct { double c[3], axis[3], angle, dir[3], face; } probes[] = {
        {{0.5, 0, 0}, {0, 0, 1}, 0.3, {0, 1, 0}, 0.2},   /* box half extent y */
        {{0.5, 0, 0}, {0, 0, 1}, 0.3, {1, 0, 0}, 0.1},   /* box half extent x */
        {{-0.5, 0, 0}, {1, 0, 0}, 0.4, {0, 0, 1}, 0.07}, /* capsule: half-length + radius */
        {{0, 0.8, 0}, {0, 0, 1}, 0.0, {0, 0, 1}, 0.15},  /* cylinder half height */
        {{0, 0.8, 0}, {0, 0, 1}, 0.0, {1, 0, 0}, 0.03},  /* cylinder radius */
    };
    size_t k;
    int side;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    for (k = 0; k < sizeof probes / sizeof probes[0]; k++)
        for (side = -1; side <= 1; side += 2) {
            aqs_linkage *L = load(doc, AQS_URDF_ROOT_FIXED, 1, AQS_OK);
            double R[9], p[3], size[3] = {0.01, 0, 0}, q[4] = {1, 0, 0, 0};
            double d = probes[k].face + 0.01 + side * 2e-3; /* -: overlapping, +: apart */
            int32_t hit = -1, i;
            test_rodrigues(probes[k].axis, probes[k].angle, R);
            for (i = 0; i < 3; i++)
                p[i] = probes[k].c[i] + d * (R[3 * i] * probes[k].dir[0] + R[3 * i + 1] * probes[k].dir[1] +
                                             R[3 * i + 2] * probes[k].dir[2]);
            assert_int_equal(aqs_shape_add(L, AQS_WORLD, AQS_SHAPE_SPHERE, size, p, q, NULL), AQS_OK);
            assert_int_equal(aqs_linkage_any_contact(L, &hit), AQS_OK);
            if (hit != (side < 0)) {
                print_error("probe %d side %d: hit %d\n", (int)k, side, (int)hit);
                fail();
            }
            aqs_linkage_destroy(L);
        }
}

#define WORLD_LINK "<link name='world'/>"
#define LINK(n) "<link name='" n "'><inertial><mass value='1'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial></link>"
#define JOINT(n, type, p, c, extra) "<joint name='" n "' type='" type "'><parent link='" p "'/><child link='" c "'/>" extra "</joint>"
#define ROBOT(body) "<robot name='bad'>" body "</robot>"

static const struct {
    const char *doc, *message;
    aqs_status status;
} errors[] = {
    {"<robot>", "test.urdf: not well-formed XML (no element found) at line 1", AQS_EINVAL},
    {"<?xml version='1.0' encoding='klingon-8'?><robot/>", "not well-formed XML (unknown encoding)", AQS_EINVAL},
    {"", "not well-formed XML (no element found)", AQS_EINVAL},
    {"<model/>", "the root element is <model>, not <robot>", AQS_EINVAL},
    {ROBOT(""), "no <link>", AQS_EINVAL},
    {ROBOT(LINK("a") LINK("a")), "link 'a' is defined twice", AQS_EINVAL},
    {ROBOT("<link/>"), "a <link> has no name", AQS_EINVAL},
    {ROBOT(LINK("a") LINK("b") LINK("c") JOINT("ab", "continuous", "a", "b", "") JOINT("bc", "continuous", "b", "c", "") JOINT("ca", "continuous", "c", "a", "")),
     "cycle: every link has a parent ('a' <- 'c' <- 'b' <- 'a')", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") LINK("b") LINK("c") JOINT("wa", "continuous", "world", "a", "") JOINT("bc", "continuous", "b", "c", "") JOINT("cb", "continuous", "c", "b", "")),
     "cycle not connected to the root link 'world' ('b' <- 'c' <- 'b')", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") LINK("b") JOINT("wa", "continuous", "world", "a", "")),
     "several root links (links that are no joint's child): 'world', 'b'", AQS_EINVAL},
    {ROBOT(WORLD_LINK JOINT("wa", "continuous", "world", "ghost", "")), "joint 'wa': child link 'ghost' is not defined", AQS_EINVAL},
    {ROBOT(WORLD_LINK "<link name='a'><inertial><mass value='2'/></inertial></link>" JOINT("wa", "continuous", "world", "a", "")),
     "link 'a': <inertial> has mass 2 but no <inertia>", AQS_EINVAL},
    {ROBOT(WORLD_LINK "<link name='a'><inertial><mass value='-1'/><inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link>" JOINT("wa", "continuous", "world", "a", "")),
     "link 'a': mass = -1 is negative", AQS_EINVAL},
    {ROBOT(WORLD_LINK "<link name='a'><inertial><mass value='1'/><inertia ixx='0' ixy='0' ixz='0' iyy='0' iyz='0' izz='0'/></inertial></link>" JOINT("wa", "continuous", "world", "a", "")),
     "aqs_linkage_finalize: body 0 'a' (welded to no other body) has a singular inertia (total mass 1)", AQS_EMODEL},
    {ROBOT(WORLD_LINK "<link name='a'/>" LINK("b") JOINT("wa", "continuous", "world", "a", "") JOINT("ab", "continuous", "a", "b", "")),
     "link 'a' has no mass (no <inertial>) and is not welded by fixed joints to a link with mass or to the world (its rigid group: 'a')", AQS_EINVAL},
    {ROBOT(WORLD_LINK "<link name='a'/><link name='b'/>" JOINT("wa", "continuous", "world", "a", "") JOINT("ab", "fixed", "a", "b", "")),
     "rigid group: 'a', 'b'", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "spherical", "world", "a", "")),
     "joint 'wa': type = 'spherical' is not supported (aqs loads continuous, fixed, floating, planar, prismatic, revolute)", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") LINK("b") JOINT("wa", "continuous", "world", "a", "") JOINT("ab", "floating", "a", "b", "")),
     "joint 'ab': a floating joint must hang from the massless root link (the world); its parent is 'a'", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") LINK("b") JOINT("wa", "continuous", "world", "a", "") JOINT("wb", "continuous", "world", "b", "") JOINT("ab", "continuous", "a", "b", "")),
     "link 'b' is the child of two joints ('wb' and 'ab')", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<origin xyz='1 two 3'/>")),
     "joint 'wa' <origin>: xyz = '1 two 3' is not 3 numbers", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<origin xyz='1 2'/>")),
     "joint 'wa' <origin>: xyz = '1 2' has 2 numbers, expected 3", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<axis xyz='0 nan 1'/>")),
     "joint 'wa' <axis>: xyz = '0 nan 1' is not finite", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<axis xyz='0 0x1 1'/>")),
     "xyz = '0 0x1 1' is not 3 numbers", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<axis xyz='0 0 0'/>")),
     "joint 'wa': <axis xyz> is zero", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "revolute", "world", "a", "<limit lower='1' upper='-1'/>")),
     "joint 'wa' <limit>: lower = 1 is above upper = -1", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "<limit effort='-1'/>")),
     "joint 'wa' <limit>: effort = -1 is negative", AQS_EINVAL},
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "")),
     NULL, AQS_OK},
    {ROBOT(WORLD_LINK "<link name='a'><inertial><mass value='1'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial>"
           "<collision><geometry><sphere radius='-1'/></geometry></collision></link>" JOINT("wa", "continuous", "world", "a", "")),
     "link 'a' <collision> <sphere>: aqs_shape_add: ", AQS_EINVAL},
    {ROBOT(WORLD_LINK "<link name='a'><inertial><mass value='1'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial>"
           "<collision><geometry><box size='1 1'/></geometry></collision></link>" JOINT("wa", "continuous", "world", "a", "")),
     "link 'a' <collision> <box>: size = '1 1' has 2 numbers, expected 3", AQS_EINVAL},
    /* root = free with a massless root that has nothing welded to float */
    {ROBOT(WORLD_LINK LINK("a") JOINT("wa", "continuous", "world", "a", "")), "#free", AQS_EINVAL},
};

static void test_load_errors(void **state)
{
    size_t k;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    for (k = 0; k < sizeof errors / sizeof errors[0]; k++) {
        int free_root = errors[k].message && strcmp(errors[k].message, "#free") == 0;
        aqs_linkage *L = load(errors[k].doc, free_root ? AQS_URDF_ROOT_FREE : AQS_URDF_ROOT_FIXED, 1,
                              errors[k].status);
        int32_t nb = -1, nj = -1, ns = -1;
        if (errors[k].status != AQS_OK) {
            const char *msg = aqs_linkage_last_error(L);
            test_assert_contains(msg, "aqs_linkage_load_urdf_buffer: test.urdf: ");
            if (free_root)
                test_assert_contains(msg, "root = free, but the root link 'world' has no mass and no link with mass is welded to it");
            else
                test_assert_contains(msg, errors[k].message);
            /* empty again, and usable: the same linkage loads a good file */
            assert_int_equal(aqs_linkage_get_sizes(L, &nb, &nj, NULL, NULL), AQS_OK);
            assert_int_equal(aqs_linkage_get_shape_count(L, &ns), AQS_OK);
            assert_true(nb == 0 && nj == 0 && ns == 0);
            assert_string_equal(aqs_linkage_load_warnings(L), "");
            assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, NULL), AQS_OK);
        }
        aqs_linkage_destroy(L);
    }
}

static void test_load_arguments(void **state)
{
    aqs_linkage *L = test_new_linkage();
    aqs_urdf_options o;
    char path[] = "/tmp/aqs_test_urdf_XXXXXX";
    FILE *f;
    int fd;
    (void)state;
    if (!aqs_urdf_supported()) {
        assert_int_equal(aqs_linkage_load_urdf(L, "x.urdf", NULL), AQS_ESTATE);
        test_assert_contains(aqs_linkage_last_error(L), "built without URDF support");
        aqs_linkage_destroy(L);
        skip();
    }
    assert_int_equal(aqs_linkage_load_urdf(NULL, "x", NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_load_urdf(L, NULL, NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_load_urdf: path is NULL");
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, NULL, 3, NULL, NULL), AQS_EINVAL);
    assert_int_equal(aqs_linkage_load_urdf(L, "/nonexistent/robot.urdf", NULL), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "aqs_linkage_load_urdf: /nonexistent/robot.urdf: cannot read (");
    aqs_urdf_options_init(&o);
    o.root = 2;
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, &o), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "options->root = 2");
    aqs_urdf_options_init(&o);
    o.collision = 5;
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, &o), AQS_EINVAL);
    o.collision = 0;
    o.size = 0;
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, &o), AQS_EINVAL);
    test_assert_contains(aqs_linkage_last_error(L), "options->size = 0");
    /* an older caller's smaller struct: the fields it lacks take their defaults */
    o.size = (uint32_t)offsetof(aqs_urdf_options, collision);
    o.finalize = 0; /* beyond size: ignored */
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), "<memory>", &o), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK); /* finalized */
    /* only into an empty linkage */
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, NULL), AQS_ESTATE);
    test_assert_contains(aqs_linkage_last_error(L), "the linkage must be empty (it has 5 bodies, 5 joints, finalized)");
    aqs_linkage_destroy(L);

    /* From a file, left building with finalize = 0. */
    fd = mkstemp(path);
    assert_true(fd >= 0);
    f = fdopen(fd, "w");
    fputs(cad_arm, f);
    fclose(f);
    L = test_new_linkage();
    aqs_urdf_options_init(&o);
    o.finalize = 0;
    assert_int_equal(aqs_linkage_load_urdf(L, path, &o), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_ESTATE);
    assert_int_equal(aqs_linkage_finalize(L), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    aqs_linkage_destroy(L);
    remove(path);

    /* Collision settings without a shape leave a linkage empty: it loads (it
     * was refused, "it has 0 bodies, 0 joints, shapes", until 2026-12-05). */
    L = test_new_linkage();
    assert_int_equal(aqs_body_set_collision_filter(L, AQS_WORLD, 4, 4), AQS_OK);
    assert_int_equal(aqs_linkage_set_collide_joined(L, 1), AQS_OK);
    assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, NULL), AQS_OK);
    assert_int_equal(aqs_linkage_solve(L), AQS_OK);
    aqs_linkage_destroy(L);
}

/* root = free: a massless root link floats with what is welded to it. */
static void test_load_free_massless_root(void **state)
{
    static const char doc[] = ROBOT(
        "<link name='base_footprint'/>"
        LINK("base") LINK("arm")
        JOINT("footprint_to_base", "fixed", "base_footprint", "base", "<origin xyz='0 0 0.3'/>")
        JOINT("shoulder", "continuous", "base", "arm", ""));
    aqs_linkage *L;
    int32_t type, parent, child, nb;
    const char *name;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    L = load(doc, AQS_URDF_ROOT_FREE, 0, AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(nb, 3);
    assert_int_equal(aqs_joint_get_definition(L, 0, &type, &parent, &child, NULL, NULL, NULL), AQS_OK);
    assert_true(type == AQS_JOINT_FREE && parent == AQS_WORLD && child == 0);
    assert_int_equal(aqs_joint_get_name(L, 0, &name), AQS_OK);
    assert_string_equal(name, "world_to_base_footprint");
    aqs_linkage_destroy(L);
    /* root = fixed: the massless root is the world */
    L = load(doc, AQS_URDF_ROOT_FIXED, 0, AQS_OK);
    assert_int_equal(aqs_linkage_get_sizes(L, &nb, NULL, NULL, NULL), AQS_OK);
    assert_int_equal(nb, 2);
    assert_int_equal(aqs_joint_get_definition(L, 0, &type, &parent, NULL, NULL, NULL, NULL), AQS_OK);
    assert_true(type == AQS_JOINT_FIXED && parent == AQS_WORLD);
    aqs_linkage_destroy(L);
}

/* Every allocation of a load can fail: ENOMEM, nothing leaked, linkage empty. */
static void test_load_oom(void **state)
{
    long k, total;
    aqs_urdf_options o;
    (void)state;
    if (!aqs_urdf_supported()) skip();
    aqs_urdf_options_init(&o);
    o.collision = 1;
    {
        counting_state cs = {0};
        aqs_linkage *L;
        assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
        total = cs.count;
        assert_int_equal(aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, &o), AQS_OK);
        total = cs.count - total;
        aqs_linkage_destroy(L);
        assert_int_equal(cs.live, 0);
    }
    for (k = 1; k <= total; k++) {
        counting_state cs = {0};
        aqs_linkage *L;
        aqs_status st;
        int32_t nb = -1;
        assert_int_equal(aqs_linkage_create_with_allocator(counting_alloc, counting_free, &cs, &L), AQS_OK);
        cs.fail_at = cs.count + k;
        st = aqs_linkage_load_urdf_buffer(L, cad_arm, strlen(cad_arm), NULL, &o);
        assert_int_equal(st, AQS_ENOMEM);
        assert_int_equal(aqs_linkage_get_sizes(L, &nb, NULL, NULL, NULL), AQS_OK);
        assert_int_equal(nb, 0);
        aqs_linkage_destroy(L);
        assert_int_equal(cs.live, 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names),
        cmocka_unit_test(test_names_oom),
        cmocka_unit_test(test_limits),
        cmocka_unit_test(test_load_cad_arm),
        cmocka_unit_test(test_load_solves_like_the_file),
        cmocka_unit_test(test_collision_placement),
        cmocka_unit_test(test_load_errors),
        cmocka_unit_test(test_load_arguments),
        cmocka_unit_test(test_load_free_massless_root),
        cmocka_unit_test(test_load_oom),
    };
    return cmocka_run_group_tests_name("urdf", tests, NULL, NULL);
}
