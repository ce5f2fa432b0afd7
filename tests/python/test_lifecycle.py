"""Version, library discovery, owning the handle, custom allocators."""

import ctypes
import ctypes.util
import gc
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import aqs
from aqs import _lib
from aqs_testutil import apply_state, build, exact_vector_files, load_case, rel_err

BINDINGS = os.path.dirname(os.path.dirname(os.path.abspath(aqs.__file__)))


def run_python(code, env_changes, cwd=None):
    env = dict(os.environ)
    for key, value in env_changes.items():
        if value is None:
            env.pop(key, None)
        else:
            env[key] = value
    return subprocess.run([sys.executable, "-c", code], env=env, cwd=cwd, capture_output=True,
                          text=True, timeout=120)


def small_linkage():
    L = aqs.Linkage()
    L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
    L.add_joint("revolute", aqs.WORLD, 0)
    L.finalize()
    return L


# -- version --------------------------------------------------------------------------------

def test_version():
    assert re.fullmatch(r"\d+\.\d+\.\d+", aqs.version())
    major, minor, patch = map(int, aqs.version().split("."))
    assert aqs.version_number() == major * 10000 + minor * 100 + patch
    assert major == _lib.VERSION_MAJOR == 0


def test_major_mismatch_is_an_import_error():
    _lib.check_major(0 * 10000 + 7 * 100 + 3, "libaqs.so")
    with pytest.raises(ImportError, match="major 1"):
        _lib.check_major(10203, "/somewhere/libaqs.so.1")


# -- library discovery ------------------------------------------------------------------------

def test_loaded_library_is_aqs_library():
    if os.environ.get("AQS_LIBRARY"):
        assert os.path.samefile(aqs.library_path, os.environ["AQS_LIBRARY"])


def test_missing_library_named_by_env_is_an_import_error(tmp_path):
    result = run_python("import aqs", {"AQS_LIBRARY": str(tmp_path / "nope.so"),
                                       "PYTHONPATH": BINDINGS})
    assert result.returncode != 0
    assert "ImportError" in result.stderr and "AQS_LIBRARY" in result.stderr


def test_a_library_that_is_not_aqs_is_an_import_error():
    libm = ctypes.util.find_library("m")
    if libm is None:
        pytest.skip("no libm to stand in for a foreign library")
    result = run_python("import aqs", {"AQS_LIBRARY": libm, "PYTHONPATH": BINDINGS})
    assert result.returncode != 0
    assert "not libaqs" in result.stderr


def test_found_in_the_source_checkout_build_directory():
    build = os.path.normpath(os.path.join(BINDINGS, "..", "..", "build"))
    if not (os.path.isdir(build) and any(n.startswith("libaqs.so") for n in os.listdir(build))):
        pytest.skip("the source checkout has no build/libaqs.so (make lib)")
    result = run_python("import aqs; print(aqs.library_path)",
                        {"AQS_LIBRARY": None, "PYTHONPATH": BINDINGS})
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(os.path.dirname(result.stdout.strip()), build)


# -- owning the handle -----------------------------------------------------------------------------

def test_close_twice_and_context_manager():
    L = small_linkage()
    assert not L.closed
    L.close()
    L.close()
    assert L.closed
    assert "closed" in repr(L)
    with small_linkage() as L2:
        L2.solve()
        assert "bodies=1" in repr(L2)
    assert L2.closed


CALLS = [
    ("set_inertia_check", (False,)), ("set_tree_builder", ("bisection",)), ("add_body", (1.0, (0, 0, 0), np.eye(3))),
    ("add_joint", ("revolute", -1, 0)),
    ("finalize", ()), ("sizes", ()), ("joint_layout", (0,)), ("tree_stats", ()), ("memory", ()),
    ("set_gravity", ((0, 0, -9.81),)), ("set_body_force", (0, (1, 0, 0))),
    ("clear_body_force", (0,)), ("clear_forces", ()), ("set_joint_force", (0, 1.0)),
    ("solve", ()), ("step", (0.01,)),
    ("set_tolerance", ("rel_joint", 1e-3)), ("set_max_computed", (10,)),
    ("set_joint_bound", ("sum",)), ("set_exact_solver", ("dca",)), ("exact_solver", ()),
    ("set_dca_form", ("phi",)), ("dca_form", ()),
    ("set_exact_refinement", (1,)), ("exact_refinement", ()),
    ("set_exact_fallback", (0.5,)), ("exact_fallback", ()), ("set_rounding_fallback", (1e-9,)), ("rounding_fallback", ()), ("set_adaptive_refinement", (1e-9,)), ("adaptive_refinement", ()), ("set_prediction", (16.0,)), ("prediction", ()), ("set_auto", (False,)), ("auto", ()), ("refine", (1e-4,)), ("stats", ()), ("joint_computed", (0,)),
    ("accelerations", ()), ("joint_acceleration", (0,)),
    ("positions", ()), ("set_positions", ([0.0],)), ("joint_position", (0,)),
    ("set_joint_position", (0, 0.0)), ("constraint_forces", ()), ("joint_constraint_force", (0,)),
    ("body_pose", (0,)), ("body_poses", ()),
    # collision
    ("add_shape", (0, "sphere", [0.5])), ("add_hull", (0, np.eye(4, 3) + 0.1 * np.arange(12).reshape(4, 3))),
    ("set_collision_filter", (0, 1, 1)), ("exclude_collision", (0, -1)), ("set_collide_joined", (True,)),
    ("collide", ()), ("any_contact", ()), ("collision_stats", ()), ("set_contact_stiffness", (10.0,)),
    ("body_inertial", (0,)), ("joint_definition", (0,)), ("save_urdf", ("never-written.urdf",)),
    # names and limits
    ("set_body_name", (0, "b")), ("set_joint_name", (0, "j")), ("body_name", (0,)),
    ("joint_name", (0,)), ("find_body", ("b",)), ("find_joint", ("j",)),
    ("set_joint_limits", (0, -1.0, 1.0)), ("joint_limits", (0,)),
]


@pytest.mark.parametrize("name, args", CALLS, ids=[c[0] for c in CALLS])
def test_closed_linkage_raises_state_error(name, args):
    L = small_linkage()
    L.close()
    with pytest.raises(aqs.StateError, match="closed"):
        getattr(L, name)(*args)


def test_closed_linkage_properties_raise_state_error():
    L = small_linkage()
    L.close()
    for name in ("num_bodies", "num_joints", "nq", "nv", "last_error", "shape_count",
                 "body_names", "joint_names", "load_warnings"):
        with pytest.raises(aqs.StateError):
            getattr(L, name)


def test_every_method_listed():
    public = {n for n in dir(aqs.Linkage) if not n.startswith("_")}
    listed = {c[0] for c in CALLS} | {"num_bodies", "num_joints", "nq", "nv", "last_error",
                                      "close", "closed", "with_allocator", "shape_count",
                                      "body_names", "joint_names", "load_warnings"}
    assert public == listed


def test_garbage_collected_linkages_are_destroyed():
    for _ in range(200):
        L = small_linkage()
        L.solve()
        del L
    gc.collect()


def test_many_linkages_alive():
    linkages = [small_linkage() for _ in range(50)]
    for k, L in enumerate(linkages):
        L.set_joint_force(0, float(k))
    for k, L in enumerate(linkages):
        L.solve()
        assert L.accelerations()[0] == pytest.approx(k / (0.1 + 0.25))
        L.close()


# -- custom allocators -----------------------------------------------------------------------------

class CountingAllocator:
    """malloc/free through ctypes, counting what is outstanding; fails the
    allocation number fail_at (0-based) and every later one when sticky."""

    libc = ctypes.CDLL(None)
    libc.malloc.restype = ctypes.c_void_p
    libc.malloc.argtypes = [ctypes.c_size_t]
    libc.free.restype = None
    libc.free.argtypes = [ctypes.c_void_p]

    def __init__(self, fail_at=None):
        self.fail_at = fail_at
        self.calls = 0
        self.live = {}

    def alloc(self, size):
        index, self.calls = self.calls, self.calls + 1
        if self.fail_at is not None and index >= self.fail_at:
            return 0
        ptr = self.libc.malloc(max(size, 1))
        self.live[ptr] = size
        return ptr

    def free(self, ptr):
        assert ptr in self.live, "free of a pointer not allocated here"
        del self.live[ptr]
        self.libc.free(ptr)


def test_memory_matches_allocator():
    """Linkage.memory() against the allocator's own count, at each phase."""
    allocator = CountingAllocator()
    L = aqs.Linkage.with_allocator(allocator.alloc, allocator.free)

    def check():
        m = L.memory()
        assert m.bytes == sum(allocator.live.values())
        assert m.blocks == len(allocator.live)
        assert m.bytes <= m.peak
        assert m.model + m.tree + m.exact + m.dca + m.factors + m.world + m.collision == m.bytes
        return m

    assert check().blocks == 1  # the handle
    for i in range(30):
        L.add_body(1.0, (0.5, 0, 0), np.eye(3) * 0.1)
        L.add_joint("revolute", aqs.WORLD if i == 0 else i - 1, i, pos=(1.0, 0, 0))
    built = check()
    assert built.tree == built.exact == built.dca == built.factors == 0
    L.finalize()
    L.solve()
    exact = check()
    assert exact.tree > 0 and exact.exact > 0 and exact.dca == exact.factors == 0
    L.set_tolerance("rel_joint", 2.0 ** -19)
    L.solve()
    adaptive = check()
    assert adaptive.dca > 0 and adaptive.factors > 0 and adaptive.model == exact.model
    L.close()
    assert allocator.live == {}


def test_allocator_sees_all_memory():
    case = load_case(exact_vector_files()[4])
    allocator = CountingAllocator()
    L = aqs.Linkage.with_allocator(allocator.alloc, allocator.free)
    build(aqs, case, L)
    L.solve()
    L.step(1e-3)
    assert allocator.calls > 0 and allocator.live
    L.close()
    assert allocator.live == {}


def test_out_of_memory_everywhere():
    """Every allocation failure surfaces as OutOfMemoryError and changes
    nothing: once memory is available again the same call succeeds and the
    answer is right. Nothing leaks."""
    case = load_case(exact_vector_files()[4])
    expected = case["expected"]["accelerations"]
    total = CountingAllocator()
    L = aqs.Linkage.with_allocator(total.alloc, total.free)
    build(aqs, case, L)
    L.solve()
    L.close()
    failures = 0
    for fail_at in range(total.calls + 1):
        allocator = CountingAllocator(fail_at)
        try:
            L = aqs.Linkage.with_allocator(allocator.alloc, allocator.free)
        except aqs.OutOfMemoryError:
            assert allocator.live == {}
            failures += 1
            continue

        def attempt(call, *args):
            nonlocal failures
            try:
                return call(*args)
            except aqs.OutOfMemoryError as exc:
                assert exc.message
                failures += 1
                allocator.fail_at = None
                return call(*args)

        try:
            attempt(L.set_inertia_check, False)
            for b in case["bodies"]:
                attempt(L.add_body, b["mass"], b["com"], b["inertia"])
            for j in case["joints"]:
                attempt(L.add_joint, j["type"], j["parent"], j["child"], j["pos"], j["quat"],
                        j["axis"])
            attempt(L.finalize)
            attempt(apply_state, L, case)
            attempt(L.solve)
            assert rel_err(L.accelerations(), expected) <= 1e-8
        finally:
            L.close()
        assert allocator.live == {}, "leak when allocation %d fails" % fail_at
    assert failures >= total.calls
