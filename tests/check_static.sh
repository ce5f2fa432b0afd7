#!/usr/bin/env bash
# The installed static library hides its internals (issue 15, item 3):
#  1. every global symbol that libaqs.a defines starts with "aqs", and it defines every
#     function of tests/symbols.txt;
#  2. a program that itself defines every internal global name of the internal archive
#     (vec3_dot, heap_push, model_build, ... taken from libaqs_internal.a, not a fixed
#     list) links against libaqs.a, and both the program's own functions and the library
#     (a pendulum against its closed form) give the right answers;
#  3. control: the same program against libaqs_internal.a fails to link (multiple
#     definitions), so step 2 can fail.
# Usage: check_static.sh build/libaqs.a build/libaqs_internal.a CC "SANFLAGS" "LDLIBS"
set -euo pipefail
stlib=$1 intlib=$2 cc=$3 san=${4:-} ldlibs=${5:--lccd -lm}
fail=0
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# nm prints "archive member:" headers and blank lines; keep "ADDR TYPE NAME" lines.
globals() { nm -g --defined-only "$1" | awk 'NF == 3 {print $2, $3}' | sort -u -k2; }

globals "$stlib" > "$work/static"
bad=$(awk '$2 !~ /^aqs/ {print $2}' "$work/static")
if [ -n "$bad" ]; then
    echo "check_static: $stlib defines $(echo "$bad" | wc -l) global symbols without the aqs prefix:" $bad
    fail=1
fi
missing=$(comm -23 <(sort tests/symbols.txt) <(awk '{print $2}' "$work/static" | sort))
if [ -n "$missing" ]; then
    echo "check_static: $stlib lacks public functions:" $missing
    fail=1
fi

globals "$intlib" | awk '$2 !~ /^aqs/' > "$work/internal"
n=$(wc -l < "$work/internal")
if [ "$n" -eq 0 ]; then
    echo "check_static: $intlib has no internal globals: nothing to test against"
    exit 1
fi
{
    echo '#include <aqs.h>'
    echo '#include <stdio.h>'
    i=0
    while read -r type name; do
        i=$((i + 1))
        case $type in
            T) echo "int $name(void);"; echo "int $name(void) { return $i; }" ;;
            *) echo "int $name = $i;" ;;
        esac
    done < "$work/internal"
    echo 'int main(void)'
    echo '{'
    echo '    long sum = 0, expected = 0;'
    i=0
    while read -r type name; do
        i=$((i + 1))
        case $type in
            T) echo "    sum += $name(); expected += $i;" ;;
            *) echo "    sum += $name; expected += $i;" ;;
        esac
    done < "$work/internal"
    cat <<'C'
    aqs_linkage *l = NULL;
    const double com[3] = {0.5, 0, 0}, inertia[9] = {0.01, 0, 0, 0, 0.1, 0, 0, 0, 0.1};
    const double pos[3] = {0, 0, 0}, quat[4] = {1, 0, 0, 0}, axis[3] = {0, 0, 1};
    const double g[3] = {0, -9.81, 0};
    double qdd = 0, err;
    int32_t body = -1;
    if (sum != expected) { printf("own definitions: sum %ld, expected %ld\n", sum, expected); return 1; }
    if (aqs_linkage_create(&l) != AQS_OK) return 2;
    if (aqs_body_add(l, 2.0, com, inertia, &body) != AQS_OK) return 3;
    if (aqs_joint_add(l, AQS_JOINT_REVOLUTE, AQS_WORLD, body, pos, quat, axis, NULL) != AQS_OK) return 4;
    if (aqs_linkage_finalize(l) != AQS_OK || aqs_linkage_set_gravity(l, g) != AQS_OK) return 5;
    if (aqs_linkage_solve(l) != AQS_OK || aqs_linkage_get_accelerations(l, &qdd, 1) != AQS_OK) return 6;
    aqs_linkage_destroy(l);
    /* rod pendulum: qdd = -m g L / (I_zz + m L^2) = -9.81 / 0.6; tolerance 1e-12 relative */
    err = (qdd + 9.81 / 0.6) / (9.81 / 0.6);
    if (err > 1e-12 || err < -1e-12) { printf("pendulum qdd %.17g\n", qdd); return 7; }
    return 0;
}
C
} > "$work/names.c"

# shellcheck disable=SC2086
if ! $cc -std=c99 -Iinclude $san "$work/names.c" -o "$work/names" "$stlib" $ldlibs 2> "$work/link.log"; then
    echo "check_static: a program defining the $n internal names does not link against $stlib:"
    head -5 "$work/link.log"
    fail=1
elif ! "$work/names"; then
    echo "check_static: the program linked against $stlib fails"
    fail=1
fi
# shellcheck disable=SC2086
# (every member of the internal archive: which ones a plain link pulls in depends
# on which file defines what, e.g. whether api.o still defines an internal name)
if $cc -std=c99 -Iinclude $san "$work/names.c" -o "$work/control" -Wl,--whole-archive "$intlib" \
    -Wl,--no-whole-archive $ldlibs 2> "$work/control.log"; then
    echo "check_static: control failed: the program also links against $intlib"
    fail=1
elif ! grep -q "multiple definition" "$work/control.log"; then
    echo "check_static: control failed for another reason than multiple definitions:"
    head -5 "$work/control.log"
    fail=1
fi
if [ $fail -eq 0 ]; then
    echo "check_static: $(wc -l < "$work/static") globals of $stlib, all aqs-prefixed; a program defining the $n internal names links and runs (against $intlib it does not link)"
fi
exit $fail
