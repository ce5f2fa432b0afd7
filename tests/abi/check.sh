#!/usr/bin/env bash
# The shared library's ABI against the committed baseline of the release (docs/abi.md).
#   check.sh LIB BASELINE           compare: fails on removed or changed functions and
#                                   types, reports (and passes) added functions
#   check.sh --update LIB BASELINE  rewrite BASELINE from LIB (make abi-baseline)
# Size-versioned structs (first member `uint32_t size`, found in include/aqs.h) may grow
# at their end: those insertions are suppressed, any other change of them is not.
set -euo pipefail
update=0
if [ "${1:-}" = "--update" ]; then update=1; shift; fi
lib=$1 baseline=$2
for tool in abidw abidiff; do
    if ! command -v $tool >/dev/null; then
        echo "check_abi: $tool not found: install the Debian package abigail-tools (make deps)"
        exit 1
    fi
done
# Only the public types (include/), no paths of this machine: the dump is reproducible.
dump() { abidw --no-corpus-path --no-comp-dir-path --no-show-locs --headers-dir include \
               --drop-private-types --out-file "$2" "$1"; }
if [ $update = 1 ]; then
    mkdir -p "$(dirname "$baseline")"
    dump "$lib" "$baseline"
    echo "check_abi: wrote $baseline from $lib ($(grep -c '<elf-symbol ' "$baseline") symbols)"
    exit 0
fi
if [ ! -f "$baseline" ]; then
    echo "check_abi: no baseline $baseline (make abi-baseline writes it)"
    exit 1
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dump "$lib" "$work/current.abi"
# Structs whose first member is `uint32_t size`.
awk '/^typedef struct [a-z_0-9]+ \{/ { name = $3; next }
     name != "" && NF > 0 { if ($1 == "uint32_t" && $2 == "size;") print name; name = "" }' \
    include/aqs.h > "$work/sized"
: > "$work/aqs.suppr"
while read -r name; do
    printf '[suppress_type]\n  type_kind = struct\n  name = %s\n  has_data_member_inserted_at = end\n  has_size_change = yes\n\n' \
        "$name" >> "$work/aqs.suppr"
done < "$work/sized"
# Pass 1: everything but added symbols must be unchanged (abidiff exit 0).
set +e
abidiff --no-added-syms --suppressions "$work/aqs.suppr" "$baseline" "$work/current.abi" > "$work/incompatible"
rc=$?
set -e
if [ $rc -ne 0 ]; then
    echo "check_abi: incompatible with $baseline (abidiff status $rc):"
    cat "$work/incompatible"
    echo "check_abi: a removed or changed function or type breaks callers built against the release; see docs/abi.md"
    exit 1
fi
# Pass 2: report what was added (abidiff status 4 = ABI change, here only additions).
set +e
abidiff --suppressions "$work/aqs.suppr" "$baseline" "$work/current.abi" > "$work/all"
rc=$?
set -e
if [ $((rc & ~4)) -ne 0 ]; then
    echo "check_abi: abidiff failed (status $rc):"
    cat "$work/all"
    exit 1
fi
added=$(grep -c "^  \[A\] " "$work/all" || true)
grown=$(tr '\n' ' ' < "$work/sized")
echo "check_abi: compatible with $baseline ($(grep -c '<elf-symbol ' "$baseline") symbols in the baseline, $added added; size-versioned structs may grow: ${grown% })"
if [ "$added" -gt 0 ]; then
    grep "^  \[A\] " "$work/all"
    echo "check_abi: additions are compatible; at the next release run make abi-baseline (docs/abi.md)"
fi
