#!/usr/bin/env bash
# make bench-peer: Pinocchio 4.1's articulated-body algorithm against aqs's exact
# pass on the same models and states (bench/pinpeer_main.cpp; docs/bench.md,
# "Exact pass at memory speed"). Installs the Pinocchio and Boost headers from
# PyPI (the wheels libpinocchio 4.1.0 and cmeel-boost, no dependencies, into
# build/pin; nothing outside build/), builds the program with -O3 -march=native,
# runs the interleaved timing, then callgrind for the instructions per joint of
# both sides. Skipped, with a message and exit 0, when the headers cannot be
# installed (offline) or valgrind is missing (the counts only).
#   tools/bench_peer.sh BUILD_DIR LIBAQS_INTERNAL_A "LDLIBS" [ROUNDS] [CASES]
set -euo pipefail
BUILD=${1:-build}
INTLIB=${2:-$BUILD/libaqs_internal.a}
LIBS=${3:--lccd -lexpat -lm}
ROUNDS=${4:-9}
CASES=${5:-chain30:30,chain:1000,molecule:5000,molecule:50000,millipede:13000}
PY=${PYTHON:-python3}
PIN=$BUILD/pin
INC=$PIN/cmeel.prefix/include
if [ ! -f "$INC/pinocchio/multibody.hpp" ] || [ ! -d "$INC/boost" ]; then
    echo "bench-peer: installing the libpinocchio 4.1.0 and cmeel-boost headers into $PIN (PyPI)"
    if ! $PY -m pip install --quiet --no-deps --target "$PIN" libpinocchio==4.1.0 "cmeel-boost~=1.90.0" \
        >"$BUILD/pin-install.log" 2>&1; then
        echo "bench-peer: SKIPPED: could not install the Pinocchio headers from PyPI (offline?);"
        echo "            see $BUILD/pin-install.log"
        exit 0
    fi
fi
mkdir -p "$BUILD/peer" "$BUILD/bench"
# Pinocchio's CMake config (lib/cmake/pinocchio) gives its users these definitions.
PINDEF="-DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12"
BIN=$BUILD/bench/pinpeer_main
# build NAME MARCH: the program with -march=MARCH. The timed one is -march=native; the
# one run under callgrind is -march=x86-64-v3 (AVX2: valgrind does not decode AVX-512).
# -w: the warnings are Pinocchio's headers' own (array bounds in joint-composite.hxx).
build() {
    local bin=$BUILD/bench/$1 obj=$BUILD/peer/$1.o
    if [ -x "$bin" ] && [ "$bin" -nt bench/pinpeer_main.cpp ] && [ "$bin" -nt "$INTLIB" ]; then return 0; fi
    echo "bench-peer: compiling bench/pinpeer_main.cpp -march=$2 (Pinocchio's headers: a few minutes)"
    ${CXX:-g++} -std=c++17 -O3 -march="$2" -DNDEBUG -g -w $PINDEF -Iinclude -Ibench -isystem "$INC" \
        -isystem /usr/include/eigen3 -c bench/pinpeer_main.cpp -o "$obj"
    for f in scenes timing urdf; do
        ${CC:-cc} -std=c99 -O2 -g -Iinclude -Ibench -c bench/$f.c -o "$BUILD/peer/$f.o"
    done
    ${CXX:-g++} -o "$bin" "$obj" "$BUILD/peer/scenes.o" "$BUILD/peer/timing.o" "$BUILD/peer/urdf.o" \
        "$INTLIB" $LIBS
}
build pinpeer_main native
echo "bench-peer: load average $(cut -d' ' -f1-3 /proc/loadavg), $(date -u +%FT%TZ), $(git rev-parse --short HEAD 2>/dev/null || echo '?')"
"$BIN" --cases "$CASES" --rounds "$ROUNDS" --reps 5
if ! command -v valgrind >/dev/null || ! command -v callgrind_annotate >/dev/null; then
    echo "bench-peer: instruction counts SKIPPED (valgrind not installed)"
    exit 0
fi
build pinpeer_main_v3 x86-64-v3
echo "instructions per joint (callgrind, -march=x86-64-v3 build, 1 round x 3 passes per case, each side's function inclusive):"
printf "%-10s %8s %12s %12s\n" scene joints "pin instr/j" "aqs instr/j"
for c in ${CASES//,/ }; do
    out="$BUILD/peer/callgrind.${c/:/-}.out"
    valgrind --tool=callgrind --toggle-collect=bench_exact_pass --toggle-collect=peer_pin_aba \
        --callgrind-out-file="$out" "$BUILD/bench/pinpeer_main_v3" --cases "$c" --rounds 1 --reps 3 >"$out.log" 2>&1
    joints=$(sed -n 's/.*: \([0-9]*\) joints, nv.*/\1/p' "$out.log" | head -1)
    ann=$(callgrind_annotate --inclusive=yes "$out" 2>/dev/null)
    # the two functions wrap the 3 timed passes only (not the setup's checks)
    pin=$(awk '/:peer_pin_aba / { gsub(",", "", $1); print $1; exit }' <<<"$ann")
    aqs=$(awk '/:bench_exact_pass / { gsub(",", "", $1); print $1; exit }' <<<"$ann")
    awk -v s="${c%%:*}" -v j="$joints" -v p="$pin" -v a="$aqs" \
        'BEGIN { printf "%-10s %8d %12.0f %12.0f\n", s, j, p / (3 * j), a / (3 * j) }'
done
