#!/usr/bin/env bash
# Install what is missing of the project's dependencies (Debian packages, PyPI).
#   tools/deps.sh           what make check needs (make deps; make check and make demo
#                           call it, make / make lib never do)
#   tools/deps.sh bench     also the benchmark plots' dependency, matplotlib
#                           (`make bench-plots` / `make bench` call it so)
#   tools/deps.sh --peers   also the optional peers of bench/peers.py (make peers):
#                           pin (Pinocchio) and mujoco from PyPI
set -euo pipefail
peers=0
[ "${1:-}" = "--peers" ] && peers=1
# cmake: the CMake consumer of tests/install/run.sh; abigail-tools: abidw/abidiff of
# tests/abi/check.sh; libexpat1-dev: URDF loading (optional for the library, tested). clang and its libFuzzer runtime (libclang-rt-<major>-dev, the one of
# Debian's default clang: 14 on bookworm): make check-fuzz (docs/testing.md).
pkgs=(libccd-dev libcmocka-dev libeigen3-dev nlohmann-json3-dev pkg-config cmake abigail-tools libexpat1-dev clang)
if command -v clang >/dev/null; then
    pkgs+=("libclang-rt-$(clang -dumpversion | cut -d. -f1)-dev")
else
    pkgs+=(libclang-rt-14-dev)
fi
missing=()
for p in "${pkgs[@]}"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
command -v gcc >/dev/null && command -v g++ >/dev/null || missing+=(gcc g++)
command -v make >/dev/null || missing+=(make)
# A fresh Debian machine may have no Python at all: take Debian's, with pip.
PY=${PYTHON:-python3}
command -v "$PY" >/dev/null || missing+=(python3 python3-pip)
# tests/python/test_install.py installs the package into a fresh venv (Debian: python3-venv).
command -v "$PY" >/dev/null && ! $PY -c "import venv, ensurepip" 2>/dev/null && missing+=(python3-venv)
if [ ${#missing[@]} -gt 0 ]; then
    echo "deps: installing ${missing[*]}"
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi
pymissing=()
$PY -c "import numpy" 2>/dev/null || pymissing+=(numpy)
$PY -c "import pytest" 2>/dev/null || pymissing+=(pytest)
# `pip install --no-build-isolation ./bindings/python` (tests/python/test_install.py)
# needs the build backend locally: setuptools, and wheel for setuptools < 70.1.
$PY -c "import setuptools" 2>/dev/null || pymissing+=(setuptools)
$PY -c "import wheel" 2>/dev/null || pymissing+=(wheel)
if [ "${1:-}" = bench ]; then
    $PY -c "import matplotlib" 2>/dev/null || pymissing+=(matplotlib)
fi
# pip_install PKG...: from PyPI into the Python that runs the tests. Debian's
# own python3 is "externally managed" (PEP 668) and refuses a plain
# `pip install`; there the packages go into the user's site-packages
# (--user --break-system-packages), which the same python3 imports.
pip_install() {
    if ! $PY -m pip --version >/dev/null 2>&1; then
        echo "deps: installing python3-pip"
        SUDO=""
        [ "$(id -u)" -ne 0 ] && SUDO="sudo"
        $SUDO apt-get update -qq
        DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3-pip >/dev/null
    fi
    if $PY -c 'import sys, sysconfig, os; sys.exit(0 if os.path.exists(os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED")) else 1)'; then
        $PY -m pip install -q --user --break-system-packages "$@"
    else
        $PY -m pip install -q "$@"
    fi
}
# The real-model corpus of tests/python/test_real_models.py: 69 robot URDFs (a 131 MB wheel
# with meshes; no Python dependency beyond cmeel).
$PY -c "import importlib.metadata as m; m.distribution('example-robot-data')" 2>/dev/null \
    || pymissing+=(example-robot-data)
if [ ${#pymissing[@]} -gt 0 ]; then
    echo "deps: pip installing ${pymissing[*]}"
    pip_install "${pymissing[@]}"
fi
if [ "$peers" = 1 ]; then
    peermissing=()
    $PY -c "import pinocchio" 2>/dev/null || peermissing+=(pin)
    $PY -c "import mujoco" 2>/dev/null || peermissing+=(mujoco)
    if [ ${#peermissing[@]} -gt 0 ]; then
        echo "deps: pip installing the bench peers ${peermissing[*]}"
        pip_install "${peermissing[@]}"
    fi
fi
