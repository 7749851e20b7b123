# SPDX-License-Identifier: BSD-3-Clause
# make embedded: the core as firmware uses it.
#  1. libcyl for a Cortex-M4 (arm-none-eabi-gcc -Os -Werror, `make cross`), nm check that the
#     archive references no heap, stdio or exit, and its code size;
#  2. the memory a 320x240 frame needs, computed on 32-bit ARM (qemu-arm);
#  3. every core unit test (tests/unit) built for armhf and run under qemu-arm: a second
#     architecture (32-bit, other alignment and calling convention) than the host; this
#     build has no NEON (Debian's armhf default), so it runs the scalar path;
#  4. the vector paths on ARM: the segmentation, table, colour-learning and image tests built for
#     AArch64 (NEON) and run under qemu-aarch64, and the segmentation and table tests built for
#     ARMv7 with -mfpu=neon under qemu-arm (the vector path against the scalar one, bit for bit).
DEBS_ARMHF := gcc-arm-linux-gnueabihf libc6-dev-armhf-cross qemu-user
DEBS_ARM64 := gcc-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user
ARMHF_LIB := libcyl/build/armhf/libcyl.a
ARMHF_TESTS := $(patsubst tests/unit/%.c,build/armhf/%,$(sort $(wildcard tests/unit/test_*.c)))
ARMHF_COMMON := $(wildcard tests/common/*.c)

# cmocka for armhf and arm64 comes from Debian multiarch (dpkg --add-architecture, idempotent).
$(STAMP)/%-cmocka: $(STAMP)/debs-%
	@if ! dpkg-query -W -f='$${Status}' libcmocka-dev:$* 2>/dev/null | grep -q 'install ok installed'; then \
	  SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO dpkg --add-architecture $* && ($$SUDO apt-get update -qq || true) && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libcmocka-dev:$* >&2; fi
	@touch $@

$(ARMHF_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-armhf
	$(MAKE) -C libcyl BUILD=build/armhf CC=arm-linux-gnueabihf-gcc AR=arm-linux-gnueabihf-ar CFLAGS='-O2 -Werror'

build/armhf/%: tests/unit/%.c $(ARMHF_COMMON) $(ARMHF_LIB) $(STAMP)/armhf-cmocka
	@mkdir -p $(dir $@)
	arm-linux-gnueabihf-gcc -std=c99 -O2 -Wall -Wextra -Ilibcyl/include -Itests/common $< $(ARMHF_COMMON) \
	  -o $@ $(ARMHF_LIB) -lcmocka -lm

build/armhf/workspace: libcyl/examples/workspace.c $(ARMHF_LIB)
	@mkdir -p build/armhf
	arm-linux-gnueabihf-gcc -std=c99 -O2 -Wall -Wextra -Ilibcyl/include $< -o $@ $(ARMHF_LIB) -lm

# AArch64 (NEON vector path)
ARM64_LIB := libcyl/build/arm64/libcyl.a
# the tests of what has a vector path or feeds it (the rest of the core is the same C as on armhf)
ARM64_TESTS := $(addprefix build/arm64/,test_segment test_colortable test_colorlearn test_image)
$(ARM64_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-arm64
	$(MAKE) -C libcyl BUILD=build/arm64 CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar CFLAGS='-O2 -Werror'
build/arm64/%: tests/unit/%.c $(ARMHF_COMMON) $(ARM64_LIB) $(STAMP)/arm64-cmocka
	@mkdir -p $(dir $@)
	aarch64-linux-gnu-gcc -std=c99 -O2 -Wall -Wextra -Ilibcyl/include -Itests/common $< $(ARMHF_COMMON) \
	  -o $@ $(ARM64_LIB) -lcmocka -lm

# ARMv7 with NEON (the same sources as the armhf build, -mfpu=neon)
NEON7_LIB := libcyl/build/armhf-neon/libcyl.a
NEON7_TESTS := build/armhf-neon/test_segment build/armhf-neon/test_colortable
$(NEON7_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-armhf
	$(MAKE) -C libcyl BUILD=build/armhf-neon CC=arm-linux-gnueabihf-gcc AR=arm-linux-gnueabihf-ar \
	  CFLAGS='-O2 -Werror -mfpu=neon'
build/armhf-neon/%: tests/unit/%.c $(ARMHF_COMMON) $(NEON7_LIB) $(STAMP)/armhf-cmocka
	@mkdir -p $(dir $@)
	arm-linux-gnueabihf-gcc -std=c99 -O2 -mfpu=neon -Wall -Wextra -Ilibcyl/include -Itests/common $< \
	  $(ARMHF_COMMON) -o $@ $(NEON7_LIB) -lcmocka -lm

embedded: cross build/armhf/workspace $(ARMHF_TESTS) $(ARM64_TESTS) $(NEON7_TESTS)
	qemu-arm build/armhf/workspace 320 240
	scripts/run-tests.sh $(addprefix scripts/qemu-arm.sh:,$(ARMHF_TESTS) $(NEON7_TESTS)) \
	  $(addprefix scripts/qemu-aarch64.sh:,$(ARM64_TESTS))
.PHONY: embedded
