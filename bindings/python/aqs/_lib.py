"""Loading libaqs and declaring its C functions (private).

Everything that touches ctypes directly lives here: where the shared library
is found, the one table of prototypes (argtypes/restype of every function in
include/aqs.h), and the fixed constants of the header.
"""

import ctypes
import ctypes.util
import glob
import os

import numpy as np

# ---------------------------------------------------------------------------
# Constants copied from include/aqs.h (fixed values, never renumbered).
# ---------------------------------------------------------------------------

#: The library MAJOR version these bindings speak (AQS_VERSION_MAJOR).
VERSION_MAJOR = 0

OK = 0
EINVAL = -1
ERANGE = -2
ESTATE = -3
ENOMEM = -4
EMODEL = -5
ENUMERIC = -6
ESIZE = -7

STATUS_NAMES = {
    OK: "AQS_OK",
    EINVAL: "AQS_EINVAL",
    ERANGE: "AQS_ERANGE",
    ESTATE: "AQS_ESTATE",
    ENOMEM: "AQS_ENOMEM",
    EMODEL: "AQS_EMODEL",
    ENUMERIC: "AQS_ENUMERIC",
    ESIZE: "AQS_ESIZE",
}

WORLD = -1

JOINT_REVOLUTE = 0
JOINT_PRISMATIC = 1
JOINT_SPHERICAL = 2
JOINT_FREE = 3
JOINT_FIXED = 4
JOINT_UNIVERSAL = 5
JOINT_CYLINDRICAL = 6
JOINT_PLANAR = 7

JOINT_KINDS = {
    "revolute": JOINT_REVOLUTE,
    "prismatic": JOINT_PRISMATIC,
    "spherical": JOINT_SPHERICAL,
    "free": JOINT_FREE,
    "fixed": JOINT_FIXED,
    "universal": JOINT_UNIVERSAL,
    "cylindrical": JOINT_CYLINDRICAL,
    "planar": JOINT_PLANAR,
}

# Error measures of adaptive solving (AQS_METRIC_*), over the joints a solve
# did not compute; a joint's error is the 2-norm of its acceleration vector,
# free joints excluded.
METRIC_ABS_LINKAGE = 0  # sqrt(sum of ||qdd_j||^2 over uncomputed j)
METRIC_REL_LINKAGE = 1  # the above / sqrt(sum over all joints)
METRIC_ABS_JOINT = 2    # max ||qdd_j|| over uncomputed j
METRIC_REL_JOINT = 3    # the above / max ||qdd_j|| over all joints
# World-space measures: e_b = |delta a_b| + ell_b |delta alpha_b| per body
# (centre-of-mass and angular acceleration errors; docs/math.md section 10a).
METRIC_ABS_WORLD = 4    # max_b e_b over all bodies
METRIC_REL_WORLD = 5    # the above / max_b (|a_b| + ell_b |alpha_b|)

METRICS = {
    "abs_linkage": METRIC_ABS_LINKAGE,
    "rel_linkage": METRIC_REL_LINKAGE,
    "abs_joint": METRIC_ABS_JOINT,
    "rel_joint": METRIC_REL_JOINT,
    "abs_world": METRIC_ABS_WORLD,
    "rel_world": METRIC_REL_WORLD,
}
METRIC_NAMES = {value: name for name, value in METRICS.items()}

# Which bound the joint-wise measures stop on (AQS_JOINT_BOUND_*).
JOINT_BOUND_HEAP_TOP = 0  # sqrt(max of the queued A(C)), tighter (default)
JOINT_BOUND_SUM = 1       # sqrt(sum of the queued A(C)), the paper's

JOINT_BOUNDS = {
    "heap_top": JOINT_BOUND_HEAP_TOP,
    "sum": JOINT_BOUND_SUM,
}

# Which algorithm computes an exact solve (AQS_EXACT_*).
EXACT_ABA = 0  # articulated-body algorithm over the joints, O(N) (default)
EXACT_DCA = 1  # full divide-and-conquer back-substitution over the assembly tree

# Exact solves after an adaptive solve that computed more than the fallback
# fraction of the joints (aqs_linkage_set_exact_fallback).
FALLBACK_RUN = 15
# The rounding fallback's default level (AQS_ROUNDING_FALLBACK_LEVEL).
ROUNDING_FALLBACK_LEVEL = 1e-8
# The adaptive refinement's default level (AQS_ADAPTIVE_REFINEMENT_LEVEL).
ADAPTIVE_REFINEMENT_LEVEL = 1e-10

# Most corrections of an exact DCA solve, and the default (AQS_REFINEMENT_MAX).
REFINEMENT_MAX = 3

# Default margin of aqs_linkage_set_prediction (AQS_PREDICTION_MARGIN).
PREDICTION_MARGIN = 1024.0

# Which path a solve ran (aqs_solve_stats.path, AQS_PATH_*).
PATH_ADAPTIVE = 0   # the adaptive solver (a tolerance or a cap)
PATH_EXACT_ABA = 1  # exact, the articulated-body algorithm
PATH_EXACT_DCA = 2  # exact, the full DCA back-substitution
PATH_NAMES = {PATH_ADAPTIVE: "adaptive", PATH_EXACT_ABA: "exact_aba", PATH_EXACT_DCA: "exact_dca"}

EXACT_SOLVERS = {
    "aba": EXACT_ABA,
    "dca": EXACT_DCA,
}
EXACT_SOLVER_NAMES = {value: name for name, value in EXACT_SOLVERS.items()}

# How the divide-and-conquer solver keeps Phi (AQS_DCA_FORM_*).
DCA_FORM_SQRT = 0  # composite inertia + square-root factor (default; accurate)
DCA_FORM_PHI = 1   # explicit Phi (faster per node, loses digits on hard cases)
DCA_FORMS = {
    "sqrt": DCA_FORM_SQRT,
    "phi": DCA_FORM_PHI,
}
DCA_FORM_NAMES = {value: name for name, value in DCA_FORMS.items()}

# How finalize builds the assembly tree (AQS_TREE_*).
TREE_CONTRACTION = 0  # rake and compress rounds (default)
TREE_BISECTION = 1    # recursive bisection at the most balancing joint

TREE_BUILDERS = {
    "contraction": TREE_CONTRACTION,
    "bisection": TREE_BISECTION,
}

# Collision shapes (AQS_SHAPE_*) and query modes (AQS_COLLIDE_*).
SHAPE_SPHERE = 0    # size[0] radius
SHAPE_CAPSULE = 1   # size[0] radius, size[1] half-length along z
SHAPE_BOX = 2       # size[0..2] half-extents
SHAPE_CYLINDER = 3  # size[0] radius, size[1] half-height along z
SHAPE_HULL = 4      # convex hull of points (add_hull)

SHAPES = {
    "sphere": SHAPE_SPHERE,
    "capsule": SHAPE_CAPSULE,
    "box": SHAPE_BOX,
    "cylinder": SHAPE_CYLINDER,
    "hull": SHAPE_HULL,
}

COLLIDE_LAZY = 0   # tree, refit and skip what did not move (default)
COLLIDE_FULL = 1   # tree, everything refitted and re-tested
COLLIDE_BRUTE = 2  # all pairs of shapes (reference)

COLLIDE_MODES = {
    "lazy": COLLIDE_LAZY,
    "full": COLLIDE_FULL,
    "brute": COLLIDE_BRUTE,
}

# ---------------------------------------------------------------------------
# C types
# ---------------------------------------------------------------------------


class aqs_linkage(ctypes.Structure):
    """The opaque struct aqs_linkage (only ever used through a pointer)."""

    _fields_ = []


linkage_p = ctypes.POINTER(aqs_linkage)
status_t = ctypes.c_int32
int32_p = ctypes.POINTER(ctypes.c_int32)
double_p = ctypes.POINTER(ctypes.c_double)



class aqs_solve_stats(ctypes.Structure):
    """struct aqs_solve_stats, field for field (the caller sets size)."""

    _fields_ = [
        ("size", ctypes.c_uint32),          # set by the caller: sizeof(aqs_solve_stats)
        ("metric", ctypes.c_int32),         # AQS_METRIC_* in force
        ("eps", ctypes.c_double),           # the bound asked for (0 = exact)
        ("error_bound", ctypes.c_double),   # certified bound achieved (0 when exact)
        ("computed_joints", ctypes.c_int32),  # joint accelerations computed (free excluded)
        ("counted_joints", ctypes.c_int32),   # joints counted by the measures (not free)
        ("nodes_updated", ctypes.c_int32),    # tree nodes recomputed by the last update
        ("nodes_processed", ctypes.c_int32),  # internal nodes back-substituted by the solve
        ("capped", ctypes.c_int32),           # 1 if the solve stopped at the max_computed cap
        ("fallback", ctypes.c_int32),         # 1 if exact because of the exact fallback
        ("nodes_predicted", ctypes.c_int32),  # processed without evaluating A (prediction)
        ("factors_updated", ctypes.c_int32),  # total-acceleration factors recomputed
        ("path", ctypes.c_int32),             # AQS_PATH_*: the path the solve ran
        ("auto_chosen", ctypes.c_int32),      # 1 if the automatic path chose it
        ("cost_adaptive", ctypes.c_double),   # its predicted cost of the adaptive path (instructions)
        ("cost_exact", ctypes.c_double),      # and of the exact path
        ("rounding_bound", ctypes.c_double),  # estimate of what the DCA's rounding adds (inf: none)
        ("certified", ctypes.c_int32),        # 1: error_bound + rounding_bound is a bound, <= eps
        ("rounding_fallback", ctypes.c_int32),  # 1 if exact because of the rounding fallback
    ]


solve_stats_p = ctypes.POINTER(aqs_solve_stats)

# URDF loading (AQS_URDF_ROOT_*).
URDF_ROOT_FIXED = 0
URDF_ROOT_FREE = 1


class aqs_urdf_options(ctypes.Structure):
    """struct aqs_urdf_options, field for field (filled by aqs_urdf_options_init)."""

    _fields_ = [
        ("size", ctypes.c_uint32),
        ("root", ctypes.c_int32),              # AQS_URDF_ROOT_*
        ("collision", ctypes.c_int32),         # 1: <collision> primitives become shapes
        ("finalize", ctypes.c_int32),          # 1: finalize after loading
        ("physical_inertia", ctypes.c_int32),  # 1: unphysical link inertias are errors
    ]


urdf_options_p = ctypes.POINTER(aqs_urdf_options)


class aqs_memory_stats(ctypes.Structure):
    """struct aqs_memory_stats, field for field (the caller sets size)."""

    _fields_ = [
        ("size", ctypes.c_uint32),  # set by the caller: sizeof(aqs_memory_stats)
        ("blocks", ctypes.c_uint32),
        ("bytes", ctypes.c_uint64),
        ("peak", ctypes.c_uint64),
        ("model", ctypes.c_uint64),
        ("tree", ctypes.c_uint64),
        ("exact", ctypes.c_uint64),
        ("dca", ctypes.c_uint64),
        ("factors", ctypes.c_uint64),
        ("world", ctypes.c_uint64),
        ("collision", ctypes.c_uint64),
    ]


class aqs_collision_stats(ctypes.Structure):
    """struct aqs_collision_stats, field for field (the caller sets size)."""

    _fields_ = [
        ("size", ctypes.c_uint32),  # set by the caller: sizeof(aqs_collision_stats)
        ("nodes_refit", ctypes.c_int32),
        ("volume_tests", ctypes.c_int32),
        ("narrow_tests", ctypes.c_int32),
        ("nodes_skipped", ctypes.c_int32),
        ("certs_reused", ctypes.c_int32),
        ("certs_made", ctypes.c_int32),
        ("near_tests", ctypes.c_int32),
    ]


class aqs_contact(ctypes.Structure):
    """struct aqs_contact, field for field."""

    _fields_ = [
        ("body_a", ctypes.c_int32),
        ("body_b", ctypes.c_int32),   # WORLD for an obstacle
        ("shape_a", ctypes.c_int32),
        ("shape_b", ctypes.c_int32),
        ("depth", ctypes.c_double),
        ("nx", ctypes.c_double),      # unit normal from a towards b, world frame
        ("ny", ctypes.c_double),
        ("nz", ctypes.c_double),
        ("px", ctypes.c_double),      # contact point, world frame
        ("py", ctypes.c_double),
        ("pz", ctypes.c_double),
    ]


contact_p = ctypes.POINTER(aqs_contact)
size_p = ctypes.POINTER(ctypes.c_size_t)

alloc_fn = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)
free_fn = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p)


def _double_array(writable, nullable):
    """An argtype for a `double *` taking a float64 C-contiguous numpy array.

    numpy.ctypeslib.ndpointer passes the array's own buffer (no copy) and
    rejects any other dtype or layout with TypeError; the Python layer
    converts inputs beforehand, so this is a safety net. With nullable, None
    passes NULL.
    """
    flags = ("C_CONTIGUOUS", "WRITEABLE") if writable else ("C_CONTIGUOUS",)
    base = np.ctypeslib.ndpointer(dtype=np.float64, flags=flags)
    if not nullable:
        return base

    def from_param(cls, obj):
        if obj is None:
            return None
        return base.from_param(obj)

    return type(base.__name__ + "_or_NULL", (base,), {"from_param": classmethod(from_param)})


din = _double_array(writable=False, nullable=False)  # const double *, non-NULL
din_or_null = _double_array(writable=False, nullable=True)  # const double *, may be NULL
dout = _double_array(writable=True, nullable=False)  # double * filled by C
dout_or_null = _double_array(writable=True, nullable=True)

# ---------------------------------------------------------------------------
# The one table: name -> (restype, argtypes), in the order of aqs.h.
# To add a C function, add its row here and a method in __init__.py.
# ---------------------------------------------------------------------------

PROTOTYPES = {
    # Version
    "aqs_version": (ctypes.c_int32, []),
    "aqs_version_string": (ctypes.c_char_p, []),
    # Status codes
    "aqs_status_string": (ctypes.c_char_p, [status_t]),
    # Creation, allocation, errors
    "aqs_linkage_create": (status_t, [ctypes.POINTER(linkage_p)]),
    "aqs_linkage_create_with_allocator": (
        status_t, [alloc_fn, free_fn, ctypes.c_void_p, ctypes.POINTER(linkage_p)]),
    "aqs_linkage_destroy": (None, [linkage_p]),
    "aqs_linkage_last_error": (ctypes.c_char_p, [linkage_p]),
    # Building
    "aqs_linkage_set_inertia_check": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_set_tree_builder": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_body_add": (status_t, [linkage_p, ctypes.c_double, din, din, int32_p]),
    "aqs_joint_add": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_int32, ctypes.c_int32,
                                 din, din, din_or_null, int32_p]),
    "aqs_linkage_finalize": (status_t, [linkage_p]),
    "aqs_linkage_get_sizes": (status_t, [linkage_p, int32_p, int32_p, int32_p, int32_p]),
    "aqs_joint_get_layout": (status_t, [linkage_p, ctypes.c_int32,
                                        int32_p, int32_p, int32_p, int32_p]),
    "aqs_linkage_get_tree_stats": (status_t, [linkage_p, int32_p, int32_p, double_p, int32_p]),
    # Reading the model back
    "aqs_body_get_inertial": (status_t, [linkage_p, ctypes.c_int32, double_p, dout_or_null,
                                         dout_or_null]),
    "aqs_joint_get_definition": (status_t, [linkage_p, ctypes.c_int32, int32_p, int32_p,
                                            int32_p, dout_or_null, dout_or_null, dout_or_null]),
    # Names and joint limits
    "aqs_body_set_name": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_char_p]),
    "aqs_joint_set_name": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_char_p]),
    "aqs_body_get_name": (status_t, [linkage_p, ctypes.c_int32, ctypes.POINTER(ctypes.c_char_p)]),
    "aqs_joint_get_name": (status_t, [linkage_p, ctypes.c_int32,
                                      ctypes.POINTER(ctypes.c_char_p)]),
    "aqs_body_find": (status_t, [linkage_p, ctypes.c_char_p, int32_p]),
    "aqs_joint_find": (status_t, [linkage_p, ctypes.c_char_p, int32_p]),
    "aqs_joint_set_limits": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_double,
                                        ctypes.c_double, ctypes.c_double, ctypes.c_double]),
    "aqs_joint_get_limits": (status_t, [linkage_p, ctypes.c_int32, double_p, double_p, double_p,
                                        double_p]),
    # Loading URDF models
    "aqs_urdf_options_init": (None, [urdf_options_p]),
    "aqs_urdf_supported": (ctypes.c_int32, []),
    "aqs_linkage_load_urdf": (status_t, [linkage_p, ctypes.c_char_p, urdf_options_p]),
    "aqs_linkage_load_urdf_buffer": (status_t, [linkage_p, ctypes.c_char_p, ctypes.c_size_t,
                                                ctypes.c_char_p, urdf_options_p]),
    "aqs_linkage_load_warnings": (ctypes.c_char_p, [linkage_p]),
    # Loads
    "aqs_linkage_set_gravity": (status_t, [linkage_p, din]),
    "aqs_body_set_force": (status_t, [linkage_p, ctypes.c_int32, din,
                                      din_or_null, din_or_null]),
    "aqs_body_clear_force": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_clear_forces": (status_t, [linkage_p]),
    "aqs_joint_set_force": (status_t, [linkage_p, ctypes.c_int32, din_or_null, ctypes.c_int32]),
    # Solving and stepping
    "aqs_linkage_solve": (status_t, [linkage_p]),
    "aqs_linkage_step": (status_t, [linkage_p, ctypes.c_double]),
    # Error-bounded adaptive solving
    "aqs_linkage_set_tolerance": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_double]),
    "aqs_linkage_set_max_computed": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_set_joint_bound": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_set_exact_solver": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_get_exact_solver": (status_t, [linkage_p, int32_p]),
    "aqs_linkage_set_exact_refinement": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_get_exact_refinement": (status_t, [linkage_p, int32_p]),
    "aqs_linkage_set_dca_form": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_get_dca_form": (status_t, [linkage_p, int32_p]),
    "aqs_linkage_set_exact_fallback": (status_t, [linkage_p, ctypes.c_double]),
    "aqs_linkage_get_exact_fallback": (status_t, [linkage_p, ctypes.POINTER(ctypes.c_double)]),
    "aqs_linkage_set_rounding_fallback": (status_t, [linkage_p, ctypes.c_double]),
    "aqs_linkage_get_rounding_fallback": (status_t, [linkage_p, ctypes.POINTER(ctypes.c_double)]),
    "aqs_linkage_set_adaptive_refinement": (status_t, [linkage_p, ctypes.c_double]),
    "aqs_linkage_get_adaptive_refinement": (status_t, [linkage_p, ctypes.POINTER(ctypes.c_double)]),
    "aqs_linkage_set_prediction": (status_t, [linkage_p, ctypes.c_double]),
    "aqs_linkage_get_prediction": (status_t, [linkage_p, ctypes.POINTER(ctypes.c_double)]),
    "aqs_linkage_set_auto": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_get_auto": (status_t, [linkage_p, ctypes.POINTER(ctypes.c_int32)]),
    "aqs_linkage_refine": (status_t, [linkage_p, ctypes.c_double]),
    "aqs_linkage_get_stats": (status_t, [linkage_p, solve_stats_p]),
    "aqs_joint_get_computed": (status_t, [linkage_p, ctypes.c_int32, int32_p]),
    # Reading back and setting state
    "aqs_linkage_get_positions": (status_t, [linkage_p, dout_or_null, ctypes.c_size_t]),
    "aqs_linkage_set_positions": (status_t, [linkage_p, din_or_null, ctypes.c_size_t]),
    "aqs_joint_get_position": (status_t, [linkage_p, ctypes.c_int32, dout_or_null,
                                          ctypes.c_int32]),
    "aqs_joint_set_position": (status_t, [linkage_p, ctypes.c_int32, din_or_null,
                                          ctypes.c_int32]),
    "aqs_linkage_get_accelerations": (status_t, [linkage_p, dout_or_null, ctypes.c_size_t]),
    "aqs_joint_get_acceleration": (status_t, [linkage_p, ctypes.c_int32, dout_or_null,
                                              ctypes.c_int32]),
    "aqs_linkage_get_constraint_forces": (status_t, [linkage_p, dout_or_null,
                                                     ctypes.c_size_t]),
    "aqs_joint_get_constraint_force": (status_t, [linkage_p, ctypes.c_int32, dout]),
    "aqs_body_get_pose_world": (status_t, [linkage_p, ctypes.c_int32, dout, dout]),
    "aqs_linkage_get_body_poses_world": (status_t, [linkage_p, dout_or_null, ctypes.c_size_t]),
    # Collision
    "aqs_shape_add": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_int32, din, din, din, int32_p]),
    "aqs_shape_add_hull": (status_t, [linkage_p, ctypes.c_int32, din, ctypes.c_int32, din, din,
                                      int32_p]),
    "aqs_linkage_get_shape_count": (status_t, [linkage_p, int32_p]),
    "aqs_body_set_collision_filter": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_uint32,
                                                 ctypes.c_uint32]),
    "aqs_collision_exclude_pair": (status_t, [linkage_p, ctypes.c_int32, ctypes.c_int32]),
    "aqs_linkage_set_collide_joined": (status_t, [linkage_p, ctypes.c_int32]),
    "aqs_linkage_collide": (status_t, [linkage_p, ctypes.c_int32, contact_p, ctypes.c_size_t,
                                       size_p]),
    "aqs_linkage_any_contact": (status_t, [linkage_p, int32_p]),
    "aqs_linkage_get_collision_stats": (status_t, [linkage_p, int32_p, int32_p, int32_p, int32_p]),
    "aqs_linkage_get_query_stats": (status_t, [linkage_p, ctypes.POINTER(aqs_collision_stats)]),
    "aqs_linkage_get_memory": (status_t, [linkage_p, ctypes.POINTER(aqs_memory_stats)]),
    "aqs_linkage_set_contact_stiffness": (status_t, [linkage_p, ctypes.c_double]),
}

# ---------------------------------------------------------------------------
# Finding and loading the shared library
# ---------------------------------------------------------------------------

PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))


def _checkout_build_dir():
    """The source checkout's build/ when this package is the checkout's
    bindings/python/aqs (not an installed copy), else None."""
    root = os.path.normpath(os.path.join(PACKAGE_DIR, "..", "..", ".."))
    if not (os.path.isfile(os.path.join(root, "include", "aqs.h"))
            and os.path.isfile(os.path.join(root, "bindings", "python", "pyproject.toml"))):
        return None
    return os.path.join(root, "build")


def _candidates():
    """Paths to try, in order, with a label saying where each came from:
    AQS_LIBRARY alone when set; else the libaqs.so* inside the package, the
    source checkout's build/, the system's (ctypes.util.find_library)."""
    env = os.environ.get("AQS_LIBRARY")
    if env:
        # An explicit choice is final: never fall back to another library. A
        # bare file name (libaqs.so.0) is looked up by the dynamic loader.
        return [("AQS_LIBRARY", env)]
    found = []
    # Installed with the package: the soname first (what the build writes).
    shipped = sorted(glob.glob(os.path.join(PACKAGE_DIR, "libaqs.so*")),
                     key=lambda p: (os.path.basename(p) != "libaqs.so.%d" % VERSION_MAJOR, p))
    found += [("package directory", p) for p in shipped]
    build = _checkout_build_dir()
    if build is not None:
        for pattern in ("libaqs.so", "libaqs.so.%d" % VERSION_MAJOR,
                        "libaqs.so.%d.*" % VERSION_MAJOR):
            found += [("source checkout build/", p)
                      for p in sorted(glob.glob(os.path.join(build, pattern)))]
    system = ctypes.util.find_library("aqs")
    if system:
        found.append(("ctypes.util.find_library('aqs')", system))
    return found


def _load():
    tried = []
    candidates = _candidates()
    for origin, path in candidates:
        try:
            return ctypes.CDLL(path), path
        except OSError as exc:
            if origin == "AQS_LIBRARY":
                raise ImportError("aqs: cannot load the library named by AQS_LIBRARY=%r: %s"
                                  % (path, exc)) from exc
            tried.append("%s (%s): %s" % (path, origin, exc))
    raise ImportError(
        "aqs: libaqs not found. Set AQS_LIBRARY to the path of libaqs.so, reinstall the "
        "package (pip install ./bindings/python builds libaqs.so into %s), build the source "
        "checkout (make lib), or install libaqs system-wide.%s"
        % (PACKAGE_DIR, "".join("\n  tried " + t for t in tried)))


def _declare(library, where):
    for name, (restype, argtypes) in PROTOTYPES.items():
        try:
            function = getattr(library, name)
        except AttributeError as exc:
            raise ImportError("aqs: the loaded library %s lacks %s" % (where, name)) from exc
        function.restype = restype
        function.argtypes = argtypes


def check_major(version_number, where):
    """Raise ImportError unless version_number (MAJOR*10000+...) has our MAJOR."""
    major = version_number // 10000
    if major != VERSION_MAJOR:
        raise ImportError(
            "aqs: the library %s has version %d.%d.%d (major %d) but these bindings need "
            "major %d; install matching bindings or point AQS_LIBRARY at a matching libaqs"
            % (where, major, version_number // 100 % 100, version_number % 100, major,
               VERSION_MAJOR))


def _open():
    library, where = _load()
    # The version first, so that a library of another major is reported as
    # such rather than as missing some function.
    version = getattr(library, "aqs_version", None)
    if version is None:
        raise ImportError("aqs: %s is not libaqs (no aqs_version)" % where)
    version.restype, version.argtypes = PROTOTYPES["aqs_version"]
    check_major(version(), where)
    _declare(library, where)
    return library, where


lib, path = _open()
