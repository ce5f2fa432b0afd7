"""The C exporter of the bench programs (bench/urdf.c, through
build/bench/urdf_export) against the Python loader: each scene built in C
(chain30; the millipede, whose floating base becomes a URDF floating joint;
the 2,000-joint molecule) is exported with its exact solve under seeded loads
(gravity, 3 body forces with points and torques, 3 joint forces including
joint 0), loaded back with aqs.load_urdf, put under the same loads and solved:
the accelerations must agree to 1e-11 relative (max norm).

Why 1e-11: the two models differ only by the rpy round trip of each joint
rotation, a few ulp (tests/python/test_urdf.py bounds it at 1.2e-15 in the
quaternion). The solver's own rounding on one model, measured here as the
difference between the two assembly-tree builders, is about 1e-13 on the
molecule and the millipede (a failure reports it); the URDF difference
measured when this test was written is of the same size (1.6e-13 molecule, 1.2e-14 millipede, 0 on
chain30, whose rotations are identities). 1e-11 leaves a factor ~100.

The exported file is also compared with what save_urdf writes for the loaded
linkage: same elements, attributes and names, numbers within 4 ulp.

make check sets AQS_URDF_EXPORT to the program; without it these tests skip.
"""

import json
import os
import subprocess

import numpy as np
import pytest

import aqs
from test_urdf import assert_same_urdf

EXPORTER = os.environ.get("AQS_URDF_EXPORT")
pytestmark = pytest.mark.skipif(not EXPORTER, reason="AQS_URDF_EXPORT (the urdf_export "
                                "program) not set; make check sets it")


def apply(L, loads):
    L.set_gravity(loads["gravity"])
    for f in loads["body_forces"]:
        L.set_body_force(f["body"], f["force"], point=f["point"], torque=f["torque"])
    for f in loads["joint_forces"]:
        L.set_joint_force(f["joint"], f["tau"])


@pytest.mark.parametrize("scene, joints, free", [("chain30", None, False),
                                                 ("millipede", None, True),
                                                 ("molecule", 2000, False)])
def test_exported_scene_solves_the_same(tmp_path, scene, joints, free):
    urdf = tmp_path / (scene + ".urdf")
    data = tmp_path / (scene + ".json")
    args = [EXPORTER, scene] + ([str(joints)] if joints else []) + [str(urdf), str(data)]
    subprocess.run(args, check=True)
    with open(data) as handle:
        loads = json.load(handle)
    L = aqs.load_urdf(urdf)
    assert L.num_bodies == loads["bodies"] and L.num_joints == loads["joints"]
    assert (L.joint_definition(0).kind == "free") == free
    apply(L, loads)
    L.solve()
    got, expected = L.accelerations(), np.array(loads["qdd"])
    assert got.shape == expected.shape
    scale = np.abs(expected).max()
    assert scale > 0.1
    difference = np.abs(got - expected).max() / scale
    if difference > 1e-11:
        # Report the solver's rounding floor on this model with the failure.
        other = aqs.load_urdf(urdf, finalize=False)
        other.set_tree_builder("bisection")
        other.finalize()
        apply(other, loads)
        other.solve()
        floor = np.abs(other.accelerations() - got).max() / scale
        pytest.fail("URDF model differs by %.3g, the tree builders by %.3g" % (difference, floor))
    again = tmp_path / (scene + ".again.urdf")
    aqs.save_urdf(L, again, name=scene)
    assert_same_urdf(urdf, again, ulps=4)
    L.close()


def test_exporter_refuses_unknown_scene(tmp_path):
    result = subprocess.run([EXPORTER, "teapot", str(tmp_path / "a"), str(tmp_path / "b")],
                            capture_output=True, text=True)
    assert result.returncode == 2 and "unknown scene teapot" in result.stderr
    assert not (tmp_path / "a").exists()


def test_exporter_errors(tmp_path):
    """bench_export_urdf refuses a NULL linkage or path, an unwritable file
    and a spherical joint with AQS_EINVAL and a message, leaving no file
    (the checks run inside the C program; it exits 0 only if all hold)."""
    result = subprocess.run([EXPORTER, "--check-errors", str(tmp_path)], capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stderr
    assert list(tmp_path.iterdir()) == []
