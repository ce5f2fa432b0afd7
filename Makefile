# aqs -- adaptive quasi-statics. See README.md.
#   make            build/libaqs.so.X.Y.Z and build/libaqs.a
#   make check      every test (C, C++ reference, Python, install); SANITIZE=1 under ASan/UBSan
#   make demo       the README's "run it" command
#   make bench      quick benchmark sweep + plots (docs/bench/); FULL=1 the paper's protocol
#   make bench-scaling  molecule 10k..1M joints (docs/bench/scaling.jsonl)
#   make install    PREFIX=/usr/local DESTDIR=
#   make deps       install the Debian/PyPI packages that are missing

SHELL := /bin/bash
PREFIX ?= /usr/local
DESTDIR ?=
PYTHON ?= python3

MAJOR := $(shell sed -n 's/^\#define AQS_VERSION_MAJOR \([0-9]*\).*/\1/p' include/aqs.h)
MINOR := $(shell sed -n 's/^\#define AQS_VERSION_MINOR \([0-9]*\).*/\1/p' include/aqs.h)
PATCH := $(shell sed -n 's/^\#define AQS_VERSION_PATCH \([0-9]*\).*/\1/p' include/aqs.h)
VERSION := $(MAJOR).$(MINOR).$(PATCH)

ifeq ($(SANITIZE),1)
BUILD := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all
OPT := -O1 -g
else
BUILD := build
SANFLAGS :=
OPT := -O2 -funroll-loops -g
endif

CC ?= cc
CXX ?= c++
WARN := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Wno-unused-parameter
CFLAGS_LIB := -std=c99 $(OPT) $(WARN) -fPIC -fvisibility=hidden -DAQS_BUILDING_LIBRARY \
              -Iinclude -Isrc $(SANFLAGS)
CFLAGS_TEST := -std=c99 $(OPT) -Wall -Wextra -Werror -Wno-unused-parameter -Iinclude -Isrc $(SANFLAGS)
CXXFLAGS_TEST := -std=c++17 $(OPT) -Wall -Wextra -Werror -Wno-unused-parameter -Iinclude \
                 -I/usr/include/eigen3 $(SANFLAGS)
LDLIBS := -lccd -lm

# URDF loading (src/urdf.c) with expat, an optional feature: on when
# pkg-config finds expat, off with AQS_URDF=0 (the load functions then return
# AQS_ESTATE saying so). AQS_URDF=1 insists on it.
AQS_URDF ?= $(shell pkg-config --exists expat 2>/dev/null && echo 1 || echo 0)
ifeq ($(AQS_URDF),1)
CFLAGS_LIB += -DAQS_HAVE_EXPAT $(shell pkg-config --cflags expat 2>/dev/null)
LDLIBS += $(or $(shell pkg-config --libs expat 2>/dev/null),-lexpat)
endif

SRCS := $(sort $(wildcard src/*.c))
OBJS := $(patsubst src/%.c,$(BUILD)/obj/%.o,$(SRCS))
SONAME := libaqs.so.$(MAJOR)
SHLIB := $(BUILD)/libaqs.so.$(VERSION)
STLIB := $(BUILD)/libaqs.a

C_TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(sort $(wildcard tests/test_*.c)))
CXX_TESTS := $(patsubst tests/reference/%.cpp,$(BUILD)/tests/reference/%,$(sort $(wildcard tests/reference/test_*.cpp)))
TEST_SUPPORT := $(sort $(wildcard tests/support/*.c))

BENCH_MAINS := bench/demo.c bench/aqs_bench.c $(wildcard bench/*_main.c) bench/collide_bench.c
BENCH_MAINS += bench/urdf_export.c
BENCH_SUPPORT := $(filter-out $(BENCH_MAINS),$(sort $(wildcard bench/*.c)))

.PHONY: all lib check check-c check-reference check-python check-install check-symbols \
        deps demo bench bench-scaling bench-plots bench-collide check-bench install clean

all: lib
lib: $(SHLIB) $(STLIB)

DEPS_STAMP := build/.deps-ok
deps: $(DEPS_STAMP)
$(DEPS_STAMP): tools/deps.sh
	@bash tools/deps.sh
	@mkdir -p build && touch $@

$(BUILD)/obj/%.o: src/%.c $(wildcard src/*.h) include/aqs.h | $(DEPS_STAMP)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) $(CFLAGS_LIB) -c $< -o $@

$(SHLIB): $(OBJS) src/aqs.map
	@echo "  LD      $@"
	@$(CC) -shared -Wl,-soname,$(SONAME) -Wl,--version-script=src/aqs.map -Wl,--no-undefined \
	    $(SANFLAGS) -o $@ $(OBJS) $(LDLIBS)
	@ln -sf libaqs.so.$(VERSION) $(BUILD)/$(SONAME)
	@ln -sf $(SONAME) $(BUILD)/libaqs.so

$(STLIB): $(OBJS)
	@echo "  AR      $@"
	@rm -f $@
	@ar rcs $@ $(OBJS)

# C unit tests link the static library so they can reach internal functions.
$(BUILD)/tests/%: tests/%.c $(TEST_SUPPORT) $(wildcard tests/support/*.h) $(STLIB)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) $(CFLAGS_TEST) -Itests/support -o $@ $< $(TEST_SUPPORT) $(STLIB) -lcmocka $(LDLIBS)

$(BUILD)/tests/reference/%: tests/reference/%.cpp $(wildcard tests/reference/*.hpp) $(SHLIB)
	@mkdir -p $(dir $@)
	@echo "  CXX     $<"
	@$(CXX) $(CXXFLAGS_TEST) -o $@ $< -L$(BUILD) -Wl,-rpath,$(abspath $(BUILD)) -laqs $(LDLIBS)

check: check-symbols check-c check-reference check-python check-install check-bench
	@echo "make check: all suites passed ($(if $(SANITIZE),sanitized,plain) build)"

check-symbols: $(SHLIB)
	@bash tests/check_symbols.sh $(SHLIB) src/aqs.map

check-c: $(C_TESTS)
	@set -e; for t in $(C_TESTS); do echo "== $$t"; $$t; done

check-reference: $(CXX_TESTS)
	@set -e; for t in $(CXX_TESTS); do echo "== $$t"; AQS_VECTORS=$(abspath ../shared/vectors) $$t; done

ifeq ($(SANITIZE),1)
# Python loads the library into an uninstrumented interpreter: preload the runtime.
PY_ENV := LD_PRELOAD="$$($(CC) -print-file-name=libasan.so) $$($(CC) -print-file-name=libubsan.so)" \
          ASAN_OPTIONS=detect_leaks=0
else
PY_ENV :=
endif
check-python: $(SHLIB) $(BUILD)/bench/urdf_export
	cd tests/python && $(PY_ENV) AQS_LIBRARY=$(abspath $(SHLIB)) AQS_VECTORS=$(abspath ../shared/vectors) \
	    AQS_URDF_EXPORT=$(abspath $(BUILD)/bench/urdf_export) \
	    PYTHONPATH=$(abspath bindings/python) $(PYTHON) -m pytest -q -p no:cacheprovider .

check-install: lib
	@bash tests/install/run.sh "$(BUILD)" "$(CC)" "$(CXX)" "$(SANFLAGS)"

install: lib
	install -d $(DESTDIR)$(PREFIX)/include $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 include/aqs.h $(DESTDIR)$(PREFIX)/include/aqs.h
	install -m 755 $(SHLIB) $(DESTDIR)$(PREFIX)/lib/libaqs.so.$(VERSION)
	ln -sf libaqs.so.$(VERSION) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libaqs.so
	install -m 644 $(STLIB) $(DESTDIR)$(PREFIX)/lib/libaqs.a
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|$(VERSION)|g' \
	    -e 's|@URDF_REQUIRES@|$(if $(filter 1,$(AQS_URDF)), expat)|g' aqs.pc.in \
	    > $(DESTDIR)$(PREFIX)/lib/pkgconfig/aqs.pc

$(BUILD)/bench/%: bench/%.c $(wildcard bench/*.h) $(BENCH_SUPPORT) $(STLIB)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) -std=c99 -O2 -g $(WARN) $(SANFLAGS) -Iinclude -Ibench -o $@ $< $(BENCH_SUPPORT) $(STLIB) $(LDLIBS)

# The URDF exporter runs in check-python (tests/python/test_urdf_bench.py), so it is
# built like the tests, under the sanitizers with SANITIZE=1.
$(BUILD)/bench/urdf_export: bench/urdf_export.c $(wildcard bench/*.h) $(BENCH_SUPPORT) $(STLIB)
	@mkdir -p $(dir $@)
	@echo "  CC      $<"
	@$(CC) -std=c99 $(OPT) $(WARN) $(SANFLAGS) -Iinclude -Ibench -o $@ $< $(BENCH_SUPPORT) $(STLIB) $(LDLIBS)

# Pinocchio and MuJoCo side by side with aqs (bench/peers.py; results in docs/bench.md,
# section "Peers"). Installs the optional peers (pin, mujoco from PyPI) first.
# PEERS_ARGS passes options, e.g. PEERS_ARGS="--sizes 1000,10000".
.PHONY: peers
peers: $(BUILD)/bench/urdf_export $(SHLIB)
	@bash tools/deps.sh --peers
	AQS_LIBRARY=$(abspath $(SHLIB)) PYTHONPATH=$(abspath bindings/python) \
	    $(PYTHON) bench/peers.py --exporter $(abspath $(BUILD)/bench/urdf_export) $(PEERS_ARGS)

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

# Scaling: molecule 10k..1M joints, N_f = 1, rel. joint 2^-19 (1M: ~12 GB, ~3 min).
SCALING_SIZES ?= 10000 50000 200000 1000000
bench-scaling: $(AQS_BENCH)
	@mkdir -p docs/bench
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
