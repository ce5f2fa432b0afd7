"""The pip package carries its own libaqs, compiled from the repository's C sources.

A fresh virtual environment (numpy reused from the running Python through
--system-site-packages, so nothing is downloaded when setuptools and wheel are
there too), a copy of the repository's files the package needs (as a clone
has them), then, as the README says, `pip install ./bindings/python` from the
repository root, and `pip wheel` for a wheel; `import aqs` runs from another
folder with no AQS_LIBRARY and no PYTHONPATH, and must load the library
installed inside the package and solve the pendulum and the README's example.
Also the loader's order: AQS_LIBRARY, the package's library, the checkout's
build/, the system's."""

import ctypes.util
import os
import re
import shutil
import subprocess
import sys
import zipfile

import pytest

import aqs
from aqs import _lib

BINDINGS = os.path.dirname(os.path.dirname(os.path.abspath(aqs.__file__)))
REPO = os.path.dirname(os.path.dirname(BINDINGS))

SMOKE = """
import os, sys, numpy as np, aqs
site = os.path.realpath(sys.argv[1])
assert os.path.realpath(aqs.__file__).startswith(site), aqs.__file__
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


def readme_python_example():
    """The code block of the top README's "Python example" section."""
    with open(os.path.join(REPO, "README.md")) as readme:
        text = readme.read()
    match = re.search(r"^## Python example\n.*?^```python\n(.*?)^```", text, re.M | re.S)
    assert match, "README.md has no Python example"
    return match.group(1)


def copy_of_the_repository(tmp_path):
    """What a clone holds of the package's sources: bindings/python, src, include."""
    root = tmp_path / "repo"
    ignore = shutil.ignore_patterns("__pycache__", "build", "*.egg-info", "libaqs.so*")
    shutil.copytree(BINDINGS, root / "bindings" / "python", ignore=ignore)
    shutil.copytree(os.path.join(REPO, "src"), root / "src", ignore=ignore)
    shutil.copytree(os.path.join(REPO, "include"), root / "include", ignore=ignore)
    shutil.copy(os.path.join(REPO, "README.md"), root / "README.md")
    return root


def clean_env(**changes):
    env = {k: v for k, v in os.environ.items()
           if k not in ("AQS_LIBRARY", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")
           and not k.startswith("PIP_")}
    env.update(PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INPUT="1", AQS_BUILD_JOBS="2")
    env.update({k: v for k, v in changes.items() if v is not None})
    if "AQS_LIBRARY" not in env:
        # make check SANITIZE=1 preloads the sanitizer runtime for the sanitized
        # build/libaqs; pip, the compiler and the package's own library need none.
        env.pop("LD_PRELOAD", None)
    return env


def run(command, cwd, env, timeout=300):
    return subprocess.run([str(c) for c in command], cwd=str(cwd), env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    """A fresh venv seeing this Python's packages (numpy); returns (python, offline)."""
    where = tmp_path_factory.mktemp("venv")
    # Without its own pip when the base Python's pip is visible: ensurepip takes ~10 s.
    python = where / "env" / "bin" / "python"
    result = run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                  where / "env"], where, clean_env())
    if result.returncode == 0 and run([python, "-m", "pip", "--version"], where,
                                      clean_env()).returncode != 0:
        result = run([python, "-m", "ensurepip"], where, clean_env())
    if result.returncode != 0:
        pytest.skip("python3 -m venv failed (Debian: python3-venv):\n" + result.stderr[-2000:])
    check = run([python, "-c", "import numpy, setuptools, wheel"], where, clean_env())
    return python, check.returncode == 0


def pip(venv, *arguments, cwd):
    """pip of the venv; offline (no build isolation, no index) when it can be."""
    python, offline = venv
    command = [python, "-m", "pip"] + list(arguments)
    if offline and arguments[0] in ("install", "wheel"):
        command[4:4] = ["--no-build-isolation", "--no-index"]
    result = run(command, cwd, clean_env())
    if result.returncode != 0 and not offline:
        pytest.skip("no setuptools+wheel for an offline build (make deps installs them) and "
                    "fetching them failed:\n" + result.stderr[-2000:])
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    return result


def site_packages(venv):
    python, _ = venv
    result = run([python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                 "/", clean_env())
    return result.stdout.strip()


def import_from_elsewhere(venv, tmp_path, code, *arguments, **env):
    python, _ = venv
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(exist_ok=True)
    return run([python, "-c", code] + list(arguments), elsewhere, clean_env(**env), timeout=120)


def test_pip_install_from_the_repository_root(venv, tmp_path):
    root = copy_of_the_repository(tmp_path)
    pip(venv, "install", "./bindings/python", cwd=root)
    site = site_packages(venv)
    shipped = os.path.join(site, "aqs", "libaqs.so.%d" % _lib.VERSION_MAJOR)
    assert os.path.isfile(shipped)

    # No environment variable, another folder: the package's own library.
    result = import_from_elsewhere(venv, tmp_path, SMOKE, site)
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(result.stdout.strip(), shipped)
    result = import_from_elsewhere(venv, tmp_path, readme_python_example())
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip()

    # AQS_LIBRARY still wins.
    result = import_from_elsewhere(venv, tmp_path, SMOKE, site, AQS_LIBRARY=aqs.library_path)
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(result.stdout.strip(), aqs.library_path)
    pip(venv, "uninstall", "-y", "aqs", cwd=tmp_path)
    assert not os.path.exists(shipped)


def test_wheel_carries_the_library(venv, tmp_path):
    root = copy_of_the_repository(tmp_path)
    pip(venv, "wheel", "--no-deps", "-w", tmp_path / "dist", "./bindings/python", cwd=root)
    wheels = os.listdir(tmp_path / "dist")
    assert len(wheels) == 1, wheels
    wheel = wheels[0]
    # Platform-specific (it holds a C library), for any Python 3.
    assert re.fullmatch(r"aqs-[\d.]+-py3-none-linux_\w+\.whl", wheel), wheel
    with zipfile.ZipFile(tmp_path / "dist" / wheel) as archive:
        names = archive.namelist()
    assert "aqs/libaqs.so.%d" % _lib.VERSION_MAJOR in names, names
    assert {"aqs/__init__.py", "aqs/_lib.py", "aqs/_errors.py", "aqs/urdf.py"} <= set(names)

    pip(venv, "install", tmp_path / "dist" / wheel, cwd=tmp_path)
    site = site_packages(venv)
    result = import_from_elsewhere(venv, tmp_path, SMOKE, site)
    assert result.returncode == 0, result.stderr
    assert os.path.samefile(result.stdout.strip(),
                            os.path.join(site, "aqs", "libaqs.so.%d" % _lib.VERSION_MAJOR))
    pip(venv, "uninstall", "-y", "aqs", cwd=tmp_path)


def test_no_sources_is_a_clear_error(venv, tmp_path):
    """bindings/python copied alone (no ../../src): the build says what is missing."""
    python, offline = venv
    if not offline:
        pytest.skip("needs setuptools and wheel for an offline build")
    alone = tmp_path / "alone"
    shutil.copytree(BINDINGS, alone, ignore=shutil.ignore_patterns(
        "__pycache__", "build", "*.egg-info", "libaqs.so*"))
    result = run([python, "-m", "pip", "wheel", "--no-build-isolation", "--no-index",
                  "--no-deps", "-w", tmp_path / "dist", alone], tmp_path, clean_env())
    assert result.returncode != 0
    assert "AQS_SOURCE_DIR" in result.stdout + result.stderr


# -- the loader's order ------------------------------------------------------------------------

def test_candidates_order(tmp_path, monkeypatch):
    package = tmp_path / "aqs"
    package.mkdir()
    for name in ("libaqs.so", "libaqs.so.%d" % _lib.VERSION_MAJOR):
        (package / name).write_bytes(b"")
    monkeypatch.setattr(_lib, "PACKAGE_DIR", str(package))
    monkeypatch.setattr(ctypes.util, "find_library", lambda name: "libaqs.so.0")
    monkeypatch.delenv("AQS_LIBRARY", raising=False)
    got = _lib._candidates()
    # The soname first, then the other files, then the system's; no checkout build/ here.
    assert [origin for origin, _ in got] == ["package directory", "package directory",
                                             "ctypes.util.find_library('aqs')"]
    assert [os.path.basename(p) for _, p in got] == ["libaqs.so.%d" % _lib.VERSION_MAJOR,
                                                     "libaqs.so", "libaqs.so.0"]
    monkeypatch.setenv("AQS_LIBRARY", "libaqs.so.0")
    assert _lib._candidates() == [("AQS_LIBRARY", "libaqs.so.0")]


def test_checkout_build_dir_only_in_the_checkout(tmp_path, monkeypatch):
    assert _lib._checkout_build_dir() == os.path.join(REPO, "build")
    installed = tmp_path / "lib" / "python3" / "site-packages" / "aqs"
    installed.mkdir(parents=True)
    monkeypatch.setattr(_lib, "PACKAGE_DIR", str(installed))
    assert _lib._checkout_build_dir() is None
