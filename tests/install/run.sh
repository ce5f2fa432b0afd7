#!/usr/bin/env bash
# Stage an install with DESTDIR (and a LIBDIR other than PREFIX/lib), then build and
# run a tiny C program against it through pkg-config (shared and static) and through
# the CMake package (find_package(aqs CONFIG): aqs::aqs, aqs::aqs_static, the version
# check), compile aqs.h as C++, and uninstall.
set -euo pipefail
build=$1 cc=$2 cxx=$3 san=${4:-}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
prefix=/opt/aqs-test
# Debian's multiarch LIBDIR (lib/x86_64-linux-gnu), which CMake searches under a prefix.
arch=$($cc -print-multiarch 2>/dev/null || true)
libdir=$prefix/lib${arch:+/$arch}
sanitize=$([ -n "$san" ] && echo 1 || echo 0)
make -s install PREFIX=$prefix LIBDIR=$libdir DESTDIR="$stage" SANITIZE=$sanitize >/dev/null
root="$stage$prefix"
export PKG_CONFIG_PATH="$stage$libdir/pkgconfig"
grep -qxF 'libdir=${prefix}'"${libdir#$prefix}" "$PKG_CONFIG_PATH/aqs.pc"
# pkg-config reports the configured prefix; point it at the staging root.
cflags=$(pkg-config --define-variable=prefix="$root" --cflags aqs)
libs=$(pkg-config --define-variable=prefix="$root" --libs aqs)
cat > "$stage/hello.c" <<'C'
#include <aqs.h>
#include <stdio.h>
#include <string.h>
int main(void)
{
    aqs_linkage *l = NULL;
    const double com[3] = {0.5, 0, 0}, inertia[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    const double pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    const double g[3] = {0, -9.81, 0};
    double qdd = 0;
    int32_t body = -1;
    if (aqs_version() != AQS_VERSION_NUMBER) return 1;
    if (aqs_linkage_create(&l) != AQS_OK) return 2;
    if (aqs_body_add(l, 2.0, com, inertia, &body) != AQS_OK) return 3;
    if (aqs_joint_add(l, AQS_JOINT_REVOLUTE, AQS_WORLD, body, pos, quat, axis, NULL) != AQS_OK) return 4;
    if (aqs_linkage_finalize(l) != AQS_OK || aqs_linkage_set_gravity(l, g) != AQS_OK) return 5;
    if (aqs_linkage_solve(l) != AQS_OK || aqs_linkage_get_accelerations(l, &qdd, 1) != AQS_OK) return 6;
    aqs_linkage_destroy(l);
    /* rod pendulum: qdd = -m g L / (I_zz + m L^2) = -9.81 / 0.6 */
    printf("installed aqs %s: pendulum qdd = %.6f\n", aqs_version_string(), qdd);
    return (qdd + 9.81 / 0.6) * (qdd + 9.81 / 0.6) < 1e-20 ? 0 : 7;
}
C
$cc -std=c99 -Wall -Werror $san $cflags "$stage/hello.c" -o "$stage/hello_shared" $libs -Wl,-rpath,"$stage$libdir"
"$stage/hello_shared"
$cc -std=c99 -Wall -Werror $san $cflags "$stage/hello.c" -o "$stage/hello_static" "$stage$libdir/libaqs.a" $(pkg-config --define-variable=prefix="$root" --libs --static aqs | sed "s/-laqs//")
"$stage/hello_static" >/dev/null
# The header compiles as C++ (extern "C") and as strict C99.
printf '#include <aqs.h>\nint main() { return aqs_version() == AQS_VERSION_NUMBER ? 0 : 1; }\n' > "$stage/hello.cpp"
$cxx -std=c++11 -Wall -Wextra -Werror -pedantic $san $cflags "$stage/hello.cpp" -o "$stage/hello_cpp" $libs -Wl,-rpath,"$stage$libdir"
"$stage/hello_cpp"
$cc -std=c99 -pedantic -Wall -Wextra -Werror -fsyntax-only $cflags -x c - <<'C'
#include <aqs.h>
C
major=$(sed -n 's/^#define AQS_VERSION_MAJOR \([0-9]*\).*/\1/p' include/aqs.h)
test -f "$stage$libdir/libaqs.so.$major"
# CMake: a consumer project finds the staged package through CMAKE_PREFIX_PATH, links
# the shared (aqs::aqs) and the static (aqs::aqs_static) library and runs both.
if ! command -v cmake >/dev/null; then
    echo "install: cmake not found (Debian package cmake; make deps installs it)"
    exit 1
fi
version=$(sed -n 's/^Version: //p' "$PKG_CONFIG_PATH/aqs.pc")
mkdir -p "$stage/cmake-consumer"
cp "$stage/hello.c" "$stage/cmake-consumer/hello.c"
cat > "$stage/cmake-consumer/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.13)
project(aqs_consumer C)
find_package(aqs $version CONFIG REQUIRED)
if(NOT aqs_VERSION STREQUAL "$version")
  message(FATAL_ERROR "aqs_VERSION is \${aqs_VERSION}, expected $version")
endif()
add_executable(hello_shared hello.c)
target_link_libraries(hello_shared PRIVATE aqs::aqs)
add_executable(hello_static hello.c)
target_link_libraries(hello_static PRIVATE aqs::aqs_static)
CMAKE
cmake_flags=(-DCMAKE_C_COMPILER="$cc" -DCMAKE_C_FLAGS="$san" -DCMAKE_PREFIX_PATH="$root"
             -DCMAKE_BUILD_RPATH="$stage$libdir")
cmake -S "$stage/cmake-consumer" -B "$stage/cmake-build" "${cmake_flags[@]}" > "$stage/cmake.log" 2>&1 \
    || { cat "$stage/cmake.log"; exit 1; }
cmake --build "$stage/cmake-build" > "$stage/cmake-build.log" 2>&1 || { cat "$stage/cmake-build.log"; exit 1; }
"$stage/cmake-build/hello_shared" >/dev/null
"$stage/cmake-build/hello_static" >/dev/null
# The shared target is the one that was linked: libaqs.so.MAJOR is needed, and the
# static program needs no libaqs at all.
needed_shared=$(readelf -d "$stage/cmake-build/hello_shared")
needed_static=$(readelf -d "$stage/cmake-build/hello_static")
if ! grep -q "NEEDED.*libaqs.so.$major" <<< "$needed_shared" || grep -q "NEEDED.*libaqs" <<< "$needed_static"; then
    echo "install: aqs::aqs should link libaqs.so.$major and aqs::aqs_static no libaqs.so"
    exit 1
fi
# SameMajorVersion: any version of this major one up to ours is accepted, a newer minor
# or the next major one refused (a project without languages, one per request).
cat > "$stage/cmake-consumer/probe.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.13)
project(aqs_version_probe NONE)
find_package(aqs ${want} CONFIG QUIET)
message(STATUS "aqs_FOUND=${aqs_FOUND}")
CMAKE
mkdir -p "$stage/probe"
cp "$stage/cmake-consumer/probe.txt" "$stage/probe/CMakeLists.txt"
probe() {
    rm -rf "$stage/probe/build"
    local out
    out=$(cmake -S "$stage/probe" -B "$stage/probe/build" -Dwant="$1" \
              -Daqs_DIR="$stage$libdir/cmake/aqs" 2>&1)
    grep -q "aqs_FOUND=$2" <<< "$out" \
        || { echo "install: find_package(aqs $1) should give aqs_FOUND=$2:"; echo "$out"; exit 1; }
}
minor=$(echo "$version" | cut -d. -f2)
probe "$major.0" 1
probe "$major.$minor" 1
probe "$major.0...<$((major + 1)).0" 1
probe "$major.$((minor + 1))" 0
probe "$((major + 1)).0" 0
# Uninstall with the same variables leaves no file behind.
make -s uninstall PREFIX=$prefix LIBDIR=$libdir DESTDIR="$stage" SANITIZE=$sanitize >/dev/null
left=$(find "$stage/opt" \( -type f -o -type l \) | head)
if [ -n "$left" ]; then
    echo "install: make uninstall left files behind: $left"
    exit 1
fi
echo "install: staged install (LIBDIR $libdir), pkg-config build (shared, static), CMake package (aqs::aqs, aqs::aqs_static, version $version, SameMajorVersion), C++ and C99 header, uninstall: ok"
