# aqs -- adaptive quasi-statics. See README.md.
#   make            build/libaqs.so.X.Y.Z and build/libaqs.a (needs only a C compiler and
#                   libccd; installs nothing)
#   make check      every test (layers, C, C++ reference, Python, install, ABI, a short fuzz run);
#                   SANITIZE=1 under ASan/UBSan, DEBUG=1 at -O0; both check src/base/invariant.h's asserts
#   make fuzz       build/fuzz/aqs_fuzz, the libFuzzer target (clang; docs/testing.md)
#   make demo       the README's "run it" command
#   make bench      quick benchmark sweep + plots (docs/bench/); FULL=1 the paper's protocol
#   make bench-scaling  molecule 10k..1M joints (docs/bench/scaling.jsonl)
#   make bench-peer Pinocchio's ABA against aqs's exact pass, interleaved + callgrind
#   make bench-hard     hard-case suite, long mode (docs/hardcases.md); check-hard: quick, in check
#   make install    PREFIX=/usr/local LIBDIR=$(PREFIX)/lib INCLUDEDIR=$(PREFIX)/include DESTDIR=
#   make uninstall  the same variables: removes what install put there
#   make deps       install the Debian/PyPI packages the tests and benchmarks need
#                   (make check, demo and bench call it; make / make lib never do)
# Honoured from the command line or the environment: CC, CXX, CFLAGS, CXXFLAGS, CPPFLAGS,
# LDFLAGS (appended after the project's own flags), PREFIX, LIBDIR, INCLUDEDIR, DESTDIR.
# -Werror only when CI=true or WERROR=1 (.ci/run passes WERROR=1).

SHELL := /bin/bash
PREFIX ?= /usr/local
LIBDIR ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
DESTDIR ?=
PYTHON ?= python3
OBJCOPY ?= objcopy

MAJOR := $(shell sed -n 's/^\#define AQS_VERSION_MAJOR \([0-9]*\).*/\1/p' include/aqs.h)
MINOR := $(shell sed -n 's/^\#define AQS_VERSION_MINOR \([0-9]*\).*/\1/p' include/aqs.h)
PATCH := $(shell sed -n 's/^\#define AQS_VERSION_PATCH \([0-9]*\).*/\1/p' include/aqs.h)
VERSION := $(MAJOR).$(MINOR).$(PATCH)

ifeq ($(SANITIZE),1)
BUILD := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
OPT := -O1 -g
DEBUG_DEFS := -DAQS_DEBUG
else ifeq ($(DEBUG),1)
BUILD := build/debug
SANFLAGS :=
OPT := -O0 -g
DEBUG_DEFS := -DAQS_DEBUG
else
BUILD := build
SANFLAGS :=
OPT := -O2 -funroll-loops -g
DEBUG_DEFS :=
endif

# make's built-in default CC is cc and CXX is g++; both may be overridden.
CC ?= cc
CXX ?= c++
ifneq ($(filter true 1,$(CI) $(WERROR)),)
WERROR_FLAG := -Werror
else
WERROR_FLAG :=
endif
WARN := -Wall -Wextra $(WERROR_FLAG) -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
# The project's flags come first, the user's CPPFLAGS / CFLAGS after them (so -O3 or -g0
# there wins, while -std=c99 -fPIC -fvisibility=hidden stay).
# AQS_DEBUG (SANITIZE=1, DEBUG=1): the internal invariants of src/base/invariant.h are checked.
# src/ is one directory per layer (src/LAYERS, docs/design.md); its headers are found
# through one -I per layer directory that holds headers, so an #include names the file only.
SRC_INC := $(addprefix -I,$(sort $(patsubst %/,%,$(dir $(wildcard src/*/*.h)))))
CPPFLAGS_LIB := -DAQS_BUILDING_LIBRARY $(DEBUG_DEFS) -Iinclude $(SRC_INC)
CFLAGS_LIB := -std=c99 $(OPT) $(WARN) -fPIC -fvisibility=hidden $(SANFLAGS)
CFLAGS_TEST := -std=c99 $(OPT) -Wall -Wextra $(WERROR_FLAG) -Wno-unused-parameter -Iinclude $(SRC_INC) $(SANFLAGS)
CXXFLAGS_TEST := -std=c++17 $(OPT) -Wall -Wextra $(WERROR_FLAG) -Wno-unused-parameter -Iinclude \
                 -I/usr/include/eigen3 $(SANFLAGS)
# libccd through pkg-config (module ccd) when it is there, else plain -lccd.
ifndef CCD_LIBS
CCD_CFLAGS := $(shell pkg-config --cflags ccd 2>/dev/null)
CCD_LIBS := $(shell pkg-config --libs ccd 2>/dev/null || echo -lccd)
endif
LDLIBS := $(CCD_LIBS) -lm

# URDF loading (src/api/urdf.c) with expat, an optional feature: on when
# pkg-config finds expat, off with AQS_URDF=0 (the load functions then return
# AQS_ESTATE saying so). AQS_URDF=1 insists on it.
AQS_URDF ?= $(shell pkg-config --exists expat 2>/dev/null && echo 1 || echo 0)
ifeq ($(AQS_URDF),1)
CFLAGS_LIB += -DAQS_HAVE_EXPAT $(shell pkg-config --cflags expat 2>/dev/null)
LDLIBS += $(or $(shell pkg-config --libs expat 2>/dev/null),-lexpat)
endif

SRCS := $(sort $(wildcard src/*/*.c))
SRC_HDRS := $(sort $(wildcard src/*/*.h))
OBJS := $(patsubst src/%.c,$(BUILD)/obj/%.o,$(SRCS))
SONAME := libaqs.so.$(MAJOR)
SHLIB := $(BUILD)/libaqs.so.$(VERSION)
# libaqs.a (installed): one partially linked object whose only global symbols are the
# public aqs_ functions. libaqs_internal.a (never installed): the plain objects, for the
# C unit tests and the bench programs, which call internal functions.
STLIB := $(BUILD)/libaqs.a
INTLIB := $(BUILD)/libaqs_internal.a

C_TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(sort $(wildcard tests/test_*.c)))
CXX_TESTS := $(patsubst tests/reference/%.cpp,$(BUILD)/tests/reference/%,$(sort $(wildcard tests/reference/test_*.cpp)))
TEST_SUPPORT := $(sort $(wildcard tests/support/*.c))

BENCH_MAINS := bench/demo.c bench/aqs_bench.c $(wildcard bench/*_main.c) bench/collide_bench.c
BENCH_MAINS += bench/urdf_export.c
BENCH_SUPPORT := $(filter-out $(BENCH_MAINS),$(sort $(wildcard bench/*.c)))

.PHONY: all lib check check-c check-reference check-python check-install check-symbols check-layers \
        check-abi abi-baseline deps demo bench bench-peer bench-scaling bench-plots bench-collide \
        check-bench install uninstall clean

all: lib
lib: $(SHLIB) $(STLIB)

DEPS_STAMP := build/.deps-ok
deps: $(DEPS_STAMP)
$(DEPS_STAMP): tools/deps.sh
	@bash tools/deps.sh
	@mkdir -p build && touch $@

# The library needs only libccd: a missing one stops the build with one message. The
# test tools (make deps) are installed first only when a goal needs them, so that on a
# fresh Debian machine `make check` / `make demo` set themselves up.
CCD_STAMP := $(BUILD)/.ccd-ok
$(CCD_STAMP):
	@mkdir -p $(dir $@)
	@if printf '#include <ccd/ccd.h>\nint main(void) { ccd_t c; CCD_INIT(&c); return c.max_iterations == 0; }\n' \
	    | $(CC) $(CPPFLAGS) $(CCD_CFLAGS) -x c - -o $(BUILD)/.ccd-probe $(LDFLAGS) $(LDLIBS) >/dev/null 2>&1; \
	then rm -f $(BUILD)/.ccd-probe; touch $@; \
	else echo "aqs: libccd not found (header ccd/ccd.h or -lccd): install the Debian package libccd-dev (apt-get install libccd-dev), or make its pkg-config module 'ccd' visible (PKG_CONFIG_PATH) or pass CPPFLAGS=-I... LDFLAGS=-L..." >&2; exit 1; fi
DEPS_GOALS := check check-% demo bench bench-% peers
ifneq ($(filter $(DEPS_GOALS),$(MAKECMDGOALS)),)
BUILD_PREREQ := $(DEPS_STAMP) $(CCD_STAMP)
$(CCD_STAMP): | $(DEPS_STAMP)
else
BUILD_PREREQ := $(CCD_STAMP)
endif

$(BUILD)/obj/%.o: src/%.c $(SRC_HDRS) include/aqs.h | $(BUILD_PREREQ)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) $(CPPFLAGS_LIB) $(CPPFLAGS) $(CCD_CFLAGS) $(CFLAGS_LIB) $(CFLAGS) -c $< -o $@

$(SHLIB): $(OBJS) src/aqs.map
	@echo "  LD      $@"
	@$(CC) -shared -Wl,-soname,$(SONAME) -Wl,--version-script=src/aqs.map -Wl,--no-undefined \
	    $(SANFLAGS) $(CFLAGS) $(LDFLAGS) -o $@ $(OBJS) $(LDLIBS)
	@ln -sf libaqs.so.$(VERSION) $(BUILD)/$(SONAME)
	@ln -sf $(SONAME) $(BUILD)/libaqs.so

# Internals are compiled with -fvisibility=hidden and the public functions carry AQS_API
# (visibility default): after one partial link, --localize-hidden turns every internal
# global into a local symbol, so a program that defines its own vec3_dot links.
$(STLIB): $(OBJS)
	@echo "  AR      $@"
	@rm -f $@ $(BUILD)/aqs_static.o
	@$(CC) -r -nostdlib -o $(BUILD)/aqs_static.o $(OBJS)
	@$(OBJCOPY) --localize-hidden $(BUILD)/aqs_static.o
	@ar rcs $@ $(BUILD)/aqs_static.o

$(INTLIB): $(OBJS)
	@echo "  AR      $@"
	@rm -f $@
	@ar rcs $@ $(OBJS)

# C unit tests link the internal archive so they can reach internal functions.
$(BUILD)/tests/%: tests/%.c $(TEST_SUPPORT) $(wildcard tests/support/*.h) $(INTLIB) | $(BUILD_PREREQ)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) $(CFLAGS_TEST) -Itests/support $(TEST_EXTRA) $(CPPFLAGS) $(CFLAGS) $(LDFLAGS) -o $@ $< $(TEST_SUPPORT) \
	    $(TEST_EXTRA_SRC) $(INTLIB) -lcmocka $(LDLIBS)
# The world-space bound is checked on the benchmark scenes too (bench/scenes.c).
$(BUILD)/tests/test_worldbound: bench/scenes.c bench/scenes.h
$(BUILD)/tests/test_worldbound: TEST_EXTRA := -Ibench
$(BUILD)/tests/test_worldbound: TEST_EXTRA_SRC := bench/scenes.c
# Several linkages in several threads at once (POSIX threads).
$(BUILD)/tests/test_threads: TEST_EXTRA := -pthread

$(BUILD)/tests/reference/%: tests/reference/%.cpp $(wildcard tests/reference/*.hpp) $(SHLIB)
	@mkdir -p $(dir $@)
	@echo "  CXX     $<"
	@$(CXX) $(CXXFLAGS_TEST) $(CPPFLAGS) $(CXXFLAGS) $(LDFLAGS) -o $@ $< -L$(BUILD) \
	    -Wl,-rpath,$(abspath $(BUILD)) -laqs $(LDLIBS)

check: check-layers check-symbols check-abi check-c check-reference check-hard check-python check-install check-bench check-fuzz
	@echo "make check: all suites passed ($(if $(SANITIZE),sanitized,plain) build)"

# One-way layers (src/LAYERS, docs/design.md): every call between the objects goes down a
# layer or to a sibling its line lists, checked from the objects' undefined symbols; then
# the checker's own test (generated objects and bad maps that must fail).
check-layers: $(OBJS)
	@$(PYTHON) tests/check_layers.py --layers src/LAYERS --src src --objdir $(BUILD)/obj
	@$(PYTHON) tests/check_layers_test.py "$(CC)" $(BUILD)/obj > $(BUILD)/check_layers_test.log \
	    || { cat $(BUILD)/check_layers_test.log; exit 1; }
	@tail -n 1 $(BUILD)/check_layers_test.log

# Exports of the shared library; globals of the static library (all aqs-prefixed, and a
# program defining the internal archive's names links against it).
check-symbols: $(SHLIB) $(STLIB) $(INTLIB)
	@bash tests/check_symbols.sh $(SHLIB) src/aqs.map
	@bash tests/check_static.sh $(STLIB) $(INTLIB) "$(CC)" "$(SANFLAGS)" "$(LDLIBS)"

# ABI against the committed baseline of the release (docs/abi.md): removed or changed
# functions and types fail, added functions are reported. `make abi-baseline` rewrites it.
ABI_BASELINE := tests/abi/libaqs.abi
check-abi: $(SHLIB)
	@bash tests/abi/check.sh $(SHLIB) $(ABI_BASELINE)
abi-baseline: $(SHLIB)
	@bash tests/abi/check.sh --update $(SHLIB) $(ABI_BASELINE)

check-c: $(C_TESTS)
	@set -e; for t in $(C_TESTS); do echo "== $$t"; $$t; done

check-reference: $(CXX_TESTS)
	@set -e; for t in $(CXX_TESTS); do echo "== $$t"; AQS_VECTORS=$(abspath tests/vectors) $$t; done

ifeq ($(SANITIZE),1)
# Python loads the library into an uninstrumented interpreter: preload the runtime.
PY_ENV := LD_PRELOAD="$$($(CC) -print-file-name=libasan.so) $$($(CC) -print-file-name=libubsan.so)" \
          ASAN_OPTIONS=detect_leaks=0
else
PY_ENV :=
endif
# The hard-case suite of issue 12 (tests/reference/hardcases.cpp, docs/hardcases.md): every
# solver against an extended-precision (__float128) reference. check-hard: quick mode
# (< 60 s); bench-hard: chains to 10^6 links (~GBs, tens of minutes), JSON Lines in
# docs/hardcases/. hardref.so: the same reference for Python (tests/python/test_real_models.py).
HARDCASES := $(BUILD)/tests/reference/hardcases
HARDREF_SO := $(BUILD)/tests/reference/libhardref.so
$(HARDCASES): tests/reference/hardcases.cpp $(wildcard tests/reference/*.hpp) $(SHLIB)
	@mkdir -p $(dir $@)
	@echo "  CXX     $<"
	@$(CXX) $(CXXFLAGS_TEST) -fext-numeric-literals $(CPPFLAGS) $(CXXFLAGS) $(LDFLAGS) -o $@ $< -L$(BUILD) -Wl,-rpath,$(abspath $(BUILD)) -laqs -lquadmath $(LDLIBS)
$(HARDREF_SO): tests/reference/hardref_c.cpp tests/reference/hard_reference.hpp $(SHLIB)
	@mkdir -p $(dir $@)
	@echo "  CXX     $<"
	@$(CXX) $(CXXFLAGS_TEST) -fext-numeric-literals -shared -fPIC $(CPPFLAGS) $(CXXFLAGS) $(LDFLAGS) -o $@ $< -L$(BUILD) -Wl,-rpath,$(abspath $(BUILD)) -laqs -lquadmath $(LDLIBS)
.PHONY: check-hard bench-hard
check-hard: $(HARDCASES)
	$(HARDCASES) --json $(abspath $(BUILD))/hardcases-quick.jsonl
	$(HARDCASES) --dca-form phi --json $(abspath $(BUILD))/hardcases-quick-phi.jsonl
	AQS_SIMD=sse2 $(HARDCASES) --json $(abspath $(BUILD))/hardcases-quick-sse2.jsonl > /dev/null
	cmp $(abspath $(BUILD))/hardcases-quick.jsonl $(abspath $(BUILD))/hardcases-quick-sse2.jsonl
	@echo "== the same cases written in millimetres (--length-unit 1000)"
	$(HARDCASES) --length-unit 1000 --json $(abspath $(BUILD))/hardcases-quick-mm.jsonl
# The SIMD kernels of src/solve/dca.c, rounding.c, frames.c and src/base/dense.c against their scalar code (docs/testing.md): the
# AVX kernels (where the processor has AVX), the SSE2 ones (AQS_SIMD=sse2: the path of a
# processor without AVX) and the library built again with __SSE2__ undefined
# (build/scalar) must give the same hard-case JSON, byte for byte.
.PHONY: check-scalar
check-scalar: $(HARDCASES)
	$(MAKE) --no-print-directory BUILD=build/scalar CFLAGS_LIB="$(CFLAGS_LIB) -U__SSE2__" build/scalar/tests/reference/hardcases
	$(HARDCASES) --json $(abspath $(BUILD))/hardcases-simd.jsonl > /dev/null
	AQS_SIMD=sse2 $(HARDCASES) --json $(abspath $(BUILD))/hardcases-sse2.jsonl > /dev/null
	build/scalar/tests/reference/hardcases --json $(abspath $(BUILD))/hardcases-scalar.jsonl > /dev/null
	cmp $(abspath $(BUILD))/hardcases-simd.jsonl $(abspath $(BUILD))/hardcases-sse2.jsonl
	cmp $(abspath $(BUILD))/hardcases-sse2.jsonl $(abspath $(BUILD))/hardcases-scalar.jsonl
# A processor without AVX (docs/testing.md): the hard cases under qemu-x86_64 -cpu Nehalem
# (no AVX in its CPUID, an AVX instruction is an illegal instruction there: the SSE2
# kernels) and -cpu SandyBridge (AVX: the AVX kernels) must write the same JSON. Both
# without FMA, so glibc's libm takes the same (non-FMA) variants in both: a native run on
# an FMA processor differs from either in the last bits of the cases' set-up. Not in check
# (13 min at load 4); skipped without qemu-x86_64 (Debian: qemu-user) or on another processor.
.PHONY: check-noavx
check-noavx: $(HARDCASES)
	@if [ "$$(uname -m)" = x86_64 ] && command -v qemu-x86_64 >/dev/null 2>&1; then \
	    set -ex; \
	    qemu-x86_64 -cpu SandyBridge $(HARDCASES) --json $(abspath $(BUILD))/hardcases-qemu-avx.jsonl > /dev/null 2>&1; \
	    qemu-x86_64 -cpu Nehalem $(HARDCASES) --json $(abspath $(BUILD))/hardcases-qemu-noavx.jsonl > /dev/null 2>&1; \
	    cmp $(abspath $(BUILD))/hardcases-qemu-avx.jsonl $(abspath $(BUILD))/hardcases-qemu-noavx.jsonl; \
	else echo "check-noavx: SKIPPED: needs an x86-64 host and qemu-x86_64"; fi
bench-hard: $(HARDCASES)
	@mkdir -p docs/hardcases
	$(HARDCASES) --long --json docs/hardcases/long.jsonl | tee docs/hardcases/long.txt

check-python: $(SHLIB) $(BUILD)/bench/urdf_export $(HARDREF_SO)
	cd tests/python && $(PY_ENV) AQS_LIBRARY=$(abspath $(SHLIB)) AQS_VECTORS=$(abspath tests/vectors) \
	    AQS_URDF_EXPORT=$(abspath $(BUILD)/bench/urdf_export) AQS_HARDREF=$(abspath $(HARDREF_SO)) \
	    PYTHONPATH=$(abspath bindings/python) $(PYTHON) -m pytest -q -p no:cacheprovider .

check-install: lib
	@bash tests/install/run.sh "$(BUILD)" "$(CC)" "$(CXX)" "$(SANFLAGS)"

# aqs.pc and the CMake package locate the files relative to themselves (pkg-config's
# ${prefix}, CMake's CMAKE_CURRENT_LIST_DIR), so a DESTDIR tree can be moved.
PC_LIBDIR = $(patsubst $(PREFIX)/%,$${prefix}/%,$(LIBDIR))
PC_INCLUDEDIR = $(patsubst $(PREFIX)/%,$${prefix}/%,$(INCLUDEDIR))
CMAKEDIR = $(LIBDIR)/cmake/aqs
CMAKE_REL_LIBDIR = $(shell realpath -m --relative-to=$(CMAKEDIR) $(LIBDIR))
CMAKE_REL_INCLUDEDIR = $(shell realpath -m --relative-to=$(CMAKEDIR) $(INCLUDEDIR))
SIZEOF_VOID_P = $(shell printf '__SIZEOF_POINTER__\n' | $(CC) $(CPPFLAGS) $(CFLAGS) -E -P -x c - | tr -d ' \n')
install: lib
	install -d $(DESTDIR)$(INCLUDEDIR) $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(CMAKEDIR)
	install -m 644 include/aqs.h $(DESTDIR)$(INCLUDEDIR)/aqs.h
	install -m 755 $(SHLIB) $(DESTDIR)$(LIBDIR)/libaqs.so.$(VERSION)
	ln -sf libaqs.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/libaqs.so
	install -m 644 $(STLIB) $(DESTDIR)$(LIBDIR)/libaqs.a
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBDIR@|$(PC_LIBDIR)|g' \
	    -e 's|@INCLUDEDIR@|$(PC_INCLUDEDIR)|g' -e 's|@VERSION@|$(VERSION)|g' \
	    -e 's|@URDF_REQUIRES@|$(if $(filter 1,$(AQS_URDF)), expat)|g' aqs.pc.in \
	    > $(DESTDIR)$(LIBDIR)/pkgconfig/aqs.pc
	sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@SONAME@|$(SONAME)|g' \
	    -e 's|@REL_LIBDIR@|$(CMAKE_REL_LIBDIR)|g' -e 's|@REL_INCLUDEDIR@|$(CMAKE_REL_INCLUDEDIR)|g' \
	    -e 's|@URDF_LIBS@|$(if $(filter 1,$(AQS_URDF)),;expat)|g' \
	    cmake/aqsConfig.cmake.in > $(DESTDIR)$(CMAKEDIR)/aqsConfig.cmake
	sed -e 's|@VERSION@|$(VERSION)|g' -e 's|@MAJOR@|$(MAJOR)|g' -e 's|@SIZEOF_VOID_P@|$(SIZEOF_VOID_P)|g' \
	    cmake/aqsConfigVersion.cmake.in > $(DESTDIR)$(CMAKEDIR)/aqsConfigVersion.cmake

# The same PREFIX / LIBDIR / INCLUDEDIR / DESTDIR as the install; builds nothing.
uninstall:
	rm -f $(DESTDIR)$(INCLUDEDIR)/aqs.h $(DESTDIR)$(LIBDIR)/libaqs.so.$(VERSION) \
	    $(DESTDIR)$(LIBDIR)/$(SONAME) $(DESTDIR)$(LIBDIR)/libaqs.so $(DESTDIR)$(LIBDIR)/libaqs.a \
	    $(DESTDIR)$(LIBDIR)/pkgconfig/aqs.pc $(DESTDIR)$(CMAKEDIR)/aqsConfig.cmake \
	    $(DESTDIR)$(CMAKEDIR)/aqsConfigVersion.cmake
	-@rmdir $(DESTDIR)$(CMAKEDIR) 2>/dev/null || true

$(BUILD)/bench/%: bench/%.c $(wildcard bench/*.h) $(BENCH_SUPPORT) $(INTLIB)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) -std=c99 -O2 -g $(WARN) $(SANFLAGS) -Iinclude -Ibench $(CPPFLAGS) $(CFLAGS) $(LDFLAGS) \
	    -o $@ $< $(BENCH_SUPPORT) $(INTLIB) $(LDLIBS)

# The URDF exporter runs in check-python (tests/python/test_urdf_bench.py), so it is
# built like the tests, under the sanitizers with SANITIZE=1.
$(BUILD)/bench/urdf_export: bench/urdf_export.c $(wildcard bench/*.h) $(BENCH_SUPPORT) $(INTLIB)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) -std=c99 $(OPT) $(WARN) $(SANFLAGS) -Iinclude -Ibench $(CPPFLAGS) $(CFLAGS) $(LDFLAGS) \
	    -o $@ $< $(BENCH_SUPPORT) $(INTLIB) $(LDLIBS)

# Pinocchio and MuJoCo side by side with aqs (bench/peers.py; results in docs/bench.md,
# section "Peers"). Installs the optional peers (pin, mujoco from PyPI) first.
# PEERS_ARGS passes options, e.g. PEERS_ARGS="--sizes 1000,10000".
.PHONY: peers
peers: $(BUILD)/bench/urdf_export $(SHLIB)
	@bash tools/deps.sh --peers
	AQS_LIBRARY=$(abspath $(SHLIB)) PYTHONPATH=$(abspath bindings/python) \
	    $(PYTHON) bench/peers.py --exporter $(abspath $(BUILD)/bench/urdf_export) $(PEERS_ARGS)

# Pinocchio 4.1's ABA against aqs's exact pass, same models and states, interleaved in
# one process, plus callgrind instructions per joint (bench/pinpeer_main.cpp,
# tools/bench_peer.sh; docs/bench.md). Installs Pinocchio's and Boost's headers from PyPI
# into $(BUILD)/pin; skipped with a message when offline. PEER_ROUNDS, PEER_CASES.
PEER_ROUNDS ?= 9
PEER_CASES ?= chain30:30,chain:1000,molecule:5000,molecule:50000,millipede:13000
.PHONY: bench-peer
bench-peer: $(INTLIB)
	@bash tools/bench_peer.sh $(BUILD) $(INTLIB) "$(LDLIBS)" $(PEER_ROUNDS) $(PEER_CASES)

demo: $(BUILD)/bench/demo
	@$(BUILD)/bench/demo

# aqs-bench: the one benchmark program (bench/README.md).
AQS_BENCH := $(BUILD)/bench/aqs-bench
$(AQS_BENCH): $(BUILD)/bench/aqs_bench
	@cp $< $@

# make bench: quick sweep (~3 min on 2 cores); FULL=1: the paper's protocol.
# Each run overwrites its docs/bench/<set>-<scene>.jsonl (every line has a run_id).
ifeq ($(FULL),1)
BENCH_SET := full
FULL_FORCES ?= 1,10,100,1000
BENCH_CHAIN30 := --steps 10000 --eps 2^-0..19 --tip-every 20 --exact-every 100
BENCH_MILLIPEDE := --steps 4000 --eps 2^-0..19 --exact-every 100
BENCH_MOLECULE := --steps 4000 --eps 2^-0..19 --forces $(FULL_FORCES) --exact-every 100
else
BENCH_SET := quick
BENCH_CHAIN30 := --steps 2000 --eps 2^-1,2^-3,2^-5,2^-7,2^-10,2^-19 --tip-every 10
BENCH_MILLIPEDE := --steps 100 --eps 2^-0..19
BENCH_MOLECULE := --steps 30 --eps 2^-0,2^-5,2^-10,2^-15,2^-19 --forces 1,10,100,1000
endif
bench: $(AQS_BENCH)
	@mkdir -p docs/bench
	$(AQS_BENCH) --scene chain30 --first-move 0.1 $(BENCH_CHAIN30) \
	    --out docs/bench/$(BENCH_SET)-chain30.jsonl --tip-path docs/bench/$(BENCH_SET)-chain30-tip.csv
	$(AQS_BENCH) --scene millipede $(BENCH_MILLIPEDE) --out docs/bench/$(BENCH_SET)-millipede.jsonl
	$(AQS_BENCH) --scene molecule --joints 50000 $(BENCH_MOLECULE) \
	    --out docs/bench/$(BENCH_SET)-molecule.jsonl
	@$(MAKE) --no-print-directory bench-plots BENCH_SET=$(BENCH_SET)
	@$(MAKE) --no-print-directory bench-collide

# Scaling (docs/bench.md, "Scaling"): first the exact pass per joint with the sizes
# interleaved in one process, and memory per joint through aqs_linkage_get_memory, exact
# and with a tolerance (exact_main --memory: the molecule at SCALING_EXACT_SIZES, the
# millipede; ~6 GB at 10^6), into docs/bench/scaling-exact.txt with the load; then the
# adaptive step per size, molecule 10k..1M joints, N_f = 1, rel. joint 2^-19, one
# process per size (aqs-bench; 1M: ~6 GB). ~5 min.
SCALING_SIZES ?= 10000 50000 200000 1000000
SCALING_EXACT_SIZES ?= 2000,50000,1000000
bench-scaling: $(AQS_BENCH) $(BUILD)/bench/exact_main
	@mkdir -p docs/bench
	@set -e; { date -u +"run %Y-%m-%dT%H:%M:%SZ"; uptime; \
	    $(BUILD)/bench/exact_main --sizes $(SCALING_EXACT_SIZES) --rounds 7 --reps 3 --memory; \
	    $(BUILD)/bench/exact_main --scene millipede --sizes 13000 --rounds 3 --reps 3 --memory; \
	    $(BUILD)/bench/exact_main --bandwidth 1000; uptime; } | tee docs/bench/scaling-exact.txt
	@rm -f docs/bench/scaling.jsonl
	@set -e; for n in $(SCALING_SIZES); do \
	    $(AQS_BENCH) --scene molecule --joints $$n --forces 1 --eps 2^-19 --steps 20 \
	        --out docs/bench/scaling.jsonl --append; done
	@$(MAKE) --no-print-directory bench-plots BENCH_SET=$(or $(BENCH_SET),quick)

BENCH_DEPS_STAMP := build/.deps-bench-ok
$(BENCH_DEPS_STAMP): tools/deps.sh $(DEPS_STAMP)
	@bash tools/deps.sh bench
	@mkdir -p build && touch $@
bench-plots: $(BENCH_DEPS_STAMP)
	$(PYTHON) bench/plot.py --set $(or $(BENCH_SET),quick) docs/bench

# aqs-bench on a tiny molecule: JSON Lines schema and consistency (no timing asserted).
check-bench: $(AQS_BENCH) $(SHLIB)
	$(PY_ENV) AQS_BENCH=$(abspath $(AQS_BENCH)) AQS_LIBRARY=$(abspath $(SHLIB)) \
	    PYTHONPATH=$(abspath bindings/python) $(PYTHON) -m pytest -q -p no:cacheprovider \
	    tests/bench/test_aqs_bench.py

# Collision queries: lazy tree vs full tree vs brute force (docs/bench.md, "Collision").
bench-collide: $(BUILD)/bench/collide_bench
	$(BUILD)/bench/collide_bench

clean:
	rm -rf build

# Differential fuzzing of the whole API with injected allocation failures
# (tests/fuzz/api_fuzz.c, docs/testing.md): clang's libFuzzer with ASan and UBSan.
# check-fuzz also runs tests/test_stale.c under clang's UBSan (pointer-overflow:
# NULL + 0, which gcc's UBSan does not report). Both are skipped, with a message,
# when clang or its libFuzzer runtime (Debian: clang, libclang-rt-14-dev) is missing.
FUZZ_CC ?= clang
FUZZ_RUNS ?= 20000
FUZZ := build/fuzz/aqs_fuzz
FUZZ_SRC := -DAQS_BUILDING_LIBRARY -DAQS_DEBUG -Iinclude $(SRC_INC) $(CCD_CFLAGS) $(SRCS)
.PHONY: fuzz check-fuzz
fuzz: $(FUZZ)
$(FUZZ): tests/fuzz/api_fuzz.c $(SRCS) $(SRC_HDRS) include/aqs.h | $(BUILD_PREREQ)
	@mkdir -p $(dir $@)
	@echo "  CLANG   $@"
	@$(FUZZ_CC) -std=c99 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
	    -o $@ tests/fuzz/api_fuzz.c $(FUZZ_SRC) $(LDLIBS)
build/fuzz/test_stale_ubsan: tests/test_stale.c $(TEST_SUPPORT) $(SRCS) $(SRC_HDRS) include/aqs.h | $(BUILD_PREREQ)
	@mkdir -p $(dir $@)
	@echo "  CLANG   $@"
	@$(FUZZ_CC) -std=c99 -O1 -g -fsanitize=undefined,pointer-overflow -fno-sanitize-recover=all \
	    -Itests/support -o $@ tests/test_stale.c $(TEST_SUPPORT) $(FUZZ_SRC) -lcmocka $(LDLIBS)
check-fuzz: | $(BUILD_PREREQ)
	@if ! printf 'int LLVMFuzzerTestOneInput(const unsigned char *d, unsigned long n) { return d && n; }\n' \
	    | $(FUZZ_CC) -fsanitize=fuzzer -x c - -o build/.fuzz-probe >/dev/null 2>&1; then \
	    echo "check-fuzz: SKIPPED: $(FUZZ_CC) with libFuzzer not found (Debian: apt-get install clang libclang-rt-14-dev)"; \
	else rm -f build/.fuzz-probe; \
	    $(MAKE) --no-print-directory $(FUZZ) build/fuzz/test_stale_ubsan && \
	    echo "== build/fuzz/test_stale_ubsan" && build/fuzz/test_stale_ubsan && \
	    echo "== $(FUZZ) -runs=$(FUZZ_RUNS) -seed=1 (log: build/fuzz/check.log)" && \
	    if (cd build/fuzz && rm -rf check-corpus && mkdir check-corpus && \
	        ./aqs_fuzz -runs=$(FUZZ_RUNS) -seed=1 -max_len=1024 -print_final_stats=1 \
	            check-corpus $(abspath tests/fuzz/seeds) > check.log 2>&1); then grep -a '^Done\|^stat::' build/fuzz/check.log; \
	    else tail -n 60 build/fuzz/check.log; echo "check-fuzz: FAILED (reproducer crash-* in build/fuzz)"; exit 1; fi; fi
