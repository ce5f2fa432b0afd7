"""URDF in and out for aqs linkages.

    L = aqs.load_urdf("robot.urdf")      # a finalized aqs.Linkage
    aqs.save_urdf(L, "copy.urdf")        # or L.save_urdf("copy.urdf")

load_urdf calls the library's loader, aqs_linkage_load_urdf (src/api/urdf.c,
expat): one loader for C and Python, documented in docs/urdf.md. In short:
bodies are the links in document order (a massless root link is the world),
joints the URDF joints in document order, preceded by joint 0
"world_to_<root>" when the root link has mass (fixed, or free with
root="free"); bodies and joints carry the file's names (Linkage.body_names,
joint_names, find_body, find_joint) and <limit> is kept (joint_limits; not
enforced by the solvers). revolute and continuous map to aqs "revolute",
prismatic, fixed, floating to "free", planar to "planar". Inertias are
checked where the solvers use them, on each rigid group of links welded by
fixed joints. What the file holds and aqs does not model (mimic,
transmissions, gazebo tags, dynamics, meshes...) is reported with
warnings.warn(URDFWarning); every file aqs cannot load raises URDFError.

save_urdf writes the model at q = 0 (URDF has no joint state): a massless
root link "world", one link per body with its inertial (origin at the
centre of mass, rpy 0, the body-frame inertia), one joint per joint with
origin xyz and rpy from its quaternion, every number with %.17g, names
from the linkage (else link_<i>, joint_<j>), limits when set. URDF names
must be distinct: a repeated name is written "name__2", "name__3"... (the
first occurrence keeps it) and a placeholder avoids every user name, with
one URDFWarning counting the names renamed; a name with a character XML
1.0 cannot carry (a control character other than tab, newline, carriage
return) raises URDFError. aqs revolute joints without position limits are
written as "continuous"; URDF has no "none", so unbounded positions are
written as +-1e300 and an infinite effort or velocity as 1e300 (loaded back
as +-1e300, not +-inf; urdfdom's readers require both attributes). Collision shapes
are not written (a URDFWarning counts them). Spherical, universal and
cylindrical joints have no URDF equivalent and raise URDFError. Loading
the file back gives the same masses, centres of mass, inertias and
joint origins bit for bit; joint rotations and axes to a few ulp (docs/urdf.md).
"""

import ctypes
import math
import os
import warnings
import xml.etree.ElementTree as ET

import numpy as np

__all__ = ["URDFError", "URDFWarning", "load_urdf", "save_urdf", "rpy_to_quat", "quat_to_rpy",
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


class URDFWarning(UserWarning):
    """Something a URDF file holds that aqs reads but does not model."""


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
# Reading: the C loader (aqs_linkage_load_urdf), one loader for C and Python
# ---------------------------------------------------------------------------

def load_urdf(path, root="fixed", finalize=True, collision=False, physical_inertia=False):
    """Load a URDF file as an aqs.Linkage (finalized unless finalize=False),
    with the library's loader (aqs_linkage_load_urdf; docs/urdf.md).

    root: what joins the root link to the world: "fixed" (the default) or
    "free". A massless root link is the world itself with "fixed"; with
    "free" it floats with the links welded to it, or the load is refused
    when nothing with mass is welded to it (never a silent fixed base).
    collision: True turns <collision> spheres, boxes, cylinders and capsules
    into shapes (Linkage.add_shape's); meshes are reported, not loaded.
    physical_inertia: True refuses link inertias no real body has (not
    positive semi-definite, or violating the triangle inequality); by
    default they load as given (listed in a warning) and only each rigid
    group of welded links must have mass and a positive definite inertia.
    Bodies and joints carry the links' and joints' names (body_names,
    joint_names, find_body, find_joint); <limit> is kept (joint_limits).
    What the file holds and aqs does not model (mimic, transmissions, gazebo
    tags, dynamics, meshes...) is reported with warnings.warn(URDFWarning),
    one warning per kind, and kept in Linkage.load_warnings.
    Raises URDFError for every file aqs cannot load (the message names the
    file, the link or joint and the value).
    """
    from . import Linkage, _c, _lib, _flag, InvalidArgument, ModelError  # loaded by now

    roots = {"fixed": _lib.URDF_ROOT_FIXED, "free": _lib.URDF_ROOT_FREE}
    if not isinstance(root, str) or root not in roots:
        raise URDFError("load_urdf: root = %r must be 'fixed' or 'free'" % (root,))
    options = _lib.aqs_urdf_options()
    _c.aqs_urdf_options_init(ctypes.byref(options))
    options.root = roots[root]
    options.collision = _flag(collision, "load_urdf", "collision")
    options.finalize = _flag(finalize, "load_urdf", "finalize")
    options.physical_inertia = _flag(physical_inertia, "load_urdf", "physical_inertia")
    linkage = Linkage()
    try:
        try:
            linkage._call("aqs_linkage_load_urdf", os.fsencode(os.fspath(path)),
                          ctypes.byref(options))
        except (InvalidArgument, ModelError) as exc:
            message = linkage.last_error
            prefix = "aqs_linkage_load_urdf: "
            raise URDFError(message[len(prefix):] if message.startswith(prefix) else message) \
                from None
        for text in linkage.load_warnings:
            warnings.warn(text, URDFWarning, stacklevel=2)
    except BaseException:
        linkage.close()
        raise
    return linkage


# ---------------------------------------------------------------------------
# Writing
# ---------------------------------------------------------------------------

def _fmt(values):
    return " ".join("%.17g" % (float(v) + 0.0) for v in np.ravel(values))


def _unwritable_character(text):
    """The first character of text that XML 1.0 cannot carry, not even as a
    character reference (&#1; is not well-formed): those below 0x20 other
    than tab, newline and carriage return, the surrogates, U+FFFE and
    U+FFFF. None when there is none."""
    for c in text:
        o = ord(c)
        if (o < 0x20 and c not in "\t\n\r") or 0xD800 <= o <= 0xDFFF or o in (0xFFFE, 0xFFFF):
            return c
    return None


def _check_names(names, what):
    """URDFError for the first name that XML cannot carry (what: "body" or
    "joint"), naming its index and the character. Such a name is refused
    rather than altered: the file would hold another name than the model."""
    for i, n in enumerate(names):
        c = _unwritable_character(n)
        if c is not None:
            raise URDFError("save_urdf: %s %d name %r holds the character U+%04X, which XML "
                            "1.0 cannot carry (not even escaped)" % (what, i, n, ord(c)))


def _unique_names(given, placeholder, what):
    """One distinct URDF name per body or joint, deterministically: given[i],
    the user's name ("" when unnamed), for its first occurrence; a later
    occurrence is written given[i] + "__2", "__3"...; an unnamed one gets
    placeholder % i. A name made here (suffixed or placeholder) avoids every
    user name and every name already handed out, so no user name loses its
    first occurrence to it. Returns the names and, for the warning, the
    descriptions of those written otherwise than "the user's name, else the
    placeholder"."""
    users = set(n for n in given if n)
    taken = set()
    next_suffix = {}  # base -> the first suffix not tried yet (no quadratic rescans)
    names = [None] * len(given)

    def fresh(base):
        k = next_suffix.get(base, 2)
        while "%s__%d" % (base, k) in users or "%s__%d" % (base, k) in taken:
            k += 1
        next_suffix[base] = k + 1
        return "%s__%d" % (base, k)

    # The user's names first, in index order, then the placeholders, so that
    # a placeholder avoids the names of later bodies too.
    for i, n in enumerate(given):
        if n:
            names[i] = n if n not in taken else fresh(n)
            taken.add(names[i])
    for i, n in enumerate(given):
        if not n:
            base = placeholder % i
            names[i] = base if base not in users and base not in taken else fresh(base)
            taken.add(names[i])
    renamed = ["%s %d %s -> %r" % (what, i, repr(n) if n else "(unnamed)", names[i])
               for i, n in enumerate(given) if names[i] != (n or placeholder % i)]
    return names, renamed


def save_urdf(linkage, path, name="aqs"):
    """Write linkage as URDF to path (see the module's documentation).

    Link names come from linkage.body_names when it has them (as load_urdf
    sets), else "link_<i>"; joint names likewise from joint_names, else
    "joint_<j>". URDF needs link names distinct, and joint names: a name met
    again is written with "__2", "__3"... appended (its first occurrence
    keeps it), a placeholder that is some body's or joint's name likewise,
    and one URDFWarning says how many names were renamed and which. A name
    holding a character XML cannot carry (control characters other than
    tab, newline, carriage return) raises URDFError, as do joints URDF
    cannot express (spherical, universal, cylindrical). Collision shapes are
    not written (a URDFWarning counts them)."""
    sizes = linkage.sizes()
    given_bodies, given_joints = linkage.body_names, linkage.joint_names
    _check_names(given_bodies, "body")
    _check_names(given_joints, "joint")
    bad = _unwritable_character(str(name))
    if bad is not None:
        raise URDFError("save_urdf: robot name %r holds the character U+%04X, which XML 1.0 "
                        "cannot carry (not even escaped)" % (name, ord(bad)))
    body_names, renamed = _unique_names(given_bodies, "link_%d", "body")
    joint_names, renamed_joints = _unique_names(given_joints, "joint_%d", "joint")
    renamed += renamed_joints
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
        limits = linkage.joint_limits(j)
        bounded = math.isfinite(limits.lower) or math.isfinite(limits.upper)
        if kind == "continuous" and bounded:
            kind = "revolute"
        joint = ET.SubElement(robot, "joint", name=joint_names[j], type=kind)
        ET.SubElement(joint, "origin", xyz=_fmt(d.pos), rpy=_fmt(quat_to_rpy(d.quat)))
        ET.SubElement(joint, "parent", link=world if d.parent < 0 else body_names[d.parent])
        ET.SubElement(joint, "child", link=body_names[d.child])
        if kind in _AXIS_TYPES:
            ET.SubElement(joint, "axis", xyz=_fmt(d.axis))
        if kind in ("prismatic", "revolute") or math.isfinite(limits.effort) \
                or math.isfinite(limits.velocity):
            # URDF has no "none": an unbounded position, effort or velocity
            # as +-1e300 (loaded back as 1e300: unbounded for any use). Not 0,
            # which loaded back as a limit of 0, and not left out: readers
            # on urdfdom (ROS, Pinocchio) require effort and velocity.
            def bound(v, sign):
                return _fmt([v]) if math.isfinite(v) else sign + _PRISMATIC_LIMIT
            ET.SubElement(joint, "limit", lower=bound(limits.lower, "-"),
                          upper=bound(limits.upper, ""), effort=bound(limits.effort, ""),
                          velocity=bound(limits.velocity, ""))
    ET.indent(robot)
    ET.ElementTree(robot).write(str(path), encoding="utf-8", xml_declaration=True)
    # What the file does not hold as the linkage does, one warning per kind.
    if renamed:
        warnings.warn("save_urdf: %d names renamed (URDF link names must be distinct, and "
                      "joint names): %s%s" % (len(renamed), ", ".join(renamed[:5]),
                                              ", ..." if len(renamed) > 5 else ""),
                      URDFWarning, stacklevel=2)
    shapes = linkage.shape_count
    if shapes > 0:
        warnings.warn("save_urdf: %d collision shapes are not written: save_urdf writes no "
                      "<collision>" % shapes, URDFWarning, stacklevel=2)
