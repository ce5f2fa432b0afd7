"""aqs -- Python ctypes bindings of libaqs (quasi-statics of articulated linkages).

A thin, one-to-one mirror of the C API in include/aqs.h: every method calls
one C function, a non-OK aqs_status raises an aqs.Error subclass carrying the
library's last-error text, and arrays go in and out as numpy float64
C-contiguous arrays passed to C without copies.

Conventions (those of aqs.h): units are the caller's, consistent (SI
suggested: kg, m, s, N, N m); spatial vectors are 6-vectors, angular part
first ([omega; v] for motion, [n; f] for force); quaternions are (w, x, y, z);
bodies and joints are int indices in the order they were added; aqs.WORLD (-1)
is the fixed world.

>>> import numpy as np
>>> import aqs
>>> with aqs.Linkage() as L:                 # a 2 kg rod on a revolute joint about z
...     b = L.add_body(2.0, com=(0.5, 0, 0), inertia=np.diag([0.01, 0.1, 0.1]))
...     j = L.add_joint("revolute", aqs.WORLD, b, axis=(0, 0, 1))
...     L.finalize()
...     L.set_gravity((0, -9.81, 0))
...     stats = L.solve()                    # exact by default
...     print(L.accelerations().round(4), stats.computed_joints)
...     L.set_tolerance("rel_joint", 1e-6)   # error-bounded adaptive solving
...     print(L.solve().error_bound)
[-16.35] 1
0.0

Arguments are taken strictly: arrays must hold real numbers (int or float,
any numpy integer or float dtype; converted to float64, not copied when they
already are float64 C-contiguous) in exactly the documented shape, numbers
are int, float or numpy scalars, indices are ints. Anything else raises
TypeError (wrong type: a string, a bool where a number is expected, complex)
or aqs.SizeError (wrong shape), naming the argument, before any C call:

>>> with aqs.Linkage() as L:
...     L.add_body(1.0, com=(0.5, 0), inertia=np.eye(3))
Traceback (most recent call last):
...
aqs.SizeError: aqs_body_add: com has shape (2,), expected (3,) [AQS_ESIZE]
>>> with aqs.Linkage() as L:
...     L.add_body("1.0", com=(0.5, 0, 0), inertia=np.eye(3))
Traceback (most recent call last):
...
TypeError: aqs_body_add: mass must be a real number (int, float or numpy scalar), got '1.0' (str)

Bulk getters take an optional out= array, filled in place: it must be a
writable C-contiguous float64 numpy array of exactly the result's shape.

Threads: every Linkage method holds that linkage's lock (see Linkage), and
the C calls run without the GIL.

The shared library is found, in order, through: AQS_LIBRARY (a path, or a
file name such as libaqs.so.0 that the dynamic loader looks up in the system
paths), the libaqs.so.* installed inside this package (a wheel or
`pip install ./bindings/python` builds one from the C sources), the source
checkout's build/ (when this package is the checkout's bindings/python),
and the system (ctypes.util.find_library("aqs")); aqs.library_path says
which was loaded.
"""

import collections
import ctypes
import dataclasses
import functools
import math
import numbers
import operator
import threading

import numpy as np

from . import _lib
from ._errors import (Error, InvalidArgument, ModelError, NumericError, OutOfMemoryError,
                      RangeError, SizeError, StateError)
from ._lib import (EINVAL, EMODEL, ENOMEM, ENUMERIC, ERANGE, ESIZE, ESTATE, JOINT_CYLINDRICAL,
                   JOINT_FIXED, JOINT_FREE, JOINT_KINDS, JOINT_PLANAR, JOINT_PRISMATIC,
                   JOINT_REVOLUTE, JOINT_SPHERICAL, JOINT_UNIVERSAL, JOINT_BOUND_HEAP_TOP,
                   JOINT_BOUND_SUM, JOINT_BOUNDS, TREE_BISECTION, TREE_BUILDERS,
                   EXACT_ABA, EXACT_DCA, EXACT_SOLVERS, EXACT_SOLVER_NAMES, FALLBACK_RUN, PREDICTION_MARGIN, REFINEMENT_MAX,
                   ROUNDING_FALLBACK_LEVEL, ADAPTIVE_REFINEMENT_LEVEL,
                   PATH_ADAPTIVE, PATH_EXACT_ABA, PATH_EXACT_DCA,
                   DCA_FORM_SQRT, DCA_FORM_PHI, DCA_FORMS, DCA_FORM_NAMES,
                   TREE_CONTRACTION, METRIC_ABS_JOINT, METRIC_ABS_LINKAGE, METRIC_REL_JOINT, METRIC_REL_LINKAGE,
                   METRIC_ABS_WORLD, METRIC_REL_WORLD, METRICS, OK, WORLD)
from ._lib import (SHAPE_SPHERE, SHAPE_CAPSULE, SHAPE_BOX, SHAPE_CYLINDER, SHAPE_HULL, SHAPES,
                   COLLIDE_LAZY, COLLIDE_FULL, COLLIDE_BRUTE, COLLIDE_MODES)
from ._lib import URDF_ROOT_FIXED, URDF_ROOT_FREE
from ._errors import from_status as _from_status

__all__ = [
    "Linkage", "version", "version_number", "status_string", "library_path",
    "Error", "InvalidArgument", "RangeError", "StateError", "OutOfMemoryError", "ModelError",
    "NumericError", "SizeError", "Sizes", "JointLayout", "SolveStats",
    "WORLD", "OK", "EINVAL", "ERANGE", "ESTATE", "ENOMEM", "EMODEL", "ENUMERIC", "ESIZE",
    "JOINT_REVOLUTE", "JOINT_PRISMATIC", "JOINT_SPHERICAL", "JOINT_FREE", "JOINT_FIXED",
    "JOINT_UNIVERSAL", "JOINT_CYLINDRICAL", "JOINT_PLANAR", "JOINT_KINDS",
    "METRIC_ABS_LINKAGE", "METRIC_REL_LINKAGE", "METRIC_ABS_JOINT", "METRIC_REL_JOINT",
    "METRIC_ABS_WORLD", "METRIC_REL_WORLD", "METRICS",
    "JOINT_BOUND_HEAP_TOP", "JOINT_BOUND_SUM", "JOINT_BOUNDS",
    "TREE_CONTRACTION", "TREE_BISECTION", "TREE_BUILDERS",
    "EXACT_ABA", "EXACT_DCA", "EXACT_SOLVERS", "FALLBACK_RUN", "PREDICTION_MARGIN", "REFINEMENT_MAX",
    "ROUNDING_FALLBACK_LEVEL", "ADAPTIVE_REFINEMENT_LEVEL",
    "PATH_ADAPTIVE", "PATH_EXACT_ABA", "PATH_EXACT_DCA",
    "DCA_FORM_SQRT", "DCA_FORM_PHI", "DCA_FORMS",
    "SHAPE_SPHERE", "SHAPE_CAPSULE", "SHAPE_BOX", "SHAPE_CYLINDER", "SHAPE_HULL", "SHAPES",
    "COLLIDE_LAZY", "COLLIDE_FULL", "COLLIDE_BRUTE", "COLLIDE_MODES", "CONTACT_DTYPE",
    "CollisionStats", "MemoryStats",
    "BodyInertial", "JointDefinition", "load_urdf", "save_urdf", "URDFError",
    "URDFWarning", "JointLimits", "URDF_ROOT_FIXED", "URDF_ROOT_FREE",
]

__version__ = "0.1.0"

_c = _lib.lib
#: Path of the loaded shared library.
library_path = _lib.path

_INT32_MIN = -(2 ** 31)
_INT32_MAX = 2 ** 31 - 1
_F64 = np.float64

#: numpy dtype of the contacts returned by Linkage.collide (the layout of struct aqs_contact).
CONTACT_DTYPE = np.dtype([(name, np.int32 if ctype is ctypes.c_int32 else np.float64)
                          for name, ctype in _lib.aqs_contact._fields_])
assert CONTACT_DTYPE.itemsize == ctypes.sizeof(_lib.aqs_contact)
CollisionStats = collections.namedtuple("CollisionStats", [name for name, _ in
                                                          _lib.aqs_collision_stats._fields_[1:]])
CollisionStats.__doc__ = "Work of the last collision query (aqs_linkage_get_query_stats)."
MemoryStats = collections.namedtuple("MemoryStats", [name for name, _ in
                                                    _lib.aqs_memory_stats._fields_[1:]])
MemoryStats.__doc__ = ("Memory held by a linkage, bytes (aqs_linkage_get_memory): blocks, bytes, "
                       "peak, and bytes by category.")

Sizes = collections.namedtuple("Sizes", "bodies joints nq nv")
Sizes.__doc__ = "Counts of a linkage: bodies, joints, nq (position values), nv (accelerations)."
JointLayout = collections.namedtuple("JointLayout", "q_offset nq v_offset nv")
JointLayout.__doc__ = ("Where a joint's values sit in the bulk arrays: q_offset/nq in "
                       "positions(), v_offset/nv in accelerations() and joint forces.")

JointLimits = collections.namedtuple("JointLimits", "lower upper effort velocity")
JointLimits.__doc__ = ("A joint's limits (Linkage.joint_limits): lower, upper (m or rad; "
                       "-inf / inf: none), effort (N or N m), velocity (m/s or rad/s; inf: "
                       "none). Kept, not enforced by the solvers.")

BodyInertial = collections.namedtuple("BodyInertial", "mass com inertia")
BodyInertial.__doc__ = ("A body's mass properties as added (Linkage.body_inertial): mass (kg), "
                        "com (3) body frame (m), inertia (3, 3) about the com, body frame "
                        "(kg m^2), symmetrized.")
JointDefinition = collections.namedtuple("JointDefinition", "kind parent child pos quat axis")
JointDefinition.__doc__ = ("A joint as added (Linkage.joint_definition): kind (name such as "
                           "\"revolute\"), parent (body or WORLD), child, pos (3), quat (4, w x y z, "
                           "normalized), axis (3, normalized; (0, 0, 1) where ignored).")
_KIND_NAMES = {value: name for name, value in JOINT_KINDS.items()}


@dataclasses.dataclass(frozen=True)
class SolveStats:
    """Statistics of the last solve (aqs_solve_stats), as returned by
    Linkage.solve(), step(), refine() and stats().

    metric: the error measure in force, "abs_linkage", "rel_linkage",
        "abs_joint" or "rel_joint" (see Linkage.set_tolerance).
    eps: the bound asked for (0.0 = exact), in the measure's unit: m/s^2 or
        rad/s^2 (as the accelerations) for the absolute measures, a pure
        number for the relative ones.
    error_bound: certified upper bound on that measure for this solve (0.0
        when every joint was computed), same unit as eps; <= eps unless the
        solve was capped.
    computed_joints: joint accelerations computed (N_E; free joints excluded).
    counted_joints: joints the measures count: every joint but free ones and
        fixed ones (which have no acceleration).
    nodes_updated: assembly-tree nodes recomputed by the last solve (after
        step(): by the update before its solve plus the one after the move).
    nodes_processed: internal tree nodes back-substituted by the solve.
    capped: True if the solve stopped at the set_max_computed cap.
    fallback: True if the solve was exact because of set_exact_fallback.
    nodes_predicted: internal nodes the solve processed without evaluating
        their total acceleration (set_prediction).
    factors_updated: total-acceleration factors recomputed, counted as
        nodes_updated (the prediction skips some).
    path: the path the solve ran: "adaptive", "exact_aba" (articulated-body
        algorithm) or "exact_dca" (aqs.PATH_*; see set_auto).
    auto_chosen: True if the automatic path (set_auto) chose it.
    cost_adaptive, cost_exact: the automatic path's predicted costs of the
        two paths, in instructions (0.0 when it did not choose).
    rounding_bound: an estimate with a safety factor of what the
        divide-and-conquer solver's rounding adds to the measure, same unit as
        eps: against the true solution, the measure is at most error_bound +
        rounding_bound when certified. inf when no bound can be given.
    certified: True if error_bound + rounding_bound bounds the measure against
        the true solution and rounding_bound <= eps (eps > 0); False where no
        honest bound can be given: the rounding exceeds eps, a near-singular
        pivot, the "phi" DCA form, or an exact solve by the articulated-body
        algorithm (which does not estimate its rounding).
    rounding_fallback: True if the solve was exact because of
        set_rounding_fallback.
    """

    metric: str
    eps: float
    error_bound: float
    computed_joints: int
    counted_joints: int
    nodes_updated: int
    nodes_processed: int
    capped: bool
    fallback: bool = False
    nodes_predicted: int = 0
    factors_updated: int = 0
    path: str = "adaptive"
    auto_chosen: bool = False
    cost_adaptive: float = 0.0
    cost_exact: float = 0.0
    rounding_bound: float = 0.0
    certified: bool = False
    rounding_fallback: bool = False

    @classmethod
    def _from_c(cls, c):
        return cls(metric=_lib.METRIC_NAMES.get(c.metric, str(c.metric)), eps=float(c.eps),
                   error_bound=float(c.error_bound), computed_joints=int(c.computed_joints),
                   counted_joints=int(c.counted_joints), nodes_updated=int(c.nodes_updated),
                   nodes_processed=int(c.nodes_processed), capped=bool(c.capped),
                   fallback=bool(c.fallback), nodes_predicted=int(c.nodes_predicted),
                   factors_updated=int(c.factors_updated),
                   path=_lib.PATH_NAMES.get(c.path, str(c.path)), auto_chosen=bool(c.auto_chosen),
                   cost_adaptive=float(c.cost_adaptive), cost_exact=float(c.cost_exact),
                   rounding_bound=float(c.rounding_bound), certified=bool(c.certified),
                   rounding_fallback=bool(c.rounding_fallback))


def version():
    """Version of the loaded libaqs as "MAJOR.MINOR.PATCH" (aqs_version_string)."""
    return _c.aqs_version_string().decode()


def version_number():
    """Version of the loaded libaqs as MAJOR*10000 + MINOR*100 + PATCH (aqs_version)."""
    return _c.aqs_version()


def status_string(status):
    """The library's fixed text for a status code (aqs_status_string)."""
    return _c.aqs_status_string(_index(status, "aqs_status_string", "status")).decode()


# ---------------------------------------------------------------------------
# Argument conversion: only what ctypes needs to call C safely, and strictly.
# Values are checked by the C library; what C cannot see is checked here: the
# type of every argument (no string, bool or complex is turned into a number)
# and the shape of every array (C would read past the end of a short com[3]).
# ---------------------------------------------------------------------------

_REAL_KINDS = "iuf"  # numpy dtype kinds taken as real numbers: signed, unsigned, float
_BOOLS = (bool, np.bool_)
_BOOL_TYPES = frozenset(_BOOLS)


def _shape_text(shape):
    return "(%s)" % ", ".join("n" if d < 0 else str(d) for d in shape) if len(shape) != 1 \
        else "(%s,)" % ("n" if shape[0] < 0 else shape[0])


def _shape_fits(shape, pattern):
    return len(shape) == len(pattern) and all(p < 0 or p == d for d, p in zip(shape, pattern))


def _holds_bool(values, ndim):
    """True when (nested) sequences, which numpy made an ndim-dimensional
    array, hold a bool among their numbers: numpy takes it as 0 or 1
    (np.asarray([0, 0, True]) is an int array)."""
    if ndim == 1 and isinstance(values, (list, tuple)):
        flat = values  # a flat sequence (the common case): scanned as it is
    else:
        try:
            flat = np.asarray(values, dtype=object).flat
        except (TypeError, ValueError):
            return False
    return not _BOOL_TYPES.isdisjoint(map(type, flat))  # (set.isdisjoint, map: loops in C)


def _array(values, function, name, shapes=((-1,),)):
    """values as a float64 C-contiguous array: the same object when it already
    is one, else a converted copy of the same values.

    values must hold real numbers (a numpy array of an integer or float
    dtype, or nested sequences of int/float): TypeError otherwise (strings,
    bools, complex numbers, None, objects). Its shape must be one of shapes
    (-1: any length in that dimension): SizeError otherwise. An int n stands
    for the shape (n,).
    """
    if isinstance(shapes, int):
        shapes = ((shapes,),)
    if isinstance(values, (str, bytes)):
        raise TypeError("%s: %s must be an array of real numbers, got the string %r"
                        % (function, name, values))
    try:
        array = np.asarray(values)
    except (TypeError, ValueError) as exc:  # ragged nested sequences, odd objects
        raise SizeError("%s: %s is not a rectangular array of numbers (%s)"
                        % (function, name, exc)) from None
    if array.dtype.kind == "O" and array.size and all(
            isinstance(v, numbers.Integral) and not isinstance(v, _BOOLS) for v in array.flat):
        # Python ints beyond 64 bits (10**20): numpy keeps them as objects;
        # they are real numbers, converted as float() would (an int too large
        # for a double raises OverflowError, not a silent inf)
        try:
            array = np.array([float(v) for v in array.flat], dtype=_F64).reshape(array.shape)
        except OverflowError:
            raise InvalidArgument("%s: %s holds an integer too large for a double"
                                  % (function, name)) from None
    if array.dtype.kind not in _REAL_KINDS:
        raise TypeError("%s: %s must be an array of real numbers (int or float), got dtype %s"
                        % (function, name, array.dtype))
    if not isinstance(values, np.ndarray) and _holds_bool(values, array.ndim):
        raise TypeError("%s: %s must be an array of real numbers (int or float), got a bool in it"
                        % (function, name))
    if not any(_shape_fits(array.shape, shape) for shape in shapes):
        raise SizeError("%s: %s has shape %s, expected %s"
                        % (function, name, _shape_text(array.shape),
                           " or ".join(_shape_text(shape) for shape in shapes)))
    return np.ascontiguousarray(array, dtype=_F64)


def _array_or_null(values, function, name, shapes=((-1,),)):
    return None if values is None else _array(values, function, name, shapes)


def _nonempty(array):
    """NULL for an empty array (C's "n = 0 and NULL"), else the array."""
    return array if array.size else None


def _number(value, function, name):
    """value as a float: an int, a float, a numpy integer or float scalar (or a
    0-d array of one). TypeError for anything else -- strings ("0.1"), bools,
    complex numbers, None -- rather than a silent conversion."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in _REAL_KINDS:
        value = value[()]
    if isinstance(value, _BOOLS) or not isinstance(value, numbers.Real):
        raise TypeError("%s: %s must be a real number (int, float or numpy scalar), got %r (%s)"
                        % (function, name, value, type(value).__name__))
    try:
        return float(value)
    except OverflowError:
        raise InvalidArgument("%s: %s = %r does not fit in a double" % (function, name, value)) \
            from None


def _index(value, function, name, low=_INT32_MIN, high=_INT32_MAX, ctype="int32_t"):
    """value as an int (int or numpy integer; not a bool, float or string)."""
    try:
        if isinstance(value, _BOOLS):
            raise TypeError
        index = operator.index(value)
    except TypeError:
        raise TypeError("%s: %s must be an integer, got %r (%s)"
                        % (function, name, value, type(value).__name__)) from None
    if not low <= index <= high:
        raise RangeError("%s: %s = %d does not fit in %s" % (function, name, index, ctype))
    return index


def _flag(value, function, name):
    """value as C's 0 or 1: True/False (also numpy's), or the integers 0 and 1."""
    if isinstance(value, _BOOLS):
        return 1 if value else 0
    flag = _index(value, function, name)
    if flag not in (0, 1):
        raise InvalidArgument("%s: %s = %d is not a boolean (True/False or 1/0)"
                              % (function, name, flag))
    return flag


def _output(out, shape, function):
    """A fresh array to be filled by C, or the caller's out, which must be a
    writable C-contiguous float64 numpy array of exactly that shape (TypeError,
    SizeError otherwise: never a silent copy or another layout)."""
    shape = (shape,) if isinstance(shape, int) else tuple(shape)
    if out is None:
        return np.empty(shape, dtype=_F64)
    if not isinstance(out, np.ndarray):
        raise TypeError("%s: out must be a numpy array, got %s" % (function, type(out).__name__))
    if out.dtype != _F64:
        raise TypeError("%s: out must have dtype float64, got %s" % (function, out.dtype))
    if not out.flags.c_contiguous:
        raise TypeError("%s: out must be C-contiguous" % function)
    if not out.flags.writeable:
        raise TypeError("%s: out must be writable" % function)
    if out.shape != shape:
        raise SizeError("%s: out has shape %s, expected %s"
                        % (function, _shape_text(out.shape), _shape_text(shape)))
    return out


def _joint_kind(kind):
    if isinstance(kind, str):
        try:
            return JOINT_KINDS[kind.lower()]
        except KeyError:
            raise InvalidArgument("aqs_joint_add: type = %r is not one of %s"
                                  % (kind, ", ".join(sorted(JOINT_KINDS)))) from None
    return _index(kind, "aqs_joint_add", "type")


def _named(value, names, function, name):
    """A constant given by its name in names (case-insensitive) or as an int."""
    if isinstance(value, str):
        try:
            return names[value.lower()]
        except KeyError:
            raise InvalidArgument("%s: %s = %r is not one of %s"
                                  % (function, name, value, ", ".join(sorted(names)))) from None
    return _index(value, function, name)


class _FairLock:
    """A reentrant lock handed to its waiters in the order they came (FIFO).

    threading.RLock is not fair: a thread that releases it and asks again at
    once (a loop of step() calls, whose C call releases the GIL) takes it
    back ahead of a thread already waiting, which then waits for the whole
    loop, not for one call. Here release() hands the lock to the oldest
    waiter directly. Uncontended, acquire and release take one short
    critical section each."""

    __slots__ = ("_mutex", "_owner", "_count", "_waiters")
    _HANDOFF = object()  # owner while the lock passes to a waiter

    def __init__(self):
        self._mutex = threading.Lock()
        self._owner = None
        self._count = 0
        self._waiters = collections.deque()

    def acquire(self):
        me = threading.get_ident()
        if self._owner == me:  # only this thread sets it to its own id
            self._count += 1
            return True
        with self._mutex:
            if self._owner is None:
                self._owner, self._count = me, 1
                return True
            gate = threading.Lock()
            gate.acquire()
            self._waiters.append(gate)
        try:
            gate.acquire()  # released by the owner that hands the lock over
        except BaseException:  # interrupted while waiting (KeyboardInterrupt)
            with self._mutex:
                try:
                    self._waiters.remove(gate)
                    handed = False
                except ValueError:
                    handed = True  # the lock came to this thread meanwhile
            if handed:
                self._owner, self._count = me, 1
                self.release()
            raise
        self._owner, self._count = me, 1
        return True

    def release(self):
        if self._owner != threading.get_ident():
            raise RuntimeError("cannot release an aqs linkage lock this thread does not hold")
        self._count -= 1
        if self._count:
            return
        with self._mutex:
            if self._waiters:
                self._owner = self._HANDOFF
                self._waiters.popleft().release()
            else:
                self._owner = None

    __enter__ = acquire

    def __exit__(self, *exc_info):
        self.release()


class Linkage:
    """An articulated linkage: owns one aqs_linkage handle.

    Build it (add_body, add_joint), finalize() it, set loads, then solve() or
    step() (both return SolveStats); set_tolerance / set_max_computed make
    the solves error-bounded and adaptive, refine() tightens one. close()
    releases the handle (also on `with` exit and on garbage collection);
    closing twice is fine; any other call on a closed linkage raises
    StateError.

    Threads: each Linkage has its own lock (reentrant, and fair: waiting
    calls get it in the order they came) that every method holds while it
    runs, close() included, so calls from several threads on one linkage run
    one after the other (a close() during another thread's step() waits for
    that step, not for the thread's later ones, which then raise StateError),
    and calls on different
    linkages run in parallel: the C calls release the GIL. A Linkage cannot
    be copied or pickled (TypeError): it owns its C handle.

    >>> import numpy as np
    >>> L = Linkage()
    >>> b = L.add_body(2.0, com=(0.5, 0, 0), inertia=np.diag([0.01, 0.1, 0.1]))
    >>> L.add_joint("revolute", WORLD, b, axis=(0, 0, 1))
    0
    >>> L.finalize()
    >>> L.set_gravity((0, -9.81, 0))
    >>> L.solve().computed_joints
    1
    >>> round(float(L.accelerations()[0]), 4)   # -9.81 * 0.5 * 2 / (0.1 + 2 * 0.5**2)
    -16.35
    >>> L.close()
    >>> L.solve()
    Traceback (most recent call last):
    ...
    aqs.StateError: aqs_linkage_solve: the linkage is closed [AQS_ESTATE]
    """

    def __init__(self):
        """Create an empty linkage using malloc/free (aqs_linkage_create)."""
        self._lock = _FairLock()
        self._in_c = False
        self._handle = None
        self._callbacks = None
        handle = _lib.linkage_p()
        status = _c.aqs_linkage_create(ctypes.byref(handle))
        if status != OK:
            raise _from_status(status, "aqs_linkage_create: " + status_string(status))
        self._handle = handle

    @classmethod
    def with_allocator(cls, alloc, free):
        """Create an empty linkage whose memory all comes from alloc/free
        (aqs_linkage_create_with_allocator).

        alloc(size) returns the address (int) of size bytes aligned for any C
        type, or 0/None on failure; free(address) releases it. Both are kept
        alive as long as the linkage. They run in the thread that called the
        method and must not call this linkage's methods (those raise
        StateError there, so alloc reports a failed allocation).
        """
        self = cls.__new__(cls)
        self._lock = _FairLock()
        self._in_c = False
        self._handle = None

        def c_alloc(user, size):
            try:
                return alloc(size) or None
            except Exception:  # an exception cannot cross C: report failure
                return None

        def c_free(user, ptr):
            free(ptr)

        self._callbacks = (_lib.alloc_fn(c_alloc), _lib.free_fn(c_free))
        handle = _lib.linkage_p()
        status = _c.aqs_linkage_create_with_allocator(self._callbacks[0], self._callbacks[1],
                                                      None, ctypes.byref(handle))
        if status != OK:
            raise _from_status(status, "aqs_linkage_create_with_allocator: "
                               + status_string(status))
        self._handle = handle
        return self

    # -- lifetime ------------------------------------------------------------

    def close(self):
        """Destroy the linkage and release its memory (aqs_linkage_destroy).
        Idempotent; waits for a call running in another thread to finish."""
        with self._lock:
            if self._handle is None:
                return
            handle = self._enter("aqs_linkage_destroy")
            self._handle = None
            try:
                _c.aqs_linkage_destroy(handle)
            finally:
                self._in_c = False
                self._callbacks = None  # only after destroy, which may still call free

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    def __del__(self):
        if getattr(self, "_handle", None) is not None and _c is not None:
            self.close()

    def __reduce__(self):
        # copy.copy would share the C handle (destroyed twice); pickle cannot carry it.
        raise TypeError("an aqs.Linkage owns a C handle: it cannot be copied or pickled")

    @property
    def closed(self):
        """True once close() has been called."""
        return self._handle is None

    def __repr__(self):
        if self._handle is None:
            return "<aqs.Linkage closed>"
        s = self.sizes()
        return "<aqs.Linkage bodies=%d joints=%d nq=%d nv=%d>" % s

    # -- plumbing --------------------------------------------------------------

    def _enter(self, function):
        """The handle, for a C call about to be made with self._lock held;
        sets self._in_c, which the caller clears once the call returned.
        StateError on a closed linkage, and for a call made from inside
        another C call on this linkage (an allocator callback)."""
        handle = self._handle
        if handle is None:
            raise StateError("%s: the linkage is closed" % function)
        if self._in_c:
            raise StateError("%s: called from inside a C call on the same linkage (an "
                             "allocator callback may not use its linkage)" % function)
        self._in_c = True
        return handle

    def _call(self, function, *args):
        """Call the C function named function with the handle first, holding the
        lock; raise the status's exception on failure."""
        with self._lock:
            handle = self._enter(function)
            try:
                status = getattr(_c, function)(handle, *args)
                if status != OK:
                    message = _c.aqs_linkage_last_error(handle).decode(errors="replace")
            finally:
                self._in_c = False
        if status != OK:
            raise _from_status(status, message or "%s: %s" % (function, status_string(status)))

    @property
    def last_error(self):
        """Message of the last failed C call on this linkage ("" if none)."""
        with self._lock:
            handle = self._enter("aqs_linkage_last_error")
            try:
                return _c.aqs_linkage_last_error(handle).decode(errors="replace")
            finally:
                self._in_c = False

    # -- building --------------------------------------------------------------

    def set_tree_builder(self, builder):
        """How finalize builds the assembly tree (aqs_linkage_set_tree_builder):
        "contraction" (default: rake and compress, handles bounded by the
        largest body degree) or "bisection" (recursive bisection), or an
        aqs.TREE_* constant. Building phase only."""
        f = "aqs_linkage_set_tree_builder"
        self._call(f, _named(builder, TREE_BUILDERS, f, "builder"))

    def set_inertia_check(self, physical):
        """Whether add_body requires physically realizable inertias (principal
        moments obeying I1 + I2 >= I3): True (the default) or False (any
        symmetric positive definite inertia, e.g. synthetic test models).
        Building phase only (aqs_linkage_set_inertia_check)."""
        f = "aqs_linkage_set_inertia_check"
        self._call(f, _flag(physical, f, "physical"))

    def add_body(self, mass, com, inertia):
        """Add a rigid body; returns its index (aqs_body_add).

        mass: kg, >= 0 (0 only if welded by fixed joints to a massive body).
        com: (3) centre of mass in the body frame, m.
        inertia: (3, 3) or (9) row-major, about the centre of mass, body frame,
        kg m^2, symmetric positive definite.
        """
        f = "aqs_body_add"
        mass = _number(mass, f, "mass")
        com = _array(com, f, "com", 3)
        inertia = _array(inertia, f, "inertia", ((3, 3), (9,)))
        out = ctypes.c_int32()
        self._call(f, mass, com, inertia, ctypes.byref(out))
        return out.value

    def add_joint(self, kind, parent, child, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0),
                  axis=(0.0, 0.0, 1.0)):
        """Add a joint from parent (body index or aqs.WORLD) to child; returns its index
        (aqs_joint_add).

        kind: "revolute", "prismatic", "spherical", "free", "fixed",
        "universal", "cylindrical", "planar", or an aqs.JOINT_* constant.
        pos: (3) joint frame origin in the parent body frame (world frame for
        WORLD), m. quat: (4, w x y z) joint frame orientation in the parent
        frame. axis: (3) joint axis in the joint frame (None for spherical,
        free and fixed joints, which ignore it). The child body frame is the
        joint frame moved by the joint position.
        """
        f = "aqs_joint_add"
        kind = _joint_kind(kind)
        parent = _index(parent, f, "parent")
        child = _index(child, f, "child")
        pos = _array(pos, f, "pos", 3)
        quat = _array(quat, f, "quat", 4)
        axis = _array_or_null(axis, f, "axis", 3)
        out = ctypes.c_int32()
        self._call(f, kind, parent, child, pos, quat, axis, ctypes.byref(out))
        return out.value

    def finalize(self):
        """Validate the linkage and build its assembly tree (aqs_linkage_finalize).
        Raises ModelError naming the first problem; the linkage then stays editable."""
        self._call("aqs_linkage_finalize")

    def sizes(self):
        """Sizes(bodies, joints, nq, nv) (aqs_linkage_get_sizes); any phase."""
        b, j, nq, nv = (ctypes.c_int32() for _ in range(4))
        self._call("aqs_linkage_get_sizes", ctypes.byref(b), ctypes.byref(j), ctypes.byref(nq),
                   ctypes.byref(nv))
        return Sizes(b.value, j.value, nq.value, nv.value)

    @property
    def num_bodies(self):
        """Number of bodies added."""
        return self.sizes().bodies

    @property
    def num_joints(self):
        """Number of joints added."""
        return self.sizes().joints

    @property
    def nq(self):
        """Number of position values (length of positions())."""
        return self.sizes().nq

    @property
    def nv(self):
        """Number of acceleration values (length of accelerations())."""
        return self.sizes().nv

    def joint_layout(self, joint):
        """JointLayout(q_offset, nq, v_offset, nv) of a joint (aqs_joint_get_layout)."""
        f = "aqs_joint_get_layout"
        qo, nq, vo, nv = (ctypes.c_int32() for _ in range(4))
        self._call(f, _index(joint, f, "joint"), ctypes.byref(qo), ctypes.byref(nq),
                   ctypes.byref(vo), ctypes.byref(nv))
        return JointLayout(qo.value, nq.value, vo.value, nv.value)

    def _layout_for(self, joint, function):
        """joint_layout(joint) for a method about to call function: a bad
        index raises the error under function's name, the call the user made."""
        try:
            return self.joint_layout(joint)
        except Error as e:
            raise type(e)(e.message.replace("aqs_joint_get_layout", function, 1)) from None

    def tree_stats(self):
        """Assembly tree statistics after finalize (aqs_linkage_get_tree_stats):
        dict(nodes, height (edges root to deepest leaf), mean_handles, max_handles)."""
        nodes, height, max_handles = (ctypes.c_int32() for _ in range(3))
        mean_handles = ctypes.c_double()
        self._call("aqs_linkage_get_tree_stats", ctypes.byref(nodes), ctypes.byref(height),
                   ctypes.byref(mean_handles), ctypes.byref(max_handles))
        return dict(nodes=nodes.value, height=height.value, mean_handles=mean_handles.value,
                    max_handles=max_handles.value)

    def memory(self):
        """Memory held by the linkage, counted through its allocator, any phase
        (aqs_linkage_get_memory): a MemoryStats (blocks, bytes held now, peak,
        and by category model, tree, exact, dca, factors, world, collision,
        which add up to bytes)."""
        m = _lib.aqs_memory_stats()
        m.size = ctypes.sizeof(m)
        self._call("aqs_linkage_get_memory", ctypes.byref(m))
        return MemoryStats(*(getattr(m, name) for name in MemoryStats._fields))

    # -- reading the model back ------------------------------------------------

    def body_inertial(self, body):
        """A body's mass properties as added, any phase (aqs_body_get_inertial):
        BodyInertial(mass kg, com (3) body frame m, inertia (3, 3) about the com,
        body frame, kg m^2 -- the symmetric part of what add_body was given)."""
        f = "aqs_body_get_inertial"
        mass = ctypes.c_double()
        com = np.empty(3, dtype=_F64)
        inertia = np.empty((3, 3), dtype=_F64)
        self._call(f, _index(body, f, "body"), ctypes.byref(mass), com, inertia)
        return BodyInertial(mass.value, com, inertia)

    def joint_definition(self, joint):
        """A joint as added, any phase (aqs_joint_get_definition):
        JointDefinition(kind name, parent (body or WORLD), child, pos (3) m in the
        parent frame, quat (4, w x y z) divided by its norm, axis (3) divided by
        its norm, (0, 0, 1) for spherical, free and fixed joints)."""
        f = "aqs_joint_get_definition"
        kind, parent, child = (ctypes.c_int32() for _ in range(3))
        pos = np.empty(3, dtype=_F64)
        quat = np.empty(4, dtype=_F64)
        axis = np.empty(3, dtype=_F64)
        self._call(f, _index(joint, f, "joint"), ctypes.byref(kind), ctypes.byref(parent),
                   ctypes.byref(child), pos, quat, axis)
        return JointDefinition(_KIND_NAMES.get(kind.value, kind.value), parent.value,
                               child.value, pos, quat, axis)

    # -- names and limits ------------------------------------------------------

    @staticmethod
    def _name_bytes(name, function):
        if not isinstance(name, str):
            raise TypeError("%s: name must be a str, got %r (%s)"
                            % (function, name, type(name).__name__))
        data = name.encode("utf-8")
        if b"\0" in data:
            raise InvalidArgument("%s: name = %r contains a NUL character" % (function, name))
        return data

    def set_body_name(self, body, name):
        """Name a body (aqs_body_set_name): a non-empty str, stored as UTF-8."""
        f = "aqs_body_set_name"
        self._call(f, _index(body, f, "body"), self._name_bytes(name, f))

    def set_joint_name(self, joint, name):
        """Name a joint (aqs_joint_set_name): a non-empty str, stored as UTF-8."""
        f = "aqs_joint_set_name"
        self._call(f, _index(joint, f, "joint"), self._name_bytes(name, f))

    def body_name(self, body):
        """A body's name ("" when unnamed; aqs_body_get_name)."""
        f = "aqs_body_get_name"
        out = ctypes.c_char_p()
        self._call(f, _index(body, f, "body"), ctypes.byref(out))
        return out.value.decode("utf-8", errors="replace")

    def joint_name(self, joint):
        """A joint's name ("" when unnamed; aqs_joint_get_name)."""
        f = "aqs_joint_get_name"
        out = ctypes.c_char_p()
        self._call(f, _index(joint, f, "joint"), ctypes.byref(out))
        return out.value.decode("utf-8", errors="replace")

    def find_body(self, name):
        """The lowest-numbered body named name (aqs_body_find); RangeError if none."""
        f = "aqs_body_find"
        out = ctypes.c_int32()
        self._call(f, self._name_bytes(name, f), ctypes.byref(out))
        return out.value

    def find_joint(self, name):
        """The lowest-numbered joint named name (aqs_joint_find); RangeError if none."""
        f = "aqs_joint_find"
        out = ctypes.c_int32()
        self._call(f, self._name_bytes(name, f), ctypes.byref(out))
        return out.value

    @property
    def body_names(self):
        """Every body's name, in body order ("" for unnamed bodies). Assign a
        list of one name per body to name them all."""
        return [self.body_name(b) for b in range(self.num_bodies)]

    @body_names.setter
    def body_names(self, names):
        names = list(names)
        if len(names) != self.num_bodies:
            raise SizeError("body_names: %d names for %d bodies" % (len(names), self.num_bodies))
        for b, name in enumerate(names):
            self.set_body_name(b, name)

    @property
    def joint_names(self):
        """Every joint's name, in joint order ("" for unnamed joints). Assign a
        list of one name per joint to name them all."""
        return [self.joint_name(j) for j in range(self.num_joints)]

    @joint_names.setter
    def joint_names(self, names):
        names = list(names)
        if len(names) != self.num_joints:
            raise SizeError("joint_names: %d names for %d joints" % (len(names), self.num_joints))
        for j, name in enumerate(names):
            self.set_joint_name(j, name)

    def set_joint_limits(self, joint, lower=-math.inf, upper=math.inf, effort=math.inf,
                         velocity=math.inf):
        """Keep a joint's limits (aqs_joint_set_limits). Not enforced by the
        solvers: quasi-statics moves past them. lower <= upper (m or rad),
        effort, velocity >= 0; infinities mean none."""
        f = "aqs_joint_set_limits"
        values = [_number(v, f, label) for label, v in
                  (("lower", lower), ("upper", upper), ("effort", effort),
                   ("velocity", velocity))]
        self._call(f, _index(joint, f, "joint"), *values)

    def joint_limits(self, joint):
        """JointLimits(lower, upper, effort, velocity) of a joint (aqs_joint_get_limits)."""
        f = "aqs_joint_get_limits"
        out = [ctypes.c_double() for _ in range(4)]
        self._call(f, _index(joint, f, "joint"), *(ctypes.byref(v) for v in out))
        return JointLimits(*(v.value for v in out))

    @property
    def load_warnings(self):
        """What the URDF load of this linkage read but does not model, one
        entry per kind (aqs_linkage_load_warnings); [] when nothing."""
        with self._lock:
            handle = self._enter("aqs_linkage_load_warnings")
            try:
                text = _c.aqs_linkage_load_warnings(handle).decode("utf-8", errors="replace")
            finally:
                self._in_c = False
        return text.split("\n") if text else []

    def save_urdf(self, path, name="aqs"):
        """Write the model (at q = 0) as URDF to path; see aqs.save_urdf."""
        from .urdf import save_urdf
        save_urdf(self, path, name=name)

    # -- loads -------------------------------------------------------------------

    def set_gravity(self, gravity):
        """Gravitational acceleration (3), world frame, m/s^2 (aqs_linkage_set_gravity)."""
        f = "aqs_linkage_set_gravity"
        self._call(f, _array(gravity, f, "gravity", 3))

    def set_body_force(self, body, force, point=None, torque=None):
        """Set a body's external load, replacing any earlier one (aqs_body_set_force).

        force: (3) world frame, N, applied at point: (3) body frame, m
        (None = the body origin). torque: (3) pure torque, world frame, N m
        (None = zero).
        """
        f = "aqs_body_set_force"
        self._call(f, _index(body, f, "body"), _array(force, f, "force", 3),
                   _array_or_null(point, f, "point", 3), _array_or_null(torque, f, "torque", 3))

    def clear_body_force(self, body):
        """Remove a body's external load (aqs_body_clear_force)."""
        f = "aqs_body_clear_force"
        self._call(f, _index(body, f, "body"))

    def clear_forces(self):
        """Remove every body load and every joint force (aqs_linkage_clear_forces)."""
        self._call("aqs_linkage_clear_forces")

    def set_joint_force(self, joint, tau):
        """Active joint force, one value per dof (N or N m), in the layout of the
        joint's acceleration; a scalar for 1-dof joints, () for fixed joints
        (aqs_joint_set_force)."""
        f = "aqs_joint_set_force"
        joint = _index(joint, f, "joint")
        tau = _array(tau, f, "tau", ((), (-1,)))
        self._call(f, joint, _nonempty(tau), tau.size)

    # -- solving and stepping ------------------------------------------------------

    def solve(self):
        """Solve the quasi-statics at the current positions and loads
        (aqs_linkage_solve); returns its SolveStats.

        Exact by default. With a tolerance (set_tolerance) or a cap
        (set_max_computed) only the joints that matter are computed; the
        others read acceleration 0 and constraint force NaN (joint_computed).
        """
        self._call("aqs_linkage_solve")
        return self.stats()

    def step(self, dt):
        """Solve, then move every computed joint by q <- q (+) dt^2 qdd
        (aqs_linkage_step); returns the SolveStats of that solve (whose
        nodes_updated counts both of the step's coefficient updates).
        dt: s, > 0. Accelerations read afterwards are those of this step's solve."""
        f = "aqs_linkage_step"
        self._call(f, _number(dt, f, "dt"))
        return self.stats()

    # -- error-bounded adaptive solving ----------------------------------------------

    def set_tolerance(self, metric, eps):
        """Set the error measure and its bound for the next solves
        (aqs_linkage_set_tolerance). After finalize only (StateError before).

        metric: "abs_linkage" (sqrt of the sum of ||qdd_j||^2 over the joints
        not computed), "rel_linkage" (that / the same over all joints),
        "abs_joint" (max ||qdd_j|| over the joints not computed), "rel_joint"
        (that / max ||qdd_j|| over all joints), "abs_world" (max over the
        bodies of e_b = |delta a_b| + ell_b |delta alpha_b|, the error of the
        centre-of-mass and angular accelerations the uncomputed joints cause,
        ell_b = sqrt(tr(I_b) / (2 m_b))), "rel_world" (that / max_b of the
        same of the accelerations), or an aqs.METRIC_* constant.
        ||qdd_j|| is the 2-norm of joint j's acceleration vector; free joints
        are always computed exactly and not counted.
        eps: finite, >= 0; m/s^2 or rad/s^2 for the absolute measures (m/s^2
        for abs_world), a pure number for the relative ones. 0 (the default)
        means exact.
        """
        f = "aqs_linkage_set_tolerance"
        self._call(f, _named(metric, METRICS, f, "metric"), _number(eps, f, "eps"))

    def set_max_computed(self, max_joints):
        """Anytime control: stop a solve once max_joints joint accelerations are
        computed (0, the default, means no cap); the bound reached is reported
        (SolveStats.error_bound, capped=True). Joints on the path to a floating
        base may exceed the cap. (aqs_linkage_set_max_computed)"""
        f = "aqs_linkage_set_max_computed"
        self._call(f, _index(max_joints, f, "max_joints"))

    def set_exact_fallback(self, fraction):
        """Exact fallback (aqs_linkage_set_exact_fallback): when an adaptive
        solve computes more than fraction (in [0, 1]) of the counted joints,
        the next aqs.FALLBACK_RUN solves are exact, by the articulated-body
        algorithm (SolveStats.fallback is True, error_bound 0), and the one
        after is adaptive again. 0, the default, turns it off. Inactive with
        a cap or eps = 0. Any phase."""
        f = "aqs_linkage_set_exact_fallback"
        self._call(f, _number(fraction, f, "fraction"))

    @property
    def exact_fallback(self):
        """The fraction of set_exact_fallback (0.0: off)."""
        value = ctypes.c_double()
        self._call("aqs_linkage_get_exact_fallback", ctypes.byref(value))
        return value.value

    def set_rounding_fallback(self, level):
        """Rounding fallback (aqs_linkage_set_rounding_fallback; on by
        default at aqs.ROUNDING_FALLBACK_LEVEL = 1e-8): when an adaptive solve
        that skips joints estimates its rounding (SolveStats.rounding_bound),
        relative to the solution's size in the measure, above level (or
        cannot estimate it), that solve and the next aqs.FALLBACK_RUN are
        exact, by the articulated-body algorithm (SolveStats.rounding_fallback
        is True, error_bound 0). level >= 0; 0 turns it off. Square-root DCA
        form only; inactive with a cap or eps = 0. Any phase."""
        f = "aqs_linkage_set_rounding_fallback"
        self._call(f, _number(level, f, "level"))

    @property
    def rounding_fallback(self):
        """The level of set_rounding_fallback (0.0: off)."""
        value = ctypes.c_double()
        self._call("aqs_linkage_get_rounding_fallback", ctypes.byref(value))
        return value.value

    def set_adaptive_refinement(self, level):
        """Refinement of adaptive solves (aqs_linkage_set_adaptive_refinement;
        on by default at aqs.ADAPTIVE_REFINEMENT_LEVEL = 1e-10): an adaptive
        solve whose rounding estimate, relative as for set_rounding_fallback,
        exceeds level, or whose computed joints' constraint forces' estimated
        error exceeds level times the largest of them, has its computed
        joints refined by the DCA on the nodes
        it back-substituted (at most exact_refinement corrections, each kept
        only when it lowers the reduced residual); skipped subtrees whose
        coefficients are lossy or whose handle accelerations cancel are
        computed first, so such a solve may compute more joints than its
        bound needs. level >= 0; 0 turns it off. On a linkage where a
        joint's child is more than 1e3 times heavier than its parent the
        trigger uses level / 1e3. Square-root DCA form and joint measures
        only. Any phase."""
        f = "aqs_linkage_set_adaptive_refinement"
        self._call(f, _number(level, f, "level"))

    @property
    def adaptive_refinement(self):
        """The level of set_adaptive_refinement (0.0: off)."""
        value = ctypes.c_double()
        self._call("aqs_linkage_get_adaptive_refinement", ctypes.byref(value))
        return value.value

    def set_prediction(self, margin):
        """Prediction (aqs_linkage_set_prediction): the joints whose total
        acceleration exceeded margin x the stopping level of the last
        adaptive solve (the largest one a queued node may have when it
        stops) are computed by the next solve without
        evaluating theirs, and the update after a step skips their
        total-acceleration factors (SolveStats.nodes_predicted,
        factors_updated). The bound stays certified; a wrong prediction only
        computes more joints. margin 0 turns it off, otherwise >= 1; default
        aqs.PREDICTION_MARGIN (1024). Unused with eps = 0 or a cap."""
        f = "aqs_linkage_set_prediction"
        self._call(f, _number(margin, f, "margin"))

    @property
    def prediction(self):
        """The margin of set_prediction (0.0: off)."""
        value = ctypes.c_double()
        self._call("aqs_linkage_get_prediction", ctypes.byref(value))
        return value.value

    def set_auto(self, enabled):
        """Automatic path (aqs_linkage_set_auto), on by default: with a
        tolerance, each solve or step runs the cheaper of the adaptive
        solver and the exact articulated-body solve, as a cost model counted
        in instructions predicts it from the last solves' counts
        (SolveStats.path, auto_chosen, cost_adaptive, cost_exact). Exact
        solves report error_bound 0. The first solve after a tolerance, cap,
        prediction margin or this mode is set is adaptive. enabled: True/False
        or 1/0; False always runs the adaptive solver. Any phase."""
        f = "aqs_linkage_set_auto"
        self._call(f, _flag(enabled, f, "enabled"))

    @property
    def auto(self):
        """Whether the automatic path is on (set_auto)."""
        value = ctypes.c_int32()
        self._call("aqs_linkage_get_auto", ctypes.byref(value))
        return bool(value.value)

    def set_joint_bound(self, kind):
        """Which certified bound the joint-wise measures ("abs_joint",
        "rel_joint") stop on (aqs_linkage_set_joint_bound): "heap_top" (the
        default; sqrt of the largest queued total acceleration, tighter, so
        fewer joints are computed for the same eps) or "sum" (the paper's
        sqrt of their sum), or an aqs.JOINT_BOUND_* constant. After finalize."""
        f = "aqs_linkage_set_joint_bound"
        self._call(f, _named(kind, JOINT_BOUNDS, f, "kind"))

    def set_dca_form(self, form):
        """How the divide-and-conquer solver keeps a subassembly's inverse
        inertia (aqs_linkage_set_dca_form): "sqrt" (the default: composite
        inertia plus a square-root factor, accurate on long chains, near
        point masses and large mass ratios) or "phi" (the explicit matrix:
        fewer instructions per node, fewer digits on those cases), or an
        aqs.DCA_FORM_* value. Only before finalize()."""
        f = "aqs_linkage_set_dca_form"
        self._call(f, _named(form, DCA_FORMS, f, "form"))

    @property
    def dca_form(self):
        """The DCA form in use: "sqrt" or "phi" (aqs_linkage_get_dca_form)."""
        value = ctypes.c_int32()
        self._call("aqs_linkage_get_dca_form", ctypes.byref(value))
        return DCA_FORM_NAMES[value.value]

    def set_exact_solver(self, solver):
        """Which algorithm computes an exact solve (eps = 0, no cap)
        (aqs_linkage_set_exact_solver): "aba" (the default; the
        articulated-body algorithm over the joints, O(N), leaving the assembly
        tree stale until an adaptive solve needs it, so exact steps report
        nodes_updated = 0; where its refinement cannot reach the rounding
        level, or its backward pass finds an articulated inertia singular on
        a linkage with a heavy child, the exact DCA answers and stats().path
        says "exact_dca") or "dca" (the full DCA back-substitution over the
        assembly tree, recomputed after every step), or an aqs.EXACT_*
        constant. Same results up to rounding. Any phase."""
        f = "aqs_linkage_set_exact_solver"
        self._call(f, _named(solver, EXACT_SOLVERS, f, "solver"))

    @property
    def exact_solver(self):
        """The exact solver in use: "aba" or "dca" (aqs_linkage_get_exact_solver)."""
        value = ctypes.c_int32()
        self._call("aqs_linkage_get_exact_solver", ctypes.byref(value))
        return EXACT_SOLVER_NAMES[value.value]

    def set_exact_refinement(self, max_corrections):
        """At most max_corrections (0 .. 3, default 3; 0: off) refinement
        cycles of a solve computing every joint through the DCA (the exact
        DCA solve, or an adaptive solve that computed every joint): GMRES
        preconditioned by the DCA itself with the inverse-dynamics residual
        as the load, its first step the plain correction, each cycle kept
        only when it lowers the residual (aqs_linkage_set_exact_refinement,
        docs/math.md 13a). The articulated-body solve (the default exact
        solver) likewise takes at most max_corrections corrections where its
        balance of forces says it lost digits (always where a joint's child is
        more than 1e2 times heavier than its parent; the residual in
        double-double arithmetic), and 0 turns that check off (docs/math.md
        5b). Any phase."""
        f = "aqs_linkage_set_exact_refinement"
        self._call(f, _index(max_corrections, f, "max_corrections"))

    @property
    def exact_refinement(self):
        """The maximum corrections of an exact solve (aqs_linkage_get_exact_refinement)."""
        value = ctypes.c_int32()
        self._call("aqs_linkage_get_exact_refinement", ctypes.byref(value))
        return value.value

    def refine(self, eps):
        """Refine the last solve down to a smaller eps, same measure, by
        continuing it rather than starting over (aqs_linkage_refine); returns
        the SolveStats. Only right after solve() or refine(), before positions
        (a step moves them), loads, the tolerance or the joint bound change
        (StateError otherwise). eps >= the bound
        already reached does nothing; the max_computed cap still applies."""
        f = "aqs_linkage_refine"
        self._call(f, _number(eps, f, "eps"))
        return self.stats()

    def stats(self):
        """SolveStats of the last solve or refine (aqs_linkage_get_stats);
        StateError before any solve."""
        c = _lib.aqs_solve_stats()
        c.size = ctypes.sizeof(_lib.aqs_solve_stats)
        self._call("aqs_linkage_get_stats", ctypes.byref(c))
        return SolveStats._from_c(c)

    def joint_computed(self, joint):
        """Whether the last solve computed joint j (aqs_joint_get_computed). An
        uncomputed joint reads acceleration 0 and constraint force NaN (a fixed
        joint counts as computed once its rigid group was reached)."""
        f = "aqs_joint_get_computed"
        out = ctypes.c_int32()
        self._call(f, _index(joint, f, "joint"), ctypes.byref(out))
        return bool(out.value)

    # -- reading back and setting state ----------------------------------------------

    def positions(self, out=None):
        """All joint positions in joint order, (nq) (aqs_linkage_get_positions).
        Spherical: quaternion w x y z; free: translation x y z then quaternion."""
        f = "aqs_linkage_get_positions"
        out = _output(out, self.sizes().nq, f)
        self._call(f, out, out.size)
        return out

    def set_positions(self, q):
        """Set all joint positions, (nq) in joint order (aqs_linkage_set_positions)."""
        f = "aqs_linkage_set_positions"
        q = _array(q, f, "q")
        self._call(f, q, q.size)

    def joint_position(self, joint):
        """Position of one joint, (its nq) (aqs_joint_get_position)."""
        f = "aqs_joint_get_position"
        joint = _index(joint, f, "joint")
        out = np.empty(self._layout_for(joint, f).nq, dtype=_F64)
        self._call(f, joint, out, out.size)
        return out

    def set_joint_position(self, joint, q):
        """Set the position of one joint, (its nq) (aqs_joint_set_position)."""
        f = "aqs_joint_set_position"
        joint = _index(joint, f, "joint")
        q = _array(q, f, "q", ((), (-1,)))
        self._call(f, joint, q, q.size)

    def accelerations(self, out=None):
        """All joint accelerations of the last solve, (nv) in joint order, m/s^2 or
        rad/s^2 (aqs_linkage_get_accelerations). Spherical: the child's angular
        acceleration relative to the parent side, child frame. Free: the child's
        spatial acceleration [dw; dv] in its own body frame, gravity included.
        Joints an adaptive solve did not compute read 0."""
        f = "aqs_linkage_get_accelerations"
        out = _output(out, self.sizes().nv, f)
        self._call(f, out, out.size)
        return out

    def joint_acceleration(self, joint):
        """Acceleration of one joint of the last solve, (its nv) (aqs_joint_get_acceleration)."""
        f = "aqs_joint_get_acceleration"
        joint = _index(joint, f, "joint")
        out = np.empty(self._layout_for(joint, f).nv, dtype=_F64)
        self._call(f, joint, out, out.size)
        return out

    def constraint_forces(self, out=None):
        """Constraint forces of the last solve, (joints, 6): row j is the spatial
        force joint j exerts on its child, child body frame about its origin,
        [n; f] in N m and N; NaN rows for joints an adaptive solve did not
        compute (aqs_linkage_get_constraint_forces)."""
        f = "aqs_linkage_get_constraint_forces"
        out = _output(out, (self.sizes().joints, 6), f)
        self._call(f, out, out.size)
        return out

    def joint_constraint_force(self, joint):
        """Constraint force of one joint, (6) [n; f], child body frame
        (aqs_joint_get_constraint_force)."""
        f = "aqs_joint_get_constraint_force"
        out = np.empty(6, dtype=_F64)
        self._call(f, _index(joint, f, "joint"), out)
        return out

    def body_pose(self, body):
        """World pose of one body after finalize (aqs_body_get_pose_world):
        (position (3) of the body frame origin, m; quaternion (4) w x y z)."""
        f = "aqs_body_get_pose_world"
        pos = np.empty(3, dtype=_F64)
        quat = np.empty(4, dtype=_F64)
        self._call(f, _index(body, f, "body"), pos, quat)
        return pos, quat

    def body_poses(self, out=None):
        """World poses of all bodies, (bodies, 7): row i = x y z w qx qy qz
        (aqs_linkage_get_body_poses_world)."""
        f = "aqs_linkage_get_body_poses_world"
        out = _output(out, (self.sizes().bodies, 7), f)
        self._call(f, out, out.size)
        return out

    # -- collision ---------------------------------------------------------------

    def add_shape(self, body, kind, size, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0)):
        """Attach a convex shape to body (or aqs.WORLD: a static obstacle); returns
        its shape index (aqs_shape_add). kind: "sphere" (size[0] radius),
        "capsule" (radius, half-length along z), "box" (half-extents),
        "cylinder" (radius, half-height along z), or an aqs.SHAPE_* constant.
        size: up to 3 values (missing ones are 0, unused). pos, quat: the
        shape frame in the body frame."""
        f = "aqs_shape_add"
        kind = _named(kind, SHAPES, f, "type")
        size = _array(size, f, "size", ((), (1,), (2,), (3,))).ravel()
        size = np.concatenate([size, np.zeros(3 - size.size)])
        out = ctypes.c_int32()
        self._call(f, _index(body, f, "body"), kind, size, _array(pos, f, "pos", 3),
                   _array(quat, f, "quat", 4), ctypes.byref(out))
        return out.value

    def add_hull(self, body, points, pos=(0.0, 0.0, 0.0), quat=(1.0, 0.0, 0.0, 0.0)):
        """Attach the convex hull of points ((n, 3), n >= 4, not coplanar) to
        body; returns its shape index (aqs_shape_add_hull)."""
        f = "aqs_shape_add_hull"
        points = _array(points, f, "points", ((-1, 3),))
        out = ctypes.c_int32()
        self._call(f, _index(body, f, "body"), points, points.size // 3,
                   _array(pos, f, "pos", 3), _array(quat, f, "quat", 4), ctypes.byref(out))
        return out.value

    @property
    def shape_count(self):
        """Number of shapes, obstacles included (aqs_linkage_get_shape_count)."""
        out = ctypes.c_int32()
        self._call("aqs_linkage_get_shape_count", ctypes.byref(out))
        return out.value

    def set_collision_filter(self, body, group, mask):
        """Collision group and mask of body (aqs.WORLD: the obstacles); two shapes
        may touch only if group_a & mask_b and group_b & mask_a are both non-zero
        (aqs_body_set_collision_filter). Defaults: group 1, mask 0xFFFFFFFF."""
        f = "aqs_body_set_collision_filter"
        body = _index(body, f, "body")
        group = _index(group, f, "group", 0, 0xFFFFFFFF, "uint32_t")
        mask = _index(mask, f, "mask", 0, 0xFFFFFFFF, "uint32_t")
        self._call(f, body, group, mask)

    def exclude_collision(self, body_a, body_b):
        """Never report contacts between body_a and body_b (either may be aqs.WORLD)
        (aqs_collision_exclude_pair)."""
        f = "aqs_collision_exclude_pair"
        self._call(f, _index(body_a, f, "body_a"), _index(body_b, f, "body_b"))

    def set_collide_joined(self, enabled):
        """Whether bodies joined by a joint may collide (default False)
        (aqs_linkage_set_collide_joined)."""
        f = "aqs_linkage_set_collide_joined"
        self._call(f, _flag(enabled, f, "enabled"))

    def collide(self, mode="lazy"):
        """All contacts at the current positions (aqs_linkage_collide), as a numpy
        structured array of dtype aqs.CONTACT_DTYPE: body_a, body_b (aqs.WORLD for
        an obstacle), shape_a, shape_b, depth, normal nx ny nz (unit, world, from
        a towards b), point px py pz (world). mode: "lazy" (default), "full" or
        "brute" (same contacts, different work)."""
        f = "aqs_linkage_collide"
        mode = _named(mode, COLLIDE_MODES, f, "mode")
        count = ctypes.c_size_t(0)
        capacity = 64
        while True:
            buffer = (_lib.aqs_contact * capacity)()
            try:
                self._call(f, mode, buffer, capacity, ctypes.byref(count))
            except SizeError:
                if count.value <= capacity:
                    raise
                capacity = count.value  # sized from the returned total, then asked again
                continue
            break
        return np.frombuffer(buffer, dtype=CONTACT_DTYPE, count=count.value).copy()

    def any_contact(self):
        """Whether any two shapes touch (aqs_linkage_any_contact)."""
        out = ctypes.c_int32()
        self._call("aqs_linkage_any_contact", ctypes.byref(out))
        return bool(out.value)

    def set_contact_stiffness(self, stiffness):
        """Penalty contact (aqs_linkage_set_contact_stiffness): each contact pushes
        its bodies apart with stiffness * depth along its normal, at every solve
        and step; 0 (the default) turns it off. After finalize."""
        f = "aqs_linkage_set_contact_stiffness"
        self._call(f, _number(stiffness, f, "stiffness"))

    def collision_stats(self):
        """Work of the last collision query (aqs_linkage_get_query_stats): a
        CollisionStats (nodes_refit, volume_tests, narrow_tests, nodes_skipped,
        certs_reused, certs_made, near_tests)."""
        c = _lib.aqs_collision_stats()
        c.size = ctypes.sizeof(c)
        self._call("aqs_linkage_get_query_stats", ctypes.byref(c))
        return CollisionStats(*(getattr(c, name) for name in CollisionStats._fields))

def _locked(function):
    """function, run with its linkage's lock held."""
    @functools.wraps(function)
    def locked(self, *args, **kwargs):
        with self._lock:
            return function(self, *args, **kwargs)
    return locked


def _synchronize(cls):
    """Every public method and property of cls (and __repr__) holds the
    linkage's lock for its whole run, so a method that makes several C calls
    (step() then its statistics, a getter sizing its output) sees no other
    thread's call in between. closed reads one attribute and does not wait."""
    for name, member in list(vars(cls).items()):
        if name in ("closed", "close") or (name.startswith("_") and name != "__repr__"):
            continue
        if isinstance(member, property):
            setattr(cls, name, property(_locked(member.fget),
                                        _locked(member.fset) if member.fset else None, None,
                                        member.__doc__))
        elif callable(member) and not isinstance(member, (classmethod, staticmethod)):
            setattr(cls, name, _locked(member))
    return cls


_synchronize(Linkage)

from .urdf import URDFError, URDFWarning, load_urdf, save_urdf  # noqa: E402  (needs Linkage)
