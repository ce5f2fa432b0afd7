#!/usr/bin/env bash
# Stage an install with DESTDIR, then build and run a tiny C program against
# it through pkg-config (shared and static), and compile aqs.h as C++.
set -euo pipefail
build=$1 cc=$2 cxx=$3 san=${4:-}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
prefix=/opt/aqs-test
make -s install PREFIX=$prefix DESTDIR="$stage" SANITIZE=$([ -n "$san" ] && echo 1 || echo 0) >/dev/null
root="$stage$prefix"
export PKG_CONFIG_PATH="$root/lib/pkgconfig"
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
$cc -std=c99 -Wall -Werror $san $cflags "$stage/hello.c" -o "$stage/hello_shared" $libs -Wl,-rpath,"$root/lib"
"$stage/hello_shared"
$cc -std=c99 -Wall -Werror $san $cflags "$stage/hello.c" -o "$stage/hello_static" "$root/lib/libaqs.a" $(pkg-config --define-variable=prefix="$root" --libs --static aqs | sed "s/-laqs//")
"$stage/hello_static" >/dev/null
# The header compiles as C++ (extern "C") and as strict C99.
printf '#include <aqs.h>\nint main() { return aqs_version() == AQS_VERSION_NUMBER ? 0 : 1; }\n' > "$stage/hello.cpp"
$cxx -std=c++11 -Wall -Wextra -Werror -pedantic $san $cflags "$stage/hello.cpp" -o "$stage/hello_cpp" $libs -Wl,-rpath,"$root/lib"
"$stage/hello_cpp"
$cc -std=c99 -pedantic -Wall -Wextra -Werror -fsyntax-only $cflags -x c - <<'C'
#include <aqs.h>
C
test -f "$root/lib/libaqs.so.$(sed -n 's/^#define AQS_VERSION_MAJOR \([0-9]*\).*/\1/p' include/aqs.h)"
echo "install: staged install, pkg-config build (shared, static), C++ and C99 header: ok"
