# SPDX-License-Identifier: BSD-3-Clause
# libcyl -- top-level build. The two commands a user needs:
#   make demo    the main job, on built-in data
#   make test    the whole test suite (what CI runs)
# Everything installs what it needs first (Debian packages via apt-get, once).
# Other targets: bench, cross (Cortex-M4 build of libcyl), install PREFIX=..., clean.

SHELL   := /bin/bash
CC      ?= cc
CXX     ?= c++
# SAN=1: the same targets built with AddressSanitizer and UndefinedBehaviorSanitizer into
# build/san (e.g. `make test SAN=1`); any finding aborts the test that hit it.
ifeq ($(SAN),1)
BUILD   := build/san
HOSTLIB := libcyl/build/san
SANFLAGS := -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer
export ASAN_OPTIONS := detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS := print_stacktrace=1:halt_on_error=1
export LSAN_OPTIONS := suppressions=$(CURDIR)/tests/sanitizer/lsan.supp
else
BUILD   := build
HOSTLIB := libcyl/build/host
SANFLAGS :=
endif
LIBCYL_A := $(HOSTLIB)/libcyl.a
# Host build of the core: what CI enforces (the libcyl Makefile adds -std=c99 -Wall -Wextra -Wpedantic).
CORE_CFLAGS := -O2 -g -Werror $(SANFLAGS)
TEST_CFLAGS := -std=c99 -O2 -g -Wall -Wextra -Ilibcyl/include -Itests/common $(SANFLAGS)
CXXFLAGS_ALL := -std=c++17 -O2 -g -Wall -Wextra -Ilibcyl/include -Itests/common -Ifrontend/include $(SANFLAGS)

DEBS_BUILD := build-essential pkg-config libcmocka-dev
DEBS_CROSS := gcc-arm-none-eabi libnewlib-arm-none-eabi
DEBS_CV    := libopencv-dev libyaml-cpp-dev libjpeg-dev
DEBS_BENCH := valgrind

STAMP := $(BUILD)/.stamps
# The project-local Python venv (mk/slam.mk creates it; the Python fuzz target adds atheris)
VENV := .venv
deps-build := $(STAMP)/debs-build
$(STAMP):
	mkdir -p $@
$(STAMP)/debs-%: scripts/ensure-debs.sh | $(STAMP)
	@scripts/ensure-debs.sh $(DEBS_$(shell echo $* | tr a-z A-Z)) && touch $@

.PHONY: all lib test unit-tests cross demo bench install clean deps
all: lib

# Feature fragments (one file per feature area) add their own targets and may
# append to TEST_EXTRA (prerequisites of `make test`) and TEST_EXTRA_BINS (test
# programs run by scripts/run-tests.sh: cmocka, GoogleTest or pytest output).
TEST_EXTRA :=
TEST_EXTRA_BINS :=
include $(sort $(wildcard mk/*.mk))

deps: $(STAMP)/debs-build $(STAMP)/debs-cross $(STAMP)/debs-cv $(STAMP)/debs-bench

# ---- the core -------------------------------------------------------------
lib: $(STAMP)/debs-build
	$(MAKE) -C libcyl BUILD=$(HOSTLIB:libcyl/%=%) CFLAGS='$(CORE_CFLAGS)'

$(LIBCYL_A): lib

# Cortex-M4 firmware build: must compile cleanly with the same sources.
M4_FLAGS := -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -Os
cross: $(STAMP)/debs-cross
	$(MAKE) -C libcyl BUILD=build/m4 CC=arm-none-eabi-gcc AR=arm-none-eabi-ar \
	  CFLAGS='$(M4_FLAGS) -Werror'
	@bad=$$(arm-none-eabi-nm -u libcyl/build/m4/libcyl.a | awk '{print $$2}' | \
	  grep -E '^(malloc|calloc|realloc|free|printf|fprintf|sprintf|puts|fopen|fwrite|exit|abort)$$' | sort -u); \
	  if [ -n "$$bad" ]; then echo "cross: libcyl.a references $$bad"; exit 1; fi
	@arm-none-eabi-size -t libcyl/build/m4/libcyl.a | tail -1 | \
	  awk '{printf "cross: Cortex-M4 libcyl.a text %d B, data %d B, bss %d B; no heap or stdio symbols\n", $$1, $$2, $$3}'
	@# what a firmware keeps: libcyl/examples/firmware.c (table, segment, observe) linked bare-metal
	@# (newlib-nano, no system calls, unused sections dropped), against an empty main
	@$(MAKE) -C libcyl BUILD=build/m4-gc CC=arm-none-eabi-gcc AR=arm-none-eabi-ar \
	  CFLAGS='$(M4_FLAGS) -ffunction-sections -fdata-sections -Werror' >/dev/null
	@printf 'int main(void) { for (;;) {} }\n' > libcyl/build/m4-gc/empty.c
	@for f in libcyl/examples/firmware.c libcyl/build/m4-gc/empty.c; do \
	  arm-none-eabi-gcc $(M4_FLAGS) -std=c99 -Werror -Ilibcyl/include $$f -Llibcyl/build/m4-gc -lcyl -lm \
	    --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections -o libcyl/build/m4-gc/$$(basename $$f .c).elf || exit 1; \
	done
	@python3 scripts/firmware_size.py libcyl/build/m4-gc/firmware.elf libcyl/build/m4-gc/empty.elf \
	  libcyl/build/m4-gc/libcyl.a
	@# the same firmware on libcyl's firmware configuration (cyl/config.h: CYL_CONFIG_FIRMWARE_MINIMAL)
	@$(MAKE) -C libcyl BUILD=build/m4-min CC=arm-none-eabi-gcc AR=arm-none-eabi-ar \
	  CFLAGS='$(M4_FLAGS) -Werror -DCYL_CONFIG_FIRMWARE_MINIMAL' >/dev/null
	@arm-none-eabi-size -t libcyl/build/m4-min/libcyl.a | tail -1 | \
	  awk '{printf "cross: Cortex-M4 libcyl.a, CYL_CONFIG_FIRMWARE_MINIMAL: text %d B, data %d B, bss %d B\n", $$1, $$2, $$3}'
	@$(MAKE) -C libcyl BUILD=build/m4-min-gc CC=arm-none-eabi-gcc AR=arm-none-eabi-ar \
	  CFLAGS='$(M4_FLAGS) -ffunction-sections -fdata-sections -Werror -DCYL_CONFIG_FIRMWARE_MINIMAL' >/dev/null
	@arm-none-eabi-gcc $(M4_FLAGS) -std=c99 -Werror -Ilibcyl/include libcyl/examples/firmware.c -Llibcyl/build/m4-min-gc \
	  -lcyl -lm --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections -o libcyl/build/m4-min-gc/firmware.elf
	@python3 scripts/firmware_size.py libcyl/build/m4-min-gc/firmware.elf libcyl/build/m4-gc/empty.elf \
	  libcyl/build/m4-min-gc/libcyl.a "firmware (CYL_CONFIG_FIRMWARE_MINIMAL)"

install: lib
	$(MAKE) -C libcyl BUILD=$(HOSTLIB:libcyl/%=%) install PREFIX=$(or $(PREFIX),/usr/local)
	$(MAKE) install-tools PREFIX=$(or $(PREFIX),/usr/local)

# ---- tests ------------------------------------------------------------------
TEST_COMMON_SRCS := $(wildcard tests/common/*.c)
UNIT_SRCS := $(sort $(wildcard tests/unit/test_*.c))
UNIT_BINS := $(UNIT_SRCS:tests/unit/%.c=$(BUILD)/tests/%)

$(BUILD)/tests/%: tests/unit/%.c $(TEST_COMMON_SRCS) $(wildcard tests/common/*.h) lib
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) $< $(TEST_COMMON_SRCS) -o $@ $(LIBCYL_A) -lcmocka -lm

unit-tests: $(UNIT_BINS)

# make test SAN=1 leaves out the SAN_SKIP items (each .mk file says why it adds one)
TEST_RUN_BINS = $(if $(filter 1,$(SAN)),$(filter-out $(SAN_SKIP),$(TEST_EXTRA_BINS)),$(TEST_EXTRA_BINS))

test: $(STAMP)/debs-build $(STAMP)/debs-cv unit-tests cross $(TEST_EXTRA)
	@scripts/run-tests.sh $(UNIT_BINS) $(TEST_RUN_BINS)

# ---- demo -----------------------------------------------------------------
# The main job (scripts/demo.sh): render a synthetic drive, detect, SLAM; last line JSON.
$(BUILD)/segment_demo: libcyl/examples/segment_demo.c lib
	@mkdir -p $(dir $@)
	$(CC) -std=c99 -O2 -Wall -Wextra -Ilibcyl/include $< -o $@ $(LIBCYL_A) -lm

demo: $(BUILD)/cyl $(BUILD)/cyl-render .venv/.stamp
	@scripts/demo.sh

# The core alone: train a table on a generated frame, segment it, print the blobs.
demo-core: $(BUILD)/segment_demo
	$(BUILD)/segment_demo
.PHONY: demo-core

# ---- benchmark ------------------------------------------------------------
BENCH_C := tests/common/synth_frames.c tests/common/rng.c
$(BUILD)/bench_segment: bench/bench_segment.cpp bench/bench_frames.hpp $(BENCH_C) lib $(STAMP)/debs-cv
	@mkdir -p $(BUILD)/bench
	for f in $(BENCH_C); do $(CC) $(TEST_CFLAGS) -O3 -c $$f -o $(BUILD)/bench/$$(basename $$f .c).o || exit 1; done
	$(CXX) $(CXXFLAGS_ALL) -O3 $< $(BENCH_C:tests/common/%.c=$(BUILD)/bench/%.o) -o $@ $(LIBCYL_A) \
	  $$(pkg-config --cflags --libs opencv4) -lm

# Each part prints its table; the last line merges every part's JSON fragment.
bench: $(BUILD)/bench_segment $(BUILD)/bench_uncertainty $(BUILD)/bench_replay $(BUILD)/cyl $(BUILD)/cyl-render $(BUILD)/cyl-train $(BUILD)/cyl-score $(STAMP)/debs-bench
	@BUILD=$(BUILD) SHARED=$(SHARED) scripts/bench.sh

clean:
	rm -rf $(BUILD) libcyl/build

# The hardening checks (sanitizers, firmware + armhf, fuzz smoke, lint, soak), one after
# another; .ci/run runs them after `make test`.
ci-hardening:
	scripts/ci-hardening.sh
.PHONY: ci-hardening
