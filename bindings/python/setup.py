"""Build the aqs Python package with its own libaqs.so, compiled from the C sources.

`pip install ./bindings/python` (or `pip wheel ./bindings/python`) runs this
through setuptools (pyproject.toml). The package itself is pure Python
(ctypes); the one compiled file is the C library, built here as
aqs/libaqs.so.MAJOR from the repository's src/*/*.c with the C compiler, the
way the Makefile builds build/libaqs.so (same flags and version script; no
-Werror), linked against libccd (Debian: libccd-dev to build, libccd2 at run
time), and against expat for URDF loading when pkg-config finds it (Debian:
libexpat1-dev; AQS_URDF=0 leaves it out, as in the Makefile). The wheel is therefore platform-specific but works with any Python 3
(tag py3-none-<platform>).

Where the C sources are, first found of:
  $AQS_SOURCE_DIR                  a checkout (has include/aqs.h and src/*/*.c)
  <this directory>/csrc            the copy an sdist carries
  <this directory>/../..           the repository this directory belongs to
Environment: CC (default cc), CFLAGS, CPPFLAGS and LDFLAGS are added to the
compile and link commands; AQS_BUILD_JOBS sets how many files compile at once
(default: the number of CPUs, at most 4).
"""

import concurrent.futures
import glob
import os
import re
import shlex
import shutil
import subprocess

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.sdist import sdist

try:  # setuptools >= 70.1 carries bdist_wheel; before, the wheel package does
    from setuptools.command.bdist_wheel import bdist_wheel
except ImportError:
    try:
        from wheel.bdist_wheel import bdist_wheel
    except ImportError:
        bdist_wheel = None

HERE = os.path.dirname(os.path.abspath(__file__))


def _is_source_root(root):
    return (os.path.isfile(os.path.join(root, "include", "aqs.h"))
            and bool(glob.glob(os.path.join(root, "src", "*", "*.c"))))


def source_root():
    """The directory holding include/aqs.h and src/*/*.c (see the module docstring)."""
    candidates = [os.environ.get("AQS_SOURCE_DIR"), os.path.join(HERE, "csrc"),
                  os.path.join(HERE, "..", "..")]
    for root in candidates:
        if root and _is_source_root(root):
            return os.path.abspath(root)
    raise RuntimeError(
        "aqs: cannot find the C sources of libaqs (include/aqs.h and src/*/*.c) in %s. Install "
        "from the repository's bindings/python directory (pip install ./bindings/python), "
        "or set AQS_SOURCE_DIR to a checkout of the repository."
        % ", ".join(os.path.abspath(c) for c in candidates if c))


def header_version(root):
    """(MAJOR, MINOR, PATCH) from include/aqs.h, as the Makefile reads them."""
    with open(os.path.join(root, "include", "aqs.h")) as header:
        text = header.read()
    return tuple(int(re.search(r"^#define AQS_VERSION_%s (\d+)" % part, text, re.M).group(1))
                 for part in ("MAJOR", "MINOR", "PATCH"))


def _urdf_support():
    """Whether to build the URDF loader (src/api/urdf.c with expat), as the
    Makefile decides: AQS_URDF=0/1 when set, else whether pkg-config finds
    expat (Debian: libexpat1-dev). Returns (cflags, libs)."""
    wanted = os.environ.get("AQS_URDF")
    if wanted is None:
        try:
            wanted = "1" if subprocess.run(["pkg-config", "--exists", "expat"]).returncode == 0 \
                else "0"
        except OSError:
            wanted = "0"
    if wanted != "1":
        return [], []
    def query(option, fallback):
        try:
            out = subprocess.run(["pkg-config", option, "expat"], capture_output=True, text=True)
            return shlex.split(out.stdout) if out.returncode == 0 and out.stdout.strip() else fallback
        except OSError:
            return fallback
    return ["-DAQS_HAVE_EXPAT"] + query("--cflags", []), query("--libs", ["-lexpat"])


def _env_flags(name):
    return shlex.split(os.environ.get(name, ""))


class build_libaqs(build_ext):
    """Compiles src/*/*.c (one directory per layer) into aqs/libaqs.so.MAJOR (instead of
    Python extensions)."""

    def run(self):
        root = source_root()
        major = header_version(root)[0]
        name = "libaqs.so.%d" % major
        if self.inplace or getattr(self, "editable_mode", False):
            package_dir = os.path.join(HERE, "aqs")
        else:
            package_dir = os.path.join(self.build_lib, "aqs")
        os.makedirs(package_dir, exist_ok=True)
        objects_dir = os.path.join(self.build_temp, "libaqs")
        os.makedirs(objects_dir, exist_ok=True)

        cc = shlex.split(os.environ.get("CC") or "cc")
        # One -I per layer directory that holds headers, as the Makefile's SRC_INC.
        layer_dirs = sorted({os.path.dirname(h)
                             for h in glob.glob(os.path.join(root, "src", "*", "*.h"))})
        cflags = (["-std=c99", "-O2", "-funroll-loops", "-fPIC", "-fvisibility=hidden",
                   "-DAQS_BUILDING_LIBRARY", "-I" + os.path.join(root, "include")]
                  + ["-I" + d for d in layer_dirs]
                  + _env_flags("CPPFLAGS") + _env_flags("CFLAGS"))
        urdf_cflags, urdf_libs = _urdf_support()
        cflags += urdf_cflags
        sources = sorted(glob.glob(os.path.join(root, "src", "*", "*.c")))

        def compile_one(source):
            layer = os.path.basename(os.path.dirname(source))
            obj = os.path.join(objects_dir, layer + "-" + os.path.basename(source)[:-2] + ".o")
            command = cc + cflags + ["-c", source, "-o", obj]
            result = subprocess.run(command, capture_output=True, text=True)
            if result.returncode != 0:
                raise RuntimeError("aqs: compiling %s failed:\n%s\n%s"
                                   % (source, " ".join(command), result.stderr))
            return obj

        jobs = int(os.environ.get("AQS_BUILD_JOBS") or min(os.cpu_count() or 1, 4))
        print("aqs: compiling %d C files of %s with %s (%d at a time)"
              % (len(sources), root, " ".join(cc), jobs))
        with concurrent.futures.ThreadPoolExecutor(max(jobs, 1)) as pool:
            objects = list(pool.map(compile_one, sources))

        target = os.path.join(package_dir, name)
        version_script = os.path.join(root, "src", "aqs.map")
        link = (cc + ["-shared", "-Wl,-soname," + name, "-Wl,--no-undefined"]
                + (["-Wl,--version-script=" + version_script]
                   if os.path.isfile(version_script) else [])
                + _env_flags("LDFLAGS") + ["-o", target] + objects + ["-lccd"] + urdf_libs + ["-lm"])
        result = subprocess.run(link, capture_output=True, text=True)
        if result.returncode != 0:
            hint = ""
            if "lccd" in result.stderr:
                hint = ("\naqs: libccd is missing: install Debian's libccd-dev "
                        "(pkg-config name: ccd)")
            raise RuntimeError("aqs: linking %s failed:\n%s\n%s%s"
                               % (target, " ".join(link), result.stderr, hint))
        # An older library of another name must not shadow the new one.
        for stale in glob.glob(os.path.join(package_dir, "libaqs.so*")):
            if os.path.basename(stale) != name:
                os.remove(stale)
        self._outputs = [target]

    def get_outputs(self):
        return list(getattr(self, "_outputs", []))

    def get_output_mapping(self):  # setuptools' editable installs
        return {}


class sdist_with_sources(sdist):
    """An sdist carries the C sources in csrc/, so a wheel builds from it alone."""

    def make_release_tree(self, base_dir, files):
        super().make_release_tree(base_dir, files)
        root = source_root()
        for pattern in ("include/aqs.h", "src/*/*.c", "src/*/*.h", "src/aqs.map"):
            for path in glob.glob(os.path.join(root, pattern)):
                relative = os.path.relpath(path, root)
                destination = os.path.join(base_dir, "csrc", relative)
                os.makedirs(os.path.dirname(destination), exist_ok=True)
                shutil.copy2(path, destination)


commands = {"build_ext": build_libaqs, "sdist": sdist_with_sources}

if bdist_wheel is not None:
    class bdist_wheel_any_python(bdist_wheel):
        """The wheel holds a C library, not a Python extension: any Python 3
        on this platform (py3-none-<platform>)."""

        def finalize_options(self):
            super().finalize_options()
            self.root_is_pure = False

        def get_tag(self):
            platform = super().get_tag()[2]
            return "py3", "none", platform

    commands["bdist_wheel"] = bdist_wheel_any_python

# One placeholder extension makes setuptools run build_ext and mark the
# distribution as platform-specific; build_libaqs replaces what it builds.
setup(ext_modules=[Extension("aqs.libaqs", sources=[])], cmdclass=commands)
