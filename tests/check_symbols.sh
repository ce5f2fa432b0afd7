#!/usr/bin/env bash
# The shared library exports exactly the functions declared in include/aqs.h
# (the committed list tests/symbols.txt), all prefixed aqs_.
set -euo pipefail
lib=$1
exported=$(nm -D --defined-only "$lib" | awk '$2 == "T" {print $3}' | sed 's/@.*//' | sort)
expected=$(sort tests/symbols.txt)
declared=$(grep -o '^AQS_API [^(]*(' include/aqs.h | sed 's/($//; s/.*[ *]//' | sort)
fail=0
# Anything else the library defines dynamically (data, weak, versioned
# objects) apart from the version-script node aqs_0 is an export too.
others=$(nm -D --defined-only "$lib" | awk '$2 != "T" && $3 !~ /^aqs_[0-9]+$/ {print $3}')
if [ -n "$others" ]; then
    echo "check_symbols: non-function symbols exported: $others"
    fail=1
fi
if [ "$exported" != "$expected" ]; then
    echo "check_symbols: exported symbols differ from tests/symbols.txt:"
    diff <(echo "$expected") <(echo "$exported") || true
    fail=1
fi
if [ "$declared" != "$expected" ]; then
    echo "check_symbols: functions declared in include/aqs.h differ from tests/symbols.txt:"
    diff <(echo "$expected") <(echo "$declared") || true
    fail=1
fi
if echo "$exported" | grep -v '^aqs_' >/dev/null; then
    echo "check_symbols: exported symbols without the aqs_ prefix"
    fail=1
fi
# Not only the dynamic table: no global symbol of the library's own symbol table lacks
# the prefix either (the static library is checked by tests/check_static.sh).
unprefixed=$(nm -g --defined-only "$lib" | awk 'NF == 3 && $3 !~ /^aqs/ {print $3}')
if [ -n "$unprefixed" ]; then
    echo "check_symbols: global symbols without the aqs prefix in $lib:" $unprefixed
    fail=1
fi
soname=$(objdump -p "$lib" | awk '/SONAME/ {print $2}')
major=$(sed -n 's/^#define AQS_VERSION_MAJOR \([0-9]*\).*/\1/p' include/aqs.h)
if [ "$soname" != "libaqs.so.$major" ]; then
    echo "check_symbols: soname is '$soname', expected libaqs.so.$major"
    fail=1
fi
n=$(echo "$exported" | wc -l)
if [ $fail -eq 0 ]; then echo "check_symbols: $n exported symbols, all declared, soname $soname"; fi
exit $fail
