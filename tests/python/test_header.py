"""The bindings' table matches include/aqs.h: every function declared, with the
same arity and compatible types; every constant with the same value; every
struct mirrored field for field."""

import ctypes
import os
import re

import pytest

import aqs
from aqs import _lib
from aqs_testutil import REPO

HEADER = os.path.join(REPO, "include", "aqs.h")


@pytest.fixture(scope="module")
def header():
    if not os.path.isfile(HEADER):
        pytest.skip("no include/aqs.h next to the tests")
    with open(HEADER) as handle:
        text = handle.read()
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)  # drop comments
    return text


def declarations(text):
    """{name: (return type, [parameter types])} of every AQS_API function."""
    found = {}
    for match in re.finditer(r"AQS_API\s+([^;(]*?)\s*\b(aqs_\w+)\s*\(([^)]*)\)\s*;", text):
        returns, name, params = match.groups()
        params = [p.strip() for p in params.split(",")]
        params = [] if params == ["void"] else params
        types = []
        for p in params:
            p = re.sub(r"\s+", " ", p)
            array = p.endswith("]")
            p = re.sub(r"\[\d*\]$", "", p).strip()
            p = re.sub(r"\b\w+$", "", p).strip()  # the parameter's name
            types.append(p + (" *" if array else ""))
        found[name] = (re.sub(r"\s+", " ", returns.strip()), types)
    return found


RETURNS = {"aqs_status": [_lib.status_t], "int32_t": [ctypes.c_int32],
           "const char *": [ctypes.c_char_p], "void": [None]}
PARAMS = {
    "aqs_linkage *": [_lib.linkage_p], "const aqs_linkage *": [_lib.linkage_p],
    "aqs_linkage **": [ctypes.POINTER(_lib.linkage_p)],
    "double": [ctypes.c_double], "int32_t": [ctypes.c_int32], "size_t": [ctypes.c_size_t],
    "aqs_status": [_lib.status_t], "void *": [ctypes.c_void_p],
    "int32_t *": [_lib.int32_p], "const double *": [_lib.din, _lib.din_or_null],
    "double *": [_lib.dout, _lib.dout_or_null, _lib.double_p],
    "aqs_alloc_fn": [_lib.alloc_fn], "aqs_free_fn": [_lib.free_fn],
    "aqs_solve_stats *": [ctypes.POINTER(_lib.aqs_solve_stats)],
    "aqs_collision_stats *": [ctypes.POINTER(_lib.aqs_collision_stats)],
    "aqs_memory_stats *": [ctypes.POINTER(_lib.aqs_memory_stats)],
    "uint32_t": [ctypes.c_uint32], "aqs_contact *": [_lib.contact_p],
    "size_t *": [_lib.size_p],
    "const char *": [ctypes.c_char_p], "const char **": [ctypes.POINTER(ctypes.c_char_p)],
    "aqs_urdf_options *": [_lib.urdf_options_p], "const aqs_urdf_options *": [_lib.urdf_options_p],
}
#: C types of struct fields -> the ctypes type that mirrors them.
FIELD_TYPES = {"uint32_t": ctypes.c_uint32, "int32_t": ctypes.c_int32, "double": ctypes.c_double,
               "uint64_t": ctypes.c_uint64}
#: Each struct of the header -> its ctypes.Structure.
STRUCTS = {"aqs_solve_stats": _lib.aqs_solve_stats, "aqs_contact": _lib.aqs_contact,
           "aqs_urdf_options": _lib.aqs_urdf_options,
           "aqs_collision_stats": _lib.aqs_collision_stats,
           "aqs_memory_stats": _lib.aqs_memory_stats}


def normalize(c_type):
    return re.sub(r"\s*\*", " *", c_type).replace("* *", "**").strip()


def test_every_function_is_in_the_table(header):
    declared = declarations(header)
    assert len(declared) >= 30
    assert set(declared) == set(_lib.PROTOTYPES)


def test_prototypes_match(header):
    for name, (returns, params) in declarations(header).items():
        restype, argtypes = _lib.PROTOTYPES[name]
        assert restype in RETURNS[normalize(returns)], name
        assert len(argtypes) == len(params), name
        for position, (c_type, argtype) in enumerate(zip(params, argtypes)):
            assert argtype in PARAMS[normalize(c_type)], (name, position, c_type)
        function = getattr(_lib.lib, name)
        assert function.restype is restype and function.argtypes == argtypes


def test_constants_match(header):
    # integer and floating literals whole (AQS_PREDICTION_MARGIN 1024.0, AQS_ROUNDING_FALLBACK_LEVEL 1e-8)
    defines = dict(re.findall(r"#define\s+(AQS_\w+)\s+\(?(-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\)?", header))
    assert int(defines["AQS_VERSION_MAJOR"]) == _lib.VERSION_MAJOR
    for name, value in defines.items():
        if name.startswith("AQS_VERSION"):
            continue
        short = name[len("AQS_"):]
        if short.startswith("TREE_"):
            assert aqs.TREE_BUILDERS[short[len("TREE_"):].lower()] == int(value), name
        if short.startswith("EXACT_"):
            assert aqs.EXACT_SOLVERS[short[len("EXACT_"):].lower()] == int(value), name
        if short.startswith("JOINT_BOUND_"):
            assert aqs.JOINT_BOUNDS[short[len("JOINT_BOUND_"):].lower()] == int(value), name
        elif short.startswith("JOINT_"):
            assert aqs.JOINT_KINDS[short[len("JOINT_"):].lower()] == int(value), name
        if short.startswith("METRIC_"):
            assert aqs.METRICS[short[len("METRIC_"):].lower()] == int(value), name
        assert getattr(aqs, short) == float(value), name
    codes = {int(v) for k, v in defines.items()
             if k in ("AQS_OK",) or (k.startswith("AQS_E") and not k.startswith("AQS_EXACT_"))}
    assert codes == set(_lib.STATUS_NAMES)
    assert set(aqs._errors.BY_STATUS) == codes - {0}
    for prefix, table in (("AQS_JOINT_BOUND_", aqs.JOINT_BOUNDS), ("AQS_METRIC_", aqs.METRICS),
                          ("AQS_TREE_", aqs.TREE_BUILDERS), ("AQS_EXACT_", aqs.EXACT_SOLVERS)):
        assert len(table) == sum(k.startswith(prefix) for k in defines), prefix
    kinds = [k for k in defines if k.startswith("AQS_JOINT_") and "BOUND" not in k]
    assert len(aqs.JOINT_KINDS) == len(kinds)


def test_structs_match(header):
    """Every struct of the header, field for field (names, order, types)."""
    found = re.findall(r"typedef\s+struct\s+(aqs_\w+)\s*\{(.*?)\}\s*(\w+)\s*;", header, re.S)
    assert {tag for tag, _, _ in found} == set(STRUCTS)
    for tag, body, name in found:
        assert name == tag
        fields = re.findall(r"(\w+)\s+(\w+)\s*;", body)
        mirror = STRUCTS[tag]
        assert [(n, FIELD_TYPES[t]) for t, n in fields] == list(mirror._fields_), tag
    # The C layout with natural alignment: 88 bytes of fields, padded to 96.
    stats = _lib.aqs_solve_stats
    assert ctypes.sizeof(stats) == 96
    assert stats.eps.offset == 8 and stats.computed_joints.offset == 24
    assert stats.fallback.offset == 44 and stats.factors_updated.offset == 52
    assert stats.path.offset == 56 and stats.cost_adaptive.offset == 64 and stats.cost_exact.offset == 72
    assert stats.rounding_bound.offset == 80 and stats.certified.offset == 88
    assert ctypes.sizeof(_lib.aqs_collision_stats) == 32  # eight 4-byte fields
    assert ctypes.sizeof(_lib.aqs_memory_stats) == 80  # two 4-byte fields, nine 8-byte ones
