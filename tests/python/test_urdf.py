"""URDF in and out (aqs.load_urdf, aqs.save_urdf) and the model read-back
(Linkage.body_inertial, Linkage.joint_definition) they are built on.

- read-back: the values given to add_body / add_joint, normalized as
  documented, in every phase; errors name the index.
- round trip: a linkage with every URDF-expressible joint type (revolute,
  prismatic, fixed, free, planar), a massless welded body and rotated joint
  frames is saved, loaded and saved again: same structure and names, numbers
  equal to a few ulp (the rpy angles are recomputed from the stored
  quaternion, which was normalized on input), and the exact solve under the
  same loads equal to the original's within 1e-12 relative.
- a URDF written by hand the way CAD exporters write them (a massive root
  link and no world link, massless frame links welded by fixed joints,
  inertial frames that are offset and rotated, visual/collision/limit/
  transmission elements to ignore), checked against the mass matrix and
  gravity torques of the planar arm it describes, computed here from the
  centre-of-mass Jacobians (not aqs's spatial algebra).
- every error case of the loader and of the writer.
- what real users load: point masses welded to massive links, unphysical
  link inertias (warned), root="free" on a massless root, limits kept (and
  not enforced), names backed by the C API, warnings for what is not
  modelled; four real robots (tests/data/urdf) against their own files:
  masses, inertias, names, limits, and gravity torques computed here from
  the file's frames, which must hold every joint at rest (1e-9 relative).
- the writer loads what it writes: equal names and names equal to a
  placeholder made distinct (one warning), names XML cannot carry refused,
  collision shapes reported as not written, infinite effort and velocity
  loading back infinite, axes within the documented 3.3e-16.
"""


import math
import warnings
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import aqs
from aqs import urdf as aqs_urdf


# ---------------------------------------------------------------------------
# Read-back
# ---------------------------------------------------------------------------

def test_body_inertial_and_joint_definition_read_back():
    with aqs.Linkage() as L:
        inertia = np.array([[0.3, 0.01, -0.02], [0.01, 0.25, 0.0], [-0.02, 0.0, 0.2]])
        b0 = L.add_body(2.5, (0.1, -0.2, 0.3), inertia)
        b1 = L.add_body(0.0, (0.0, 0.0, 0.0), np.zeros((3, 3)))
        quat = np.array([0.8, 0.0, 0.6, 0.0]) * (1 + 3e-7)
        L.add_joint("revolute", aqs.WORLD, b0, pos=(1, 2, 3), quat=quat, axis=(0, 3, 4))
        L.add_joint("fixed", b0, b1, pos=(0.5, 0, 0))
        for phase in ("building", "finalized"):
            mass, com, I = L.body_inertial(b0)
            assert mass == 2.5 and list(com) == [0.1, -0.2, 0.3]
            assert np.array_equal(I, inertia)
            d = L.joint_definition(0)
            assert (d.kind, d.parent, d.child) == ("revolute", aqs.WORLD, b0)
            assert list(d.pos) == [1, 2, 3]
            assert np.allclose(d.quat, [0.8, 0, 0.6, 0], rtol=0, atol=2.3e-16)
            assert np.allclose(d.axis, [0, 0.6, 0.8], rtol=0, atol=2.3e-16)
            d = L.joint_definition(1)
            assert (d.kind, d.parent, d.child) == ("fixed", b0, b1)
            assert list(d.axis) == [0, 0, 1]  # ignored by fixed joints: documented value
            if phase == "building":
                L.finalize()
        with pytest.raises(aqs.RangeError, match=r"aqs_body_get_inertial: body = 2 "):
            L.body_inertial(2)
        with pytest.raises(aqs.RangeError, match=r"aqs_joint_get_definition: joint = -1 "):
            L.joint_definition(-1)


# ---------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------

def random_rotation(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def random_inertia(rng, mass):
    """A physical inertia: principal moments of a box, turned at random."""
    sides = rng.uniform(0.1, 1.0, size=3)
    moments = mass / 12.0 * np.array([sides[1] ** 2 + sides[2] ** 2,
                                      sides[0] ** 2 + sides[2] ** 2,
                                      sides[0] ** 2 + sides[1] ** 2])
    r = aqs_urdf._quat_matrix(random_rotation(rng))
    return r @ np.diag(moments) @ r.T


def build_mixed(rng):
    """A floating base, a fixed-base branch, every URDF-expressible type,
    a massless body welded to a massive one, random frames and axes."""
    L = aqs.Linkage()
    masses = [3.0, 1.0, 1.5, 0.0, 0.7, 1.2, 0.9, 2.0, 1.1]
    for m in masses:
        L.add_body(m, rng.normal(size=3) * 0.3, random_inertia(rng, m) if m else np.zeros(9))
    plan = [("free", aqs.WORLD, 0), ("revolute", 0, 1), ("prismatic", 1, 2), ("fixed", 2, 3),
            ("revolute", 3, 4), ("planar", 4, 5), ("revolute", aqs.WORLD, 6),
            ("fixed", 6, 7), ("prismatic", 7, 8)]
    for kind, parent, child in plan:
        L.add_joint(kind, parent, child, pos=rng.normal(size=3), quat=random_rotation(rng),
                    axis=rng.normal(size=3))
    L.finalize()
    return L


def apply_loads(L, rng):
    L.set_gravity((0.3, -9.81, 0.4))
    for b in range(L.num_bodies):
        L.set_body_force(b, rng.normal(size=3), point=rng.normal(size=3),
                         torque=rng.normal(size=3) * 0.2)
    for j in range(L.num_joints):
        n = L.joint_layout(j).nv
        if n:
            L.set_joint_force(j, rng.normal(size=n) * 0.5)


def same_loads_solve(a, b, seed=7):
    apply_loads(a, np.random.default_rng(seed))
    apply_loads(b, np.random.default_rng(seed))
    a.solve()
    b.solve()
    return a.accelerations(), b.accelerations()


def numbers_of(path):
    """The file as [(tag, attribute, value text)] in document order, and the
    numbers of every numeric attribute in the same order."""
    structure, numbers = [], []
    for element in ET.parse(str(path)).getroot().iter():
        for key, value in element.attrib.items():
            try:
                values = [float(v) for v in value.split()]
            except ValueError:
                values = None
            if values:
                structure.append((element.tag, key, len(values)))
                numbers.extend(values)
            else:
                structure.append((element.tag, key, value))
    return structure, np.array(numbers)


def assert_same_urdf(path_a, path_b, ulps):
    sa, na = numbers_of(path_a)
    sb, nb = numbers_of(path_b)
    assert sa == sb
    assert na.shape == nb.shape
    bound = ulps * np.finfo(float).eps * np.maximum(1.0, np.abs(na))
    worst = np.max(np.abs(na - nb) - bound) if na.size else -1
    assert worst <= 0, "numbers differ by more than %d ulp" % ulps


# ---------------------------------------------------------------------------
# Round trip
# ---------------------------------------------------------------------------

def test_save_load_save_round_trip(tmp_path):
    rng = np.random.default_rng(2024)
    original = build_mixed(rng)
    first, second = tmp_path / "first.urdf", tmp_path / "second.urdf"
    aqs.save_urdf(original, first)
    loaded = aqs.load_urdf(first)
    loaded.save_urdf(second)
    # Names, types, topology and every number; numbers to 4 ulp: the rpy angles
    # are recomputed from a quaternion renormalized by the library.
    assert_same_urdf(first, second, ulps=4)
    with open(first) as a, open(second) as b:
        lines_a, lines_b = a.read().splitlines(), b.read().splitlines()
    assert len(lines_a) == len(lines_b)
    assert loaded.sizes() == original.sizes()
    assert loaded.body_names == ["link_%d" % i for i in range(9)]
    for j in range(original.num_joints):
        d0, d1 = original.joint_definition(j), loaded.joint_definition(j)
        assert (d0.kind, d0.parent, d0.child) == (d1.kind, d1.parent, d1.child)
        assert np.array_equal(d0.pos, d1.pos)
        assert np.allclose(d0.quat * np.sign(d0.quat[0]), d1.quat * np.sign(d1.quat[0]),
                           rtol=0, atol=1e-15)
    for b in range(original.num_bodies):
        i0, i1 = original.body_inertial(b), loaded.body_inertial(b)
        assert i0.mass == i1.mass and np.array_equal(i0.com, i1.com)
        assert np.array_equal(i0.inertia, i1.inertia)
    # The exact solve under the same loads. The models differ by a few ulp in
    # the joint rotations (rpy round trip); on 9 bodies the accelerations then
    # agree to ~1e-15, and 1e-12 leaves room for the conditioning of the
    # mass matrix of random geometry.
    qa, qb = same_loads_solve(original, loaded)
    assert np.linalg.norm(qa - qb) <= 1e-12 * np.linalg.norm(qa)
    assert np.linalg.norm(qa) > 1.0  # the loads do something
    original.close()
    loaded.close()


def test_names_survive_load_save(tmp_path):
    path = tmp_path / "named.urdf"
    path.write_text("""<robot name="r">
      <link name="world"/>
      <link name="upper &amp; arm"><inertial><mass value="1"/>
        <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
      <joint name="shoulder" type="continuous"><parent link="world"/>
        <child link="upper &amp; arm"/><axis xyz="0 0 1"/></joint>
    </robot>""")
    L = aqs.load_urdf(path)
    assert L.body_names == ["upper & arm"] and L.joint_names == ["shoulder"]
    L.save_urdf(tmp_path / "again.urdf")
    again = aqs.load_urdf(tmp_path / "again.urdf")
    assert again.body_names == ["upper & arm"] and again.joint_names == ["shoulder"]


def test_rpy_conventions():
    """rpy is R = Rz(yaw) Ry(pitch) Rx(roll) (URDF), checked on the three
    elementary rotations and on a product built from explicit matrices."""
    def rx(a):
        return np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])

    def ry(a):
        return np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])

    def rz(a):
        return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])

    rng = np.random.default_rng(5)
    for _ in range(200):
        rpy = rng.uniform(-math.pi, math.pi, size=3)
        rpy[1] = rng.uniform(-math.pi / 2, math.pi / 2)
        expected = rz(rpy[2]) @ ry(rpy[1]) @ rx(rpy[0])
        q = aqs_urdf.rpy_to_quat(rpy)
        assert abs(np.linalg.norm(q) - 1) < 1e-15
        assert np.allclose(aqs_urdf._quat_matrix(q), expected, rtol=0, atol=1e-15)
        assert np.allclose(aqs_urdf.rpy_to_matrix(rpy), expected, rtol=0, atol=1e-15)
        back = aqs_urdf.quat_to_rpy(q)
        assert np.allclose(aqs_urdf.rpy_to_matrix(back), expected, rtol=0, atol=4e-15)
    # quaternion -> rpy -> quaternion to a few ulp (up to the sign of q), for
    # random rotations and next to the gimbal lock (pitch = +-90 degrees),
    # where reading rpy off the rotation matrix would lose half the digits.
    quats = [random_rotation(rng) for _ in range(2000)]
    for pitch in (math.pi / 2, -math.pi / 2, math.pi / 2 - 1e-9, -math.pi / 2 + 1e-12):
        quats.append(aqs_urdf.rpy_to_quat((-0.4, pitch, 0.7)))
    for q in quats:
        rpy = aqs_urdf.quat_to_rpy(q)
        assert -math.pi / 2 <= rpy[1] <= math.pi / 2
        assert abs(rpy[0]) <= math.pi and abs(rpy[2]) <= math.pi
        again = aqs_urdf.rpy_to_quat(rpy)
        assert min(np.abs(again - q).max(), np.abs(again + q).max()) <= 1.2e-15


# ---------------------------------------------------------------------------
# A URDF as a CAD exporter writes it
# ---------------------------------------------------------------------------

CAD_URDF = """<?xml version="1.0" encoding="utf-8"?>
<!-- Exported from a CAD assembly: meshes, materials, limits, transmissions. -->
<robot name="cad_arm">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="base_link">
    <inertial>
      <origin xyz="0 0 0.05" rpy="0 0 0"/>
      <mass value="5.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/>
    </inertial>
    <visual><geometry><mesh filename="package://cad_arm/meshes/base.stl"/></geometry>
      <material name="grey"/></visual>
    <collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <link name="shoulder_frame"/>
  <link name="upper_arm">
    <inertial>
      <origin xyz="0.45 0.02 0" rpy="0.3 -0.2 0.5"/>
      <mass value="2.0"/>
      <inertia ixx="0.004" ixy="0.0001" ixz="0" iyy="0.17" iyz="0" izz="0.168"/>
    </inertial>
    <visual><geometry><mesh filename="package://cad_arm/meshes/upper.dae" scale="0.001 0.001 0.001"/></geometry></visual>
  </link>
  <link name="elbow_flange">
    <inertial>
      <origin xyz="0 0 0" rpy="0 0 0"/>
      <mass value="0"/>
      <inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/>
    </inertial>
  </link>
  <link name="forearm">
    <inertial>
      <origin xyz="0.35 0 0.01" rpy="1.1 0.4 -0.3"/>
      <mass value="1.2"/>
      <inertia ixx="0.002" ixy="0" ixz="0.0002" iyy="0.05" iyz="0" izz="0.049"/>
    </inertial>
  </link>
  <link name="tool0"/>
  <link name="gripper">
    <inertial>
      <origin xyz="0.05 0.01 0" rpy="0 0.7 0"/>
      <mass value="0.5"/>
      <inertia ixx="0.0004" ixy="0" ixz="0" iyy="0.0006" iyz="0" izz="0.0005"/>
    </inertial>
  </link>
  <joint name="base_to_shoulder_frame" type="fixed">
    <origin xyz="0 0 0.1" rpy="0 0 0.25"/>
    <parent link="base_link"/><child link="shoulder_frame"/>
  </joint>
  <joint name="shoulder" type="revolute">
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <parent link="shoulder_frame"/><child link="upper_arm"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3.14" upper="3.14" effort="150" velocity="3.15"/>
    <dynamics damping="0.5" friction="0.1"/>
  </joint>
  <joint name="upper_arm_to_elbow_flange" type="fixed">
    <origin xyz="0.9 0 0" rpy="0 0 0.4"/>
    <parent link="upper_arm"/><child link="elbow_flange"/>
  </joint>
  <joint name="elbow" type="continuous">
    <origin xyz="0 0 0" rpy="0 0 0"/>
    <parent link="elbow_flange"/><child link="forearm"/>
    <axis xyz="0 0 1"/>
  </joint>
  <joint name="forearm_to_tool0" type="fixed">
    <origin xyz="0.7 0 0" rpy="0 0 -0.6"/>
    <parent link="forearm"/><child link="tool0"/>
  </joint>
  <joint name="tool0_to_gripper" type="fixed">
    <origin xyz="0.02 0 0" rpy="0 0 0"/>
    <parent link="tool0"/><child link="gripper"/>
  </joint>
  <transmission name="shoulder_trans"><type>transmission_interface/SimpleTransmission</type>
    <joint name="shoulder"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>
  </transmission>
  <gazebo reference="forearm"><material>Gazebo/Grey</material></gazebo>
</robot>
"""


def _rz(a):
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def _rpy(r, p, y):
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    return _rz(y) @ ry @ rx


def cad_arm_reference(gravity, tau):
    """qdd of the CAD arm at q = 0 with zero velocity: M qdd = tau + G.

    Both joints turn about the world z axis (every frame above them is turned
    about z only), so the motion is planar: with p_k the world centre of mass
    of rigid body k and r_i the point on joint i's axis,
    M_ij = sum_k [m_k (z x (p_k - r_i)) . (z x (p_k - r_j)) + Izz_k] over the
    bodies k moved by both joints, Izz_k the world zz inertia about the com,
    and G_i = sum_k m_k g . (z x (p_k - r_i)).
    """
    z = np.array([0.0, 0.0, 1.0])
    # World frames at q = 0 (base_link at the world origin, welded).
    base_r, base_p = np.eye(3), np.zeros(3)
    shoulder_r = base_r @ _rz(0.25)
    shoulder_p = base_p + base_r @ np.array([0, 0, 0.1])
    upper_r, upper_p = shoulder_r, shoulder_p
    elbow_r = upper_r @ _rz(0.4)
    elbow_p = upper_p + upper_r @ np.array([0.9, 0, 0])
    fore_r, fore_p = elbow_r, elbow_p
    tool_r = fore_r @ _rz(-0.6)
    tool_p = fore_p + fore_r @ np.array([0.7, 0, 0])
    grip_r, grip_p = tool_r, tool_p + tool_r @ np.array([0.02, 0, 0])

    def body(mass, frame_r, frame_p, xyz, rpy, diag_and_off):
        ixx, ixy, ixz, iyy, iyz, izz = diag_and_off
        local = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        r = frame_r @ _rpy(*rpy)
        return mass, frame_p + frame_r @ np.array(xyz), (r @ local @ r.T)[2, 2]

    upper = body(2.0, upper_r, upper_p, (0.45, 0.02, 0), (0.3, -0.2, 0.5),
                 (0.004, 0.0001, 0, 0.17, 0, 0.168))
    fore = body(1.2, fore_r, fore_p, (0.35, 0, 0.01), (1.1, 0.4, -0.3),
                (0.002, 0, 0.0002, 0.05, 0, 0.049))
    grip = body(0.5, grip_r, grip_p, (0.05, 0.01, 0), (0, 0.7, 0),
                (0.0004, 0, 0, 0.0006, 0, 0.0005))
    moved = [[upper, fore, grip], [fore, grip]]  # by the shoulder, by the elbow
    axes_at = [shoulder_p, elbow_p]
    M = np.zeros((2, 2))
    G = np.zeros(2)
    for i in range(2):
        for k in moved[i]:
            mass, p, izz = k
            vi = np.cross(z, p - axes_at[i])
            G[i] += mass * np.dot(gravity, vi)
            for j in range(2):
                if k in moved[j]:
                    vj = np.cross(z, p - axes_at[j])
                    M[i, j] += mass * np.dot(vi, vj) + izz
    return np.linalg.solve(M, np.asarray(tau) + G)


@pytest.mark.filterwarnings("ignore::aqs.URDFWarning")
def test_cad_style_urdf_against_planar_arm(tmp_path):
    path = tmp_path / "cad_arm.urdf"
    path.write_text(CAD_URDF)
    L = aqs.load_urdf(path)
    # base_link has mass: it is welded to the world by joint 0 "world_to_base_link".
    assert L.joint_names == ["world_to_base_link", "base_to_shoulder_frame", "shoulder",
                             "upper_arm_to_elbow_flange", "elbow", "forearm_to_tool0",
                             "tool0_to_gripper"]
    assert L.body_names == ["base_link", "shoulder_frame", "upper_arm", "elbow_flange",
                            "forearm", "tool0", "gripper"]
    assert L.sizes() == aqs.Sizes(7, 7, 2, 2)
    assert L.joint_definition(0).kind == "fixed"
    # The massless links are bodies of mass 0 welded to massive ones.
    assert L.body_inertial(1).mass == 0 and L.body_inertial(5).mass == 0
    shoulder, elbow = 2, 4
    for gravity, tau in (((0.0, -9.81, 0.0), (0.0, 0.0)), ((1.0, 2.0, -9.81), (3.0, -1.5)),
                         ((0.0, 0.0, 0.0), (1.0, 0.0))):
        L.set_gravity(gravity)
        L.set_joint_force(shoulder, [tau[0]])
        L.set_joint_force(elbow, [tau[1]])
        L.solve()
        got = L.accelerations()
        expected = cad_arm_reference(np.array(gravity), tau)
        # Two independent double-precision computations of a 2x2 system with
        # condition number ~1e2: agreement to 1e-12 relative.
        assert np.linalg.norm(got - expected) <= 1e-12 * np.linalg.norm(expected), (got, expected)
        assert np.linalg.norm(expected) > 0.1
    # The same file with the root floating: base_link gets a free joint.
    free = aqs.load_urdf(path, root="free")
    assert free.joint_definition(0).kind == "free" and free.nv == 8
    L.close()
    free.close()


# ---------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------

LINK = """<link name="%s"><inertial><mass value="1"/>
  <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>"""


def joint(name, parent, child, kind="continuous", extra=""):
    return ('<joint name="%s" type="%s"><parent link="%s"/><child link="%s"/>%s</joint>'
            % (name, kind, parent, child, extra))


def robot(*parts):
    return "<robot name='bad'>%s</robot>" % "".join(parts)


ERROR_CASES = {
    "cycle": (robot(LINK % "a", LINK % "b", LINK % "c", joint("ab", "a", "b"),
                    joint("bc", "b", "c"), joint("ca", "c", "a")),
              r"cycle: every link has a parent \('a' <- 'c' <- 'b' <- 'a'\)"),
    "detached cycle": (robot('<link name="world"/>', LINK % "a", LINK % "b", LINK % "c",
                             joint("wa", "world", "a"), joint("bc", "b", "c"),
                             joint("cb", "c", "b")),
                       r"cycle not connected to the root link 'world'"),
    "several roots": (robot('<link name="world"/>', LINK % "a", LINK % "b",
                            joint("wa", "world", "a")),
                      r"several root links .*'world', 'b'"),
    "missing child link": (robot('<link name="world"/>', joint("wa", "world", "ghost")),
                           r"joint 'wa': child link 'ghost' is not defined"),
    "missing parent link": (robot(LINK % "a", joint("xa", "ghost", "a")),
                            r"joint 'xa': parent link 'ghost' is not defined"),
    "missing inertia": (robot('<link name="world"/>',
                              '<link name="a"><inertial><mass value="2"/></inertial></link>',
                              joint("wa", "world", "a")),
                        r"link 'a': <inertial> has mass 2 but no <inertia>"),
    "missing mass": (robot('<link name="world"/>',
                           '<link name="a"><inertial><inertia ixx="1" ixy="0" ixz="0" '
                           'iyy="1" iyz="0" izz="1"/></inertial></link>',
                           joint("wa", "world", "a")),
                     r"link 'a': <inertial> has no <mass>"),
    "negative mass": (robot('<link name="world"/>',
                            (LINK % "a").replace('value="1"', 'value="-1"'),
                            joint("wa", "world", "a")),
                      r"link 'a': mass = -1 is negative"),
    "non-positive inertia": (robot('<link name="world"/>',
                                   (LINK % "a").replace('ixx="0.1"', 'ixx="-0.1"'),
                                   joint("wa", "world", "a")),
                             r"aqs_linkage_finalize: body 0 'a' \(welded to no other body\) "
                             r"has a singular inertia"),
    "zero inertia": (robot('<link name="world"/>',
                           (LINK % "a").replace('0.1', '0'), joint("wa", "world", "a")),
                     r"body 0 'a' \(welded to no other body\) has a singular inertia "
                     r"\(total mass 1\)"),
    "massless moving link": (robot('<link name="world"/>', '<link name="a"/>', LINK % "b",
                                   joint("wa", "world", "a"), joint("ab", "a", "b")),
                             r"link 'a' has no mass \(no <inertial>\) and is not welded .*"
                             r"rigid group: 'a'"),
    "massless welded group": (robot('<link name="world"/>', '<link name="a"/>',
                                    '<link name="b"/>', joint("wa", "world", "a"),
                                    joint("ab", "a", "b", kind="fixed")),
                              r"link 'a' has no mass .* rigid group: 'a', 'b'"),
    "unsupported type": (robot('<link name="world"/>', LINK % "a",
                               joint("wa", "world", "a", kind="spherical")),
                         r"joint 'wa': type = 'spherical' is not supported \(aqs loads "
                         r"continuous, fixed, floating, planar, prismatic, revolute\)"),
    "floating from a body": (robot('<link name="world"/>', LINK % "a", LINK % "b",
                                   joint("wa", "world", "a"),
                                   joint("ab", "a", "b", kind="floating")),
                             r"joint 'ab': a floating joint must hang from the massless root"),
    "two parents": (robot('<link name="world"/>', LINK % "a", LINK % "b",
                          joint("wa", "world", "a"), joint("wb", "world", "b"),
                          joint("ab", "a", "b")),
                    r"link 'b' is the child of two joints \('wb' and 'ab'\)"),
    "bad number": (robot('<link name="world"/>', LINK % "a",
                         joint("wa", "world", "a", extra='<origin xyz="1 two 3"/>')),
                   r"joint 'wa' <origin>: xyz = '1 two 3' is not 3 numbers"),
    "non-finite number": (robot('<link name="world"/>', LINK % "a",
                                joint("wa", "world", "a", extra='<axis xyz="0 nan 1"/>')),
                          r"joint 'wa' <axis>: xyz = '0 nan 1' is not finite"),
    "zero axis": (robot('<link name="world"/>', LINK % "a",
                        joint("wa", "world", "a", extra='<axis xyz="0 0 0"/>')),
                  r"joint 'wa': <axis xyz> is zero"),
    "unknown encoding": ('<?xml version="1.0" encoding="klingon-8"?><robot/>',
                         r"not well-formed XML \(unknown encoding\) at line 1"),
    "hex number": (robot('<link name="world"/>', LINK % "a",
                         joint("wa", "world", "a", extra='<origin xyz="0x1 0 0"/>')),
                   r"joint 'wa' <origin>: xyz = '0x1 0 0' is not 3 numbers"),
    "limits": (robot('<link name="world"/>', LINK % "a",
                     joint("wa", "world", "a", kind="prismatic",
                           extra='<limit lower="0.2" upper="-0.2" effort="1" velocity="1"/>')),
               r"joint 'wa' <limit>: lower = 0.2 is above upper = -0.2"),
    "unknown geometry values": (robot('<link name="world"/>',
                                      (LINK % "a").replace(
                                          "</link>", '<collision><geometry><cylinder radius="0.1"/>'
                                          '</geometry></collision></link>'),
                                      joint("wa", "world", "a")),
                                r"link 'a' <collision> <cylinder>: missing attribute length"),
    "duplicate link": (robot(LINK % "a", LINK % "a"), r"link 'a' is defined twice"),
    "not a robot": ("<model/>", r"the root element is <model>, not <robot>"),
    "not xml": ("<robot>", r"not well-formed XML"),
}


@pytest.mark.filterwarnings("ignore::aqs.URDFWarning")
@pytest.mark.parametrize("case", sorted(ERROR_CASES))
def test_load_errors(tmp_path, case):
    text, pattern = ERROR_CASES[case]
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(aqs.URDFError, match=pattern) as info:
        aqs.load_urdf(path, collision=True)
    assert str(info.value).startswith(str(path) + ": ")


def test_load_error_missing_file(tmp_path):
    with pytest.raises(aqs.URDFError, match="cannot read"):
        aqs.load_urdf(tmp_path / "nowhere.urdf")
    with pytest.raises(aqs.URDFError, match=r"root = 'bolted' must be 'fixed' or 'free'"):
        aqs.load_urdf(tmp_path / "nowhere.urdf", root="bolted")


@pytest.mark.parametrize("kind", ["spherical", "universal", "cylindrical"])
def test_save_refuses_joints_urdf_lacks(tmp_path, kind):
    with aqs.Linkage() as L:
        L.add_body(1.0, (0, 0, 0), np.eye(3) * 0.1)
        L.add_joint(kind, aqs.WORLD, 0)
        with pytest.raises(aqs.URDFError, match=r"joint 0 \('joint_0'\) is %s, which URDF "
                                                 r"cannot express" % kind):
            L.save_urdf(tmp_path / "x.urdf")


# ---------------------------------------------------------------------------
# What real users load (issue 15, item 6)
# ---------------------------------------------------------------------------

def _load_text(tmp_path, text, **options):
    path = tmp_path / "robot.urdf"
    path.write_text(text)
    return aqs.load_urdf(path, **options)


POINT_MASS = ('<link name="tip"><inertial><origin xyz="0.1 0.05 0"/><mass value="0.01"/>'
              '<inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial></link>')


def test_point_mass_welded_to_a_massive_link_loads(tmp_path):
    welded = robot('<link name="world"/>', LINK % "a", POINT_MASS,
                   joint("wa", "world", "a"), joint("w", "a", "tip", kind="fixed"))
    with _load_text(tmp_path, welded) as L:
        assert L.body_names == ["a", "tip"]
        assert L.body_inertial(1).mass == 0.01
    # The same point mass moving alone: its rigid group has no inertia.
    alone = robot('<link name="world"/>', LINK % "a", POINT_MASS,
                  joint("wa", "world", "a"), joint("w", "a", "tip"))
    with pytest.raises(aqs.URDFError, match=r"body 1 'tip' \(welded to no other body\) has a "
                                            r"singular inertia \(total mass 0.01\)"):
        _load_text(tmp_path, alone)


def test_add_body_point_mass_as_massless(tmp_path):
    # One rule at add_body for mass 0 and 0.01 with zero inertia; finalize
    # judges the rigid group.
    for mass in (0.0, 0.01):
        with aqs.Linkage() as L:
            L.add_body(1.0, (0, 0, 0), np.eye(3) * 0.1)
            L.add_body(mass, (0.2, 0, 0), np.zeros((3, 3)))
            L.add_joint("revolute", aqs.WORLD, 0)
            L.add_joint("fixed", 0, 1)
            L.finalize()


def test_unphysical_inertia_warns_or_refuses(tmp_path):
    text = robot('<link name="world"/>', (LINK % "a").replace('izz="0.1"', 'izz="0.5"'),
                 joint("wa", "world", "a"))
    with pytest.warns(aqs.URDFWarning, match=r"violating the triangle inequality.*links 'a'"):
        L = _load_text(tmp_path, text)
    assert L.body_inertial(0).inertia[2, 2] == 0.5
    L.close()
    with pytest.raises(aqs.URDFError, match=r"link 'a': aqs_body_add: principal moments .* "
                                            r"triangle"):
        _load_text(tmp_path, text, physical_inertia=True)


def test_free_root(tmp_path):
    # A massless root with a massive link welded to it floats with it.
    text = robot('<link name="base_footprint"/>', LINK % "base", LINK % "arm",
                 joint("fb", "base_footprint", "base", kind="fixed",
                       extra='<origin xyz="0 0 0.3"/>'),
                 joint("shoulder", "base", "arm"))
    with _load_text(tmp_path, text, root="free") as L:
        d = L.joint_definition(0)
        assert (d.kind, d.parent, d.child) == ("free", aqs.WORLD, 0)
        assert L.joint_names[0] == "world_to_base_footprint"
        assert L.nv == 7
    with _load_text(tmp_path, text) as L:
        assert L.nv == 1 and L.body_names == ["base", "arm"]
    # A massless root with nothing welded to float: refused, never a fixed base.
    text = robot('<link name="world"/>', LINK % "a", joint("wa", "world", "a"))
    with pytest.raises(aqs.URDFError, match=r"root = free, but the root link 'world' has no "
                                            r"mass .* no rigid body to float"):
        _load_text(tmp_path, text, root="free")
    # ... unless it already floats.
    text = robot('<link name="world"/>', LINK % "a", joint("wa", "world", "a", kind="floating"))
    with _load_text(tmp_path, text, root="free") as L:
        assert L.joint_definition(0).kind == "free"


def test_limits_kept_and_not_enforced(tmp_path):
    text = robot('<link name="world"/>', LINK % "a", LINK % "b",
                 joint("slide", "world", "a", kind="prismatic",
                       extra='<axis xyz="1 0 0"/><limit lower="-0.2" upper="0.2" effort="30" '
                             'velocity="0.5"/>'),
                 joint("turn", "a", "b"))
    with _load_text(tmp_path, text) as L:
        assert L.joint_limits(0) == aqs.JointLimits(-0.2, 0.2, 30.0, 0.5)
        assert L.joint_limits(1) == aqs.JointLimits(-math.inf, math.inf, math.inf, math.inf)
        assert L.find_joint("turn") == 1 and L.find_body("b") == 1
        with pytest.raises(aqs.RangeError, match=r"no joint is named 'nope'"):
            L.find_joint("nope")
        # Quasi-statics does not enforce limits (documented): a steady push
        # slides the joint past its upper limit.
        L.set_body_force(0, (10.0, 0, 0))
        for _ in range(20):
            L.step(0.1)
        assert L.positions()[0] > 0.2
        # save_urdf writes the limits back.
        L.save_urdf(tmp_path / "copy.urdf")
    with aqs.load_urdf(tmp_path / "copy.urdf") as again:
        assert again.joint_limits(0) == aqs.JointLimits(-0.2, 0.2, 30.0, 0.5)
        assert again.joint_names == ["slide", "turn"]


def test_names_in_python():
    with aqs.Linkage() as L:
        L.add_body(1.0, (0, 0, 0), np.eye(3) * 0.1)
        L.add_joint("revolute", aqs.WORLD, 0)
        assert L.body_names == [""] and L.joint_names == [""]
        L.body_names = ["wheel"]
        L.set_joint_name(0, "axle\u00e9")
        assert L.body_name(0) == "wheel" and L.joint_names == ["axle\u00e9"]
        assert L.find_joint("axle\u00e9") == 0
        with pytest.raises(aqs.SizeError):
            L.body_names = ["a", "b"]
        with pytest.raises(aqs.InvalidArgument, match="name is empty"):
            L.set_body_name(0, "")
        with pytest.raises(TypeError, match="name must be a str"):
            L.set_body_name(0, 3)
        with pytest.raises(TypeError, match="lower must be a real number"):
            L.set_joint_limits(0, lower="0")
        with pytest.raises(TypeError, match="collision"):
            aqs.load_urdf("x.urdf", collision="yes")
        L.set_joint_limits(0, -1, 1)
        assert L.joint_limits(0) == (-1.0, 1.0, math.inf, math.inf)


def test_warnings_list_what_is_not_modelled(tmp_path):
    path = tmp_path / "cad_arm.urdf"
    path.write_text(CAD_URDF.replace('<axis xyz="0 0 1"/>\n  </joint>',
                                     '<axis xyz="0 0 1"/><mimic joint="shoulder"/>\n  </joint>'))
    with pytest.warns(aqs.URDFWarning) as record:
        L = aqs.load_urdf(path)
    texts = [str(w.message) for w in record]
    assert any("<mimic> is not modelled" in t and "'elbow'" in t for t in texts)
    assert any("<transmission> is not modelled: 'shoulder_trans' (1)" in t for t in texts)
    assert any("<gazebo>" in t and "'forearm'" in t for t in texts)
    assert all(t.startswith(str(path) + ": ") for t in texts)
    assert L.load_warnings == texts
    L.close()
    # Collision: the base_link box becomes a shape; the mesh is visual only.
    with aqs.load_urdf(path, collision=True) as L:
        assert L.shape_count == 1


# Real robots (tests/data/urdf, see its README for sources and licenses).
DATA = __import__("pathlib").Path(__file__).resolve().parents[1] / "data" / "urdf"


def _rpy_matrix(rpy):
    return _rpy(*rpy)


def _file_model(path):
    """The file read here with xml.etree, independently of the loader:
    links (mass, com, inertia in the link frame), joints, and the world pose
    of every link at q = 0 by composing the joints' origins."""
    root = ET.parse(str(path)).getroot()

    def vec(element, attr, default):
        if element is None or element.get(attr) is None:
            return np.array(default, dtype=float)
        return np.array([float(v) for v in element.get(attr).split()])

    links = {}
    for link in root.findall("link"):
        inertial = link.find("inertial")
        if inertial is None:
            links[link.get("name")] = (0.0, np.zeros(3), np.zeros((3, 3)))
            continue
        o = inertial.find("origin")
        xyz, rpy = vec(o, "xyz", [0, 0, 0]), vec(o, "rpy", [0, 0, 0])
        mass = float(inertial.find("mass").get("value"))
        e = inertial.find("inertia")
        k = {a: float(e.get(a)) for a in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        inertia = np.array([[k["ixx"], k["ixy"], k["ixz"]], [k["ixy"], k["iyy"], k["iyz"]],
                            [k["ixz"], k["iyz"], k["izz"]]])
        r = _rpy_matrix(rpy)
        links[link.get("name")] = (mass, xyz, r @ inertia @ r.T)
    joints = []
    for j in root.findall("joint"):
        o = j.find("origin")
        lim = j.find("limit")
        joints.append(dict(name=j.get("name"), type=j.get("type"),
                           parent=j.find("parent").get("link"),
                           child=j.find("child").get("link"),
                           xyz=vec(o, "xyz", [0, 0, 0]), rpy=vec(o, "rpy", [0, 0, 0]),
                           axis=vec(j.find("axis"), "xyz", [1, 0, 0]),
                           limit=None if lim is None else lim.attrib))
    return links, joints


def _world_frames(links, joints):
    parent_of = {j["child"]: j for j in joints}
    frames = {}

    def frame(name):
        if name not in frames:
            if name not in parent_of:
                frames[name] = (np.eye(3), np.zeros(3))
            else:
                j = parent_of[name]
                r, p = frame(j["parent"])
                frames[name] = (r @ _rpy_matrix(j["rpy"]), p + r @ j["xyz"])
        return frames[name]

    for name in links:
        frame(name)
    return frames


@pytest.mark.parametrize("name", ["ur5_robot", "panda", "go1", "solo12"])
def test_real_robot_against_the_file(name):
    path = DATA / (name + ".urdf")
    links, joints = _file_model(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", aqs.URDFWarning)
        L = aqs.load_urdf(path, collision=True)
    with L:
        names = L.body_names
        # Every link with mass is a body with the file's numbers.
        for link, (mass, com, inertia) in links.items():
            if link not in names:
                assert mass == 0.0  # the massless root, the world
                continue
            got = L.body_inertial(L.find_body(link))
            assert got.mass == mass and np.array_equal(got.com, com)
            assert np.allclose(got.inertia, inertia, rtol=0,
                               atol=1e-15 * max(1.0, np.abs(inertia).max()))
        # Joints in file order (after world_to_<root> when the root has mass).
        file_joints = [j["name"] for j in joints]
        assert L.joint_names[-len(file_joints):] == file_joints
        for j in joints:
            k = L.find_joint(j["name"])
            lim = L.joint_limits(k)
            if j["limit"] is not None and j["type"] in ("revolute", "prismatic"):
                assert lim.lower == float(j["limit"].get("lower", 0))
                assert lim.upper == float(j["limit"].get("upper", 0))
            if j["limit"] is not None and "effort" in j["limit"]:
                assert lim.effort == float(j["limit"]["effort"])
        # Gravity torques at q = 0 from the file (world frames composed
        # here): tau_i = a_i . sum_k (p_k - o_i) x m_k g over the links k
        # below moving joint i. Applying -tau must leave every joint at rest.
        frames = _world_frames(links, joints)
        children = {}
        for j in joints:
            children.setdefault(j["parent"], []).append(j["child"])

        def below(link):
            out = [link]
            for c in children.get(link, []):
                out += below(c)
            return out

        g = np.array([0.0, 0.0, -9.81])
        L.set_gravity(g)
        L.solve()
        free = L.accelerations().copy()
        moving = 0
        for j in joints:
            if j["type"] not in ("revolute", "continuous", "prismatic"):
                continue
            moving += 1
            r, o = frames[j["child"]]
            axis = r @ (j["axis"] / np.linalg.norm(j["axis"]))
            tau = 0.0
            for k in below(j["child"]):
                mass, com, _ = links[k]
                rk, pk = frames[k]
                force = mass * g
                if j["type"] == "prismatic":
                    tau += axis @ force
                else:
                    tau += axis @ np.cross(pk + rk @ com - o, force)
            L.set_joint_force(L.find_joint(j["name"]), [-tau])
        L.solve()
        held = L.accelerations()
        assert moving > 0 and np.linalg.norm(free) > 1.0
        # Fixed-base arms: exact equilibrium to rounding. The floating
        # quadrupeds are welded to the world too (root = fixed, the default).
        assert np.linalg.norm(held) <= 1e-9 * np.linalg.norm(free), (held, free)


def test_real_robot_root_free_floats():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", aqs.URDFWarning)
        with aqs.load_urdf(DATA / "go1.urdf", root="free") as L:
            # go1's root link 'base' has mass 1e-6 and a rank-one inertia,
            # welded to the trunk: the group floats.
            d = L.joint_definition(0)
            assert d.kind == "free" and L.joint_names[0] == "world_to_base"
            assert L.nv == 6 + 12


# ---------------------------------------------------------------------------
# The writer: every file it writes loads (found from outside, 2026-12-05)
# ---------------------------------------------------------------------------

def _chain(n=3, bodies=None, joints=None):
    """n bodies in a chain of revolute joints, named from the dicts
    {index: name} (the rest unnamed)."""
    L = aqs.Linkage()
    for i in range(n):
        L.add_body(1.0, (0, 0, 0.1), np.eye(3) * 0.01)
    for i in range(n):
        L.add_joint("revolute", i - 1, i, pos=(0, 0, 0.3), axis=(1, 0, 0))
    for i, s in (bodies or {}).items():
        L.set_body_name(i, s)
    for i, s in (joints or {}).items():
        L.set_joint_name(i, s)
    L.finalize()
    return L


def _save_with_warnings(L, path):
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        aqs.save_urdf(L, path)
    return [str(w.message) for w in record if issubclass(w.category, aqs.URDFWarning)]


# Each case: (body names, joint names) given, then the names loaded back and
# the number of names the warning counts.
NAME_CASES = {
    "duplicate bodies": (({0: "a", 1: "a"}, {}), (["a", "a__2", "link_2"], None), 1),
    "three of a kind, one already suffixed": (
        ({0: "a", 1: "a", 2: "a__2"}, {}), (["a", "a__3", "a__2"], None), 1),
    "placeholder of body 0 is body 2's name": (
        ({2: "link_0"}, {}), (["link_0__2", "link_1", "link_0"], None), 1),
    "placeholder of joint 0 is joint 2's name": (
        ({}, {2: "joint_0"}), (None, ["joint_0__2", "joint_1", "joint_0"]), 1),
    "duplicate joints": (({}, {0: "j", 1: "j", 2: "j"}), (None, ["j", "j__2", "j__3"]), 2),
    "a body and a joint may share a name": (({0: "x"}, {0: "x"}), (["x", "link_1", "link_2"],
                                                                 ["x", "joint_1", "joint_2"]), 0),
}


@pytest.mark.parametrize("case", sorted(NAME_CASES))
def test_save_makes_names_unique(tmp_path, case):
    (bodies, joints), (body_names, joint_names), renamed = NAME_CASES[case]
    path = tmp_path / "names.urdf"
    with _chain(bodies=bodies, joints=joints) as L:
        texts = _save_with_warnings(L, path)
        # The file loads (it was refused: "link 'a' is defined twice"), with
        # the same model in it.
        with aqs.load_urdf(path) as M:
            if body_names:
                assert M.body_names == body_names
            if joint_names:
                assert M.joint_names == joint_names
            assert M.sizes() == L.sizes()
    renames = [t for t in texts if "renamed" in t]
    if renamed:
        assert len(renames) == 1 and renames[0].startswith("save_urdf: %d names renamed"
                                                           % renamed), texts
    else:
        assert renames == []


def test_save_names_are_deterministic(tmp_path):
    with _chain(n=5, bodies={0: "a", 1: "a", 3: "link_4", 4: "a"}) as L:
        _save_with_warnings(L, tmp_path / "one.urdf")
        _save_with_warnings(L, tmp_path / "two.urdf")
    assert (tmp_path / "one.urdf").read_text() == (tmp_path / "two.urdf").read_text()
    with aqs.load_urdf(tmp_path / "one.urdf") as M:
        assert M.body_names == ["a", "a__2", "link_2", "link_4", "a__3"]


@pytest.mark.parametrize("what, char", [("body", "\x01"), ("joint", "\x1f"), ("body", "\x0b"),
                                        ("joint", "\ufffe")])
def test_save_refuses_names_xml_cannot_carry(tmp_path, what, char):
    names = {1: "a%sb" % char}
    path = tmp_path / "bad.urdf"
    with _chain(bodies=names if what == "body" else None,
                joints=names if what == "joint" else None) as L:
        # Was a file load_urdf refused ("not well-formed XML (invalid token)").
        with pytest.raises(aqs.URDFError, match=r"save_urdf: %s 1 name .* holds the character "
                                                 r"U\+%04X, which XML 1.0 cannot carry"
                                                 % (what, ord(char))):
            aqs.save_urdf(L, path)
    assert not path.exists()


def test_save_names_with_whitespace_and_specials_load_back(tmp_path):
    given = {0: "a\tb\nc", 1: "cr\rhere", 2: " a<&\"'>b "}
    with _chain(bodies=given) as L:
        assert _save_with_warnings(L, tmp_path / "ws.urdf") == []
    with aqs.load_urdf(tmp_path / "ws.urdf") as M:
        assert M.body_names == [given[0], given[1], given[2]]


def test_save_warns_collision_shapes_not_written(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", aqs.URDFWarning)
        L = aqs.load_urdf(DATA / "go1.urdf", collision=True)
    with L:
        assert L.shape_count == 38
        texts = _save_with_warnings(L, tmp_path / "go1.urdf")
    assert texts == ["save_urdf: 38 collision shapes are not written: save_urdf writes no "
                     "<collision>"]
    # Without shapes, nothing to say.
    with _chain() as L:
        assert _save_with_warnings(L, tmp_path / "chain.urdf") == []


def test_save_infinite_effort_and_velocity_load_back_unbounded(tmp_path):
    limits = [(-1.0, 2.0, 5.0, math.inf), (-1.0, 2.0, math.inf, 0.5),
              (-math.inf, math.inf, 3.0, math.inf), (-1.0, 2.0, math.inf, math.inf)]
    path = tmp_path / "limits.urdf"
    with _chain(n=len(limits)) as L:
        for j, lim in enumerate(limits):
            L.set_joint_limits(j, *lim)
        aqs.save_urdf(L, path)
    # An infinite effort or velocity is written 1e300, as unbounded positions
    # are (it was written 0 and loaded back as a limit of 0); every attribute
    # is there, as urdfdom's readers require.
    written = [j.find("limit").attrib for j in ET.parse(str(path)).getroot().findall("joint")]
    assert all(sorted(a) == ["effort", "lower", "upper", "velocity"] for a in written)
    def unbounded(v):
        return v if math.isfinite(v) else math.copysign(1e300, v)
    with aqs.load_urdf(path) as M:
        for j, lim in enumerate(limits):
            got = tuple(M.joint_limits(j))
            assert got[2:] == (unbounded(lim[2]), unbounded(lim[3])), (j, got)
            # positions: a revolute joint without them is written "continuous"
            # and keeps none (+-inf); else as given, +-1e300 when unbounded
            assert got[:2] in (lim[:2], (unbounded(lim[0]), unbounded(lim[1]))), (j, got)


def test_saved_axes_load_back_within_the_documented_bound(tmp_path):
    """docs/urdf.md: an axis comes back within 3.3e-16 per component (the
    loader normalizes the unit axis again, which can move it by an ulp or
    two); an axis along x, y or z comes back bit for bit."""
    rng = np.random.default_rng(3)
    n = 60
    with aqs.Linkage() as L:
        for i in range(n):
            L.add_body(1.0, (0, 0, 0.1), np.eye(3) * 0.01)
        axes = [rng.normal(size=3) for _ in range(n - 3)] + [(0, 0, 2), (0, -1, 0), (3, 0, 0)]
        for i in range(n):
            L.add_joint("revolute" if i % 2 else "prismatic", i - 1, i, axis=axes[i])
        L.finalize()
        L.save_urdf(tmp_path / "axes.urdf")
        with aqs.load_urdf(tmp_path / "axes.urdf") as M:
            got = np.array([M.joint_definition(j).axis for j in range(n)])
        given = np.array([L.joint_definition(j).axis for j in range(n)])
    assert np.abs(got - given).max() <= 3.4e-16
    assert np.array_equal(got[-3:], given[-3:])
