# SPDX-License-Identifier: BSD-3-Clause
# make embedded: the core as firmware uses it.
#  1. libcyl for a Cortex-M4 (arm-none-eabi-gcc -Os -Werror, `make cross`), nm check that the
#     archive references no heap, stdio or exit, and its code size;
#  2. the memory a 320x240 frame needs, computed on 32-bit ARM (qemu-arm);
#  3. every core unit test (tests/unit) built for armhf and run under qemu-arm: a second
#     architecture (32-bit, other alignment and calling convention) than the host.
DEBS_ARMHF := gcc-arm-linux-gnueabihf libc6-dev-armhf-cross qemu-user
ARMHF_LIB := libcyl/build/armhf/libcyl.a
ARMHF_TESTS := $(patsubst tests/unit/%.c,build/armhf/%,$(sort $(wildcard tests/unit/test_*.c)))
ARMHF_COMMON := $(wildcard tests/common/*.c)

# cmocka for armhf comes from Debian multiarch (dpkg --add-architecture armhf, idempotent).
$(STAMP)/armhf-cmocka: $(STAMP)/debs-armhf
	@if ! dpkg-query -W -f='$${Status}' libcmocka-dev:armhf 2>/dev/null | grep -q 'install ok installed'; then \
	  SUDO=""; [ "$$(id -u)" -eq 0 ] || SUDO=sudo; \
	  $$SUDO dpkg --add-architecture armhf && ($$SUDO apt-get update -qq || true) && \
	  $$SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends libcmocka-dev:armhf >&2; fi
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

embedded: cross build/armhf/workspace $(ARMHF_TESTS)
	qemu-arm build/armhf/workspace 320 240
	scripts/run-tests.sh $(addprefix scripts/qemu-arm.sh:,$(ARMHF_TESTS))
.PHONY: embedded
