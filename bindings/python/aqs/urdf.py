"""URDF in and out for aqs linkages, with Python's own xml.etree.

    L = aqs.load_urdf("robot.urdf")      # a finalized aqs.Linkage
    aqs.save_urdf(L, "copy.urdf")        # or L.save_urdf("copy.urdf")

URDF (http://wiki.ros.org/urdf/XML) describes a tree of links joined by
joints, at zero joint positions. Its conventions are aqs's own: a joint's
<origin xyz rpy> places the joint frame in the parent link's frame, the child
link's frame is the joint frame (moved by the joint position), the joint
<axis> is in the joint frame. Units are SI (m, kg, rad, kg m^2); aqs takes
them as they are. rpy = (roll, pitch, yaw) are fixed-axis rotations about x,
then y, then z: R = Rz(yaw) Ry(pitch) Rx(roll).

Joint types:
    revolute, continuous -> aqs "revolute" (limits, dynamics, safety and
                            calibration are ignored: aqs has no joint limits)
    prismatic            -> "prismatic"
    fixed                -> "fixed" (welds the child to the parent)
    floating             -> "free" (aqs free joints hang from the world only)
    planar               -> "planar" (URDF's axis is the plane normal, as
                            aqs's axis a; the translation coordinates are
                            along aqs's u and v)
Anything else (and <mimic>, which couples joints) raises URDFError.

The world: a root link without <inertial> (or with mass 0), such as the
customary "world" link, is the fixed world (aqs.WORLD). A root link with mass
is a body attached to the world by a joint named "world_to_<root>", joint 0:
fixed by default (as Pinocchio's and MuJoCo's URDF readers do), or free with
load_urdf(path, root="free").

Bodies are the non-world links in document order and joints the URDF joints
in document order; the loaded linkage carries the names as its attributes
body_names and joint_names, which save_urdf writes back.

Inertia: <inertial> holds <origin xyz rpy> (the centre of mass and the
orientation of the inertial frame in the link frame), <mass value> and
<inertia ixx ixy ixz iyy iyz izz> about the centre of mass in the inertial
frame (ixy = I[0][1], the tensor entry, as in URDF). A link without
<inertial> has no mass; aqs accepts it only when fixed joints weld it to a
link with mass or to the world (the library's rule at finalize), and
load_urdf says so, naming the link, before the library is asked.

save_urdf writes the model at q = 0 (URDF has no joint state): a massless
root link "world", one link per body with its inertial (origin at the
centre of mass, rpy 0, the body-frame inertia), one joint per joint with
origin xyz and rpy from its quaternion, every number with %.17g. aqs
revolute joints are written as "continuous" and prismatic ones with limits
of +-1e300 (URDF requires limits on them); spherical, universal and
cylindrical joints have no URDF equivalent and raise URDFError.
"""

import math
import xml.etree.ElementTree as ET

import numpy as np

__all__ = ["URDFError", "load_urdf", "save_urdf", "rpy_to_quat", "quat_to_rpy",
           "rpy_to_matrix"]

#: URDF joint type -> aqs joint kind.
URDF_TO_AQS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
               "fixed": "fixed", "floating": "free", "planar": "planar"}
#: aqs joint kind -> URDF joint type written by save_urdf.
AQS_TO_URDF = {"revolute": "continuous", "prismatic": "prismatic", "fixed": "fixed",
               "free": "floating", "planar": "planar"}
_AXIS_TYPES = ("revolute", "continuous", "prismatic", "planar")
_PRISMATIC_LIMIT = "1e300"


class URDFError(ValueError):
    """A URDF file aqs cannot load, or a linkage URDF cannot express. The
    message names the file, the link or joint, and the offending value."""


# ---------------------------------------------------------------------------
# Rotations
# ---------------------------------------------------------------------------

def rpy_to_quat(rpy):
    """Quaternion (w, x, y, z) of R = Rz(yaw) Ry(pitch) Rx(roll)."""
    roll, pitch, yaw = (0.5 * float(a) for a in rpy)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([cr * cp * cy + sr * sp * sy,
                     sr * cp * cy - cr * sp * sy,
                     cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy])


def rpy_to_matrix(rpy):
    """Rotation matrix Rz(yaw) Ry(pitch) Rx(roll)."""
    roll, pitch, yaw = (float(a) for a in rpy)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _quat_matrix(q):
    w, x, y, z = (float(v) for v in q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _wrap(angle):
    """angle moved into [-pi, pi] by a multiple of 2 pi."""
    if angle > math.pi:
        return angle - 2 * math.pi
    if angle < -math.pi:
        return angle + 2 * math.pi
    return angle


def quat_to_rpy(q):
    """(roll, pitch, yaw) with R(q) = Rz(yaw) Ry(pitch) Rx(roll), pitch in
    [-pi/2, pi/2], roll and yaw in [-pi, pi].

    Read from the quaternion's half-angle sums rather than from the rotation
    matrix, so that it stays accurate next to pitch = +-pi/2: with half
    angles (a, b, c) of (roll, pitch, yaw), w + y = (cos b + sin b) cos(c - a),
    z - x = (cos b + sin b) sin(c - a), w - y = (cos b - sin b) cos(c + a),
    z + x = (cos b - sin b) sin(c + a). Each angle pair's error is weighted
    by its factor, so the quaternion written back is right to a few ulp
    everywhere (at the gimbal lock itself, roll + yaw is taken as 0)."""
    w, x, y, z = (float(v) for v in q)
    plus = math.hypot(w + y, z - x)   # cos b + sin b >= 0
    minus = math.hypot(w - y, z + x)  # cos b - sin b >= 0
    pitch = 2.0 * math.atan2(plus - minus, plus + minus)
    total = 2.0 * math.atan2(z + x, w - y)  # yaw + roll
    difference = 2.0 * math.atan2(z - x, w + y)  # yaw - roll
    return (_wrap(0.5 * (total - difference)), pitch, _wrap(0.5 * (total + difference)))


# ---------------------------------------------------------------------------
# Reading
# ---------------------------------------------------------------------------

class _Reader:
    def __init__(self, path):
        self.path = str(path)

    def fail(self, message):
        raise URDFError("%s: %s" % (self.path, message))

    def numbers(self, element, attribute, count, default, where):
        text = element.get(attribute) if element is not None else None
        if text is None:
            if default is None:
                self.fail("%s: missing attribute %s" % (where, attribute))
            return np.array(default, dtype=float)
        try:
            values = [float(v) for v in text.split()]
        except ValueError:
            self.fail("%s: %s = %r is not %d numbers" % (where, attribute, text, count))
        if len(values) != count:
            self.fail("%s: %s = %r has %d numbers, expected %d"
                      % (where, attribute, text, len(values), count))
        for v in values:
            if not math.isfinite(v):
                self.fail("%s: %s = %r is not finite" % (where, attribute, text))
        return np.array(values, dtype=float)

    def origin(self, parent, where):
        element = parent.find("origin")
        xyz = self.numbers(element, "xyz", 3, (0.0, 0.0, 0.0), where + " <origin>")
        rpy = self.numbers(element, "rpy", 3, (0.0, 0.0, 0.0), where + " <origin>")
        return xyz, rpy

    def inertial(self, link, name):
        """(mass, com, inertia in the link frame, has_inertial)."""
        where = "link %r" % name
        element = link.find("inertial")
        if element is None:
            return 0.0, np.zeros(3), np.zeros((3, 3)), False
        xyz, rpy = self.origin(element, where + " <inertial>")
        mass_element = element.find("mass")
        if mass_element is None:
            self.fail("%s: <inertial> has no <mass>" % where)
        mass = float(self.numbers(mass_element, "value", 1, None, where + " <mass>")[0])
        if mass < 0.0:
            self.fail("%s: mass = %r is negative" % (where, mass))
        inertia_element = element.find("inertia")
        if inertia_element is None:
            if mass > 0.0:
                self.fail("%s: <inertial> has mass %r but no <inertia>" % (where, mass))
            return mass, xyz, np.zeros((3, 3)), True
        values = {}
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            values[key] = float(self.numbers(inertia_element, key, 1, None,
                                             where + " <inertia>")[0])
        local = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                          [values["ixy"], values["iyy"], values["iyz"]],
                          [values["ixz"], values["iyz"], values["izz"]]])
        moments = np.linalg.eigvalsh(local)
        scale = max(np.abs(moments).max(), 1e-300)
        if mass > 0.0 and not moments[0] > 0.0:
            self.fail("%s: inertia (ixx ixy ixz iyy iyz izz = %s) is not positive definite: "
                      "principal moments %s; a link with mass %r needs positive ones"
                      % (where, " ".join("%r" % values[k] for k in
                                         ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")),
                         ", ".join("%.6g" % m for m in moments), mass))
        if mass == 0.0 and moments[0] < -1e-9 * scale:
            self.fail("%s: massless link with an inertia that is not positive semi-definite "
                      "(principal moments %s)" % (where, ", ".join("%.6g" % m for m in moments)))
        if rpy.any():
            rotation = rpy_to_matrix(rpy)
            local = rotation @ local @ rotation.T
            local = 0.5 * (local + local.T)
        return mass, xyz, local, True


def load_urdf(path, root="fixed", finalize=True):
    """Load a URDF file as an aqs.Linkage (finalized unless finalize=False).

    root: what joins a root link that has mass to the world: "fixed" (the
    default) or "free". A root link without mass is the world itself.
    Returns the linkage, with attributes body_names (body index -> link name)
    and joint_names (joint index -> joint name). Raises URDFError for a file
    aqs cannot load: not URDF, unknown joint types, a missing or repeated
    link, a link with two parents, several roots, a cycle, a missing or
    non-positive mass or inertia, a massless link not welded to a massive
    one; the message names the link or joint and the value.
    """
    from . import Linkage, WORLD, Error, ModelError  # the package, loaded by now

    reader = _Reader(path)
    if root not in ("fixed", "free"):
        raise URDFError("load_urdf: root = %r must be 'fixed' or 'free'" % (root,))
    try:
        document = ET.parse(str(path))
    except ET.ParseError as exc:
        reader.fail("not well-formed XML (%s)" % exc)
    except OSError as exc:
        raise URDFError("%s: cannot read (%s)" % (path, exc)) from exc
    robot = document.getroot()
    if robot.tag != "robot":
        reader.fail("the root element is <%s>, not <robot>" % robot.tag)

    links, link_elements = [], {}
    for element in robot.findall("link"):
        name = element.get("name")
        if not name:
            reader.fail("a <link> has no name")
        if name in link_elements:
            reader.fail("link %r is defined twice" % name)
        links.append(name)
        link_elements[name] = element
    if not links:
        reader.fail("no <link>")

    joints = []
    parent_joint = {}
    seen_joints = set()
    for element in robot.findall("joint"):
        name = element.get("name")
        if not name:
            reader.fail("a <joint> has no name")
        if name in seen_joints:
            reader.fail("joint %r is defined twice" % name)
        seen_joints.add(name)
        where = "joint %r" % name
        kind = element.get("type")
        if kind not in URDF_TO_AQS:
            reader.fail("%s: type = %r is not supported (aqs loads %s)"
                        % (where, kind, ", ".join(sorted(URDF_TO_AQS))))
        if element.find("mimic") is not None:
            reader.fail("%s: <mimic> couples joints, which aqs does not support" % where)
        ends = []
        for tag in ("parent", "child"):
            end = element.find(tag)
            link = end.get("link") if end is not None else None
            if not link:
                reader.fail("%s: missing <%s link=...>" % (where, tag))
            if link not in link_elements:
                reader.fail("%s: %s link %r is not defined" % (where, tag, link))
            ends.append(link)
        parent, child = ends
        if parent == child:
            reader.fail("%s: parent and child are the same link %r" % (where, parent))
        if child in parent_joint:
            reader.fail("link %r is the child of two joints (%r and %r)"
                        % (child, parent_joint[child], name))
        parent_joint[child] = name
        xyz, rpy = reader.origin(element, where)
        axis = np.array([1.0, 0.0, 0.0])
        if kind in _AXIS_TYPES:
            axis = reader.numbers(element.find("axis"), "xyz", 3, (1.0, 0.0, 0.0),
                                  where + " <axis>")
            if not np.linalg.norm(axis) > 0.0:
                reader.fail("%s: <axis xyz> is zero" % where)
        joints.append(dict(name=name, kind=URDF_TO_AQS[kind], urdf_kind=kind, parent=parent,
                           child=child, xyz=xyz, rpy=rpy, axis=axis))

    roots = [name for name in links if name not in parent_joint]
    if not roots:
        reader.fail("the joints form a cycle: every link has a parent (%s)"
                    % _cycle_text(links[0], parent_joint, joints))
    if len(roots) > 1:
        reader.fail("several root links (links that are no joint's child): %s; a URDF tree "
                    "has exactly one" % ", ".join(repr(r) for r in roots))
    root_link = roots[0]
    children = {name: [] for name in links}
    for j in joints:
        children[j["parent"]].append(j["child"])
    reached, stack = {root_link}, [root_link]
    while stack:
        for c in children[stack.pop()]:
            if c not in reached:
                reached.add(c)
                stack.append(c)
    if len(reached) < len(links):
        lost = next(name for name in links if name not in reached)
        reader.fail("the joints form a cycle not connected to the root link %r (%s)"
                    % (root_link, _cycle_text(lost, parent_joint, joints)))

    inertials = {name: reader.inertial(link_elements[name], name) for name in links}
    root_is_world = inertials[root_link][0] == 0.0
    body_links = [name for name in links if not (root_is_world and name == root_link)]
    body_of = {name: i for i, name in enumerate(body_links)}

    # The library's rule, checked here to name the links: every group of links
    # welded by fixed joints needs mass, unless it is welded to the world.
    group = {name: name for name in links}

    def find(name):
        while group[name] != name:
            group[name] = group[group[name]]
            name = group[name]
        return name

    for j in joints:
        if j["kind"] == "fixed":
            group[find(j["child"])] = find(j["parent"])
    world_group = find(root_link) if root_is_world or root == "fixed" else None
    group_mass = {}
    for name in links:
        g = find(name)
        group_mass[g] = group_mass.get(g, 0.0) + inertials[name][0]
    for name in links:
        g = find(name)
        if g != world_group and not group_mass[g] > 0.0:
            members = [n for n in links if find(n) == g]
            reader.fail("link %r has no mass (%s) and is not welded by fixed joints to a link "
                        "with mass or to the world (its rigid group: %s); aqs needs mass on "
                        "every moving part"
                        % (name, "no <inertial>" if not inertials[name][3] else "mass 0",
                           ", ".join(repr(m) for m in members)))

    for j in joints:
        if j["kind"] == "free" and not (root_is_world and j["parent"] == root_link):
            reader.fail("joint %r: a floating joint must hang from the massless root link "
                        "(the world); its parent is %r" % (j["name"], j["parent"]))

    linkage = Linkage()
    try:
        linkage.set_inertia_check(True)
        for name in body_links:
            mass, com, inertia, _ = inertials[name]
            try:
                linkage.add_body(mass, com, inertia)
            except Error as exc:
                reader.fail("link %r: %s" % (name, exc))
        joint_names = []
        if not root_is_world:
            kind = root
            linkage.add_joint(kind, WORLD, body_of[root_link])
            joint_names.append("world_to_" + root_link)
        for j in joints:
            parent = WORLD if (root_is_world and j["parent"] == root_link) \
                else body_of[j["parent"]]
            try:
                linkage.add_joint(j["kind"], parent, body_of[j["child"]], pos=j["xyz"],
                                  quat=rpy_to_quat(j["rpy"]),
                                  axis=j["axis"] if j["urdf_kind"] in _AXIS_TYPES else None)
            except Error as exc:
                reader.fail("joint %r: %s" % (j["name"], exc))
            joint_names.append(j["name"])
        linkage.body_names = list(body_links)
        linkage.joint_names = joint_names
        if finalize:
            try:
                linkage.finalize()
            except ModelError as exc:
                reader.fail("%s (bodies are the links %s)"
                            % (exc, _name_list(body_links)))
    except BaseException:
        linkage.close()
        raise
    return linkage


def _name_list(names, limit=20):
    shown = ", ".join("%d = %r" % (i, n) for i, n in enumerate(names[:limit]))
    return shown + (", ..." if len(names) > limit else "")


def _cycle_text(start, parent_joint, joints):
    parent_of = {j["child"]: j["parent"] for j in joints}
    path, name = [], start
    while name in parent_of and name not in path:
        path.append(name)
        name = parent_of[name]
    if name in path:
        path = path[path.index(name):] + [name]
    return " <- ".join(repr(n) for n in path)


# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------

def _fmt(values):
    return " ".join("%.17g" % (float(v) + 0.0) for v in np.ravel(values))


def save_urdf(linkage, path, name="aqs"):
    """Write linkage as URDF to path (see the module's documentation).

    Link names come from linkage.body_names when it has them (as load_urdf
    sets), else "link_<i>"; joint names likewise from joint_names, else
    "joint_<j>". Raises URDFError for joints URDF cannot express (spherical,
    universal, cylindrical, or a free joint from a body)."""
    sizes = linkage.sizes()
    body_names = getattr(linkage, "body_names", None)
    joint_names = getattr(linkage, "joint_names", None)
    if body_names is None or len(body_names) != sizes.bodies:
        body_names = ["link_%d" % i for i in range(sizes.bodies)]
    if joint_names is None or len(joint_names) != sizes.joints:
        joint_names = ["joint_%d" % j for j in range(sizes.joints)]
    world = "world"
    while world in body_names:
        world = "_" + world

    robot = ET.Element("robot", name=name)
    ET.SubElement(robot, "link", name=world)
    for b in range(sizes.bodies):
        mass, com, inertia = linkage.body_inertial(b)
        link = ET.SubElement(robot, "link", name=body_names[b])
        inertial = ET.SubElement(link, "inertial")
        ET.SubElement(inertial, "origin", xyz=_fmt(com), rpy="0 0 0")
        ET.SubElement(inertial, "mass", value=_fmt([mass]))
        ET.SubElement(inertial, "inertia", ixx=_fmt([inertia[0, 0]]),
                      ixy=_fmt([inertia[0, 1]]), ixz=_fmt([inertia[0, 2]]),
                      iyy=_fmt([inertia[1, 1]]), iyz=_fmt([inertia[1, 2]]),
                      izz=_fmt([inertia[2, 2]]))
    for j in range(sizes.joints):
        d = linkage.joint_definition(j)
        kind = AQS_TO_URDF.get(d.kind)
        if kind is None:
            raise URDFError("save_urdf: joint %d (%r) is %s, which URDF cannot express "
                            "(URDF has %s)" % (j, joint_names[j], d.kind,
                                               ", ".join(sorted(URDF_TO_AQS))))
        joint = ET.SubElement(robot, "joint", name=joint_names[j], type=kind)
        ET.SubElement(joint, "origin", xyz=_fmt(d.pos), rpy=_fmt(quat_to_rpy(d.quat)))
        ET.SubElement(joint, "parent", link=world if d.parent < 0 else body_names[d.parent])
        ET.SubElement(joint, "child", link=body_names[d.child])
        if kind in _AXIS_TYPES:
            ET.SubElement(joint, "axis", xyz=_fmt(d.axis))
        if kind == "prismatic":
            ET.SubElement(joint, "limit", lower="-" + _PRISMATIC_LIMIT, upper=_PRISMATIC_LIMIT,
                          effort="0", velocity="0")
    ET.indent(robot)
    ET.ElementTree(robot).write(str(path), encoding="utf-8", xml_declaration=True)
