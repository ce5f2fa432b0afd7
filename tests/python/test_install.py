"""`pip install ./bindings/python` works offline, and the installed package
finds its library (AQS_LIBRARY, or a libaqs.so shipped inside it)."""

import os
import shutil
import subprocess
import sys

import pytest

import aqs

BINDINGS = os.path.dirname(os.path.dirname(os.path.abspath(aqs.__file__)))

SMOKE = """
import os, sys, numpy as np, aqs
assert os.path.realpath(aqs.__file__).startswith(os.path.realpath(sys.argv[1])), aqs.__file__
with aqs.Linkage() as L:
    L.add_body(2.0, (0.5, 0, 0), np.diag([0.1, 0.1, 0.1]))
    L.add_joint("revolute", aqs.WORLD, 0)
    L.finalize()
    L.set_gravity((0, -10.0, 0))
    L.solve()
    qdd = L.accelerations()[0]
assert abs(qdd - (-2.0 * 10.0 * 0.5 / (0.1 + 2.0 * 0.25))) < 1e-12, qdd
print(aqs.library_path)
"""


def local_backend():
    """Whether setuptools can build a wheel here without downloading anything."""
    try:
        import setuptools
    except ImportError:
        return False
    try:
        import wheel  # noqa: F401  (bdist_wheel for setuptools < 70.1)
        return True
    except ImportError:
        version = tuple(int(x) for x in setuptools.__version__.split(".")[:2] if x.isdigit())
        return version >= (70, 1)


def pip_install(tmp_path):
    # Build from a copy: an in-tree build would leave build/ and *.egg-info in the checkout.
    source = tmp_path / "src"
    shutil.copytree(BINDINGS, source,
                    ignore=shutil.ignore_patterns("__pycache__", "build", "*.egg-info",
                                                  "libaqs.so*"))
    target = tmp_path / "site"
    env = dict(os.environ, PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1")
    command = [sys.executable, "-m", "pip", "install", "--no-deps", "--no-cache-dir",
               "--target", str(target), str(source)]
    offline = local_backend()
    if offline:
        command[4:4] = ["--no-build-isolation", "--no-index"]
    # else: pip fetches setuptools and wheel into an isolated build environment.
    result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=600)
    if result.returncode != 0 and not offline:
        pytest.skip("no local setuptools+wheel (make deps installs them) and fetching them "
                    "failed:\n" + result.stderr[-2000:])
    assert result.returncode == 0, result.stdout + result.stderr
    assert (target / "aqs" / "__init__.py").is_file()
    assert (target / "aqs" / "_lib.py").is_file()
    return target


def run_smoke(target, env_changes, cwd):
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    env.update(env_changes)
    env = {k: v for k, v in env.items() if v is not None}
    env["PYTHONPATH"] = str(target)
    return subprocess.run([sys.executable, "-c", SMOKE, str(target)], env=env, cwd=str(cwd),
                          capture_output=True, text=True, timeout=120)


def test_pip_install_target(tmp_path):
    target = pip_install(tmp_path)
    result = run_smoke(target, {"AQS_LIBRARY": aqs.library_path}, tmp_path)
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(result.stdout.strip(), aqs.library_path)

    # A libaqs.so shipped inside the package is found without AQS_LIBRARY.
    shipped = target / "aqs" / ("libaqs.so.%d" % aqs._lib.VERSION_MAJOR)
    shutil.copy(os.path.realpath(aqs.library_path), shipped)
    result = run_smoke(target, {"AQS_LIBRARY": None}, tmp_path)
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(result.stdout.strip(), shipped)
