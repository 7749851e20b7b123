# SPDX-License-Identifier: BSD-3-Clause
# libcyl's compile-time options (libcyl/include/cyl/config.h): the firmware configuration
# (CYL_CONFIG_FIRMWARE_MINIMAL: no image estimator, sub-pixel edges, landmark models or colour
# learning; YUYV only) built on the host, and tests/unit/test_config.c run against it (the default
# configuration runs the same test among the unit tests). `make cross` measures its size on a
# Cortex-M4.
MINIMAL_LIB := libcyl/build/host-minimal/libcyl.a
$(MINIMAL_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-build
	$(MAKE) -C libcyl BUILD=build/host-minimal CFLAGS='-O2 -Werror -DCYL_CONFIG_FIRMWARE_MINIMAL'

$(BUILD)/tests-minimal/test_config: tests/unit/test_config.c $(wildcard tests/common/*.c tests/common/*.h) $(MINIMAL_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) -DCYL_CONFIG_FIRMWARE_MINIMAL $< $(wildcard tests/common/*.c) -o $@ $(MINIMAL_LIB) -lcmocka -lm

TEST_EXTRA += $(BUILD)/tests-minimal/test_config
TEST_EXTRA_BINS += $(BUILD)/tests-minimal/test_config

# The x86 vector path without AVX2 (the SSSE3 background skip and the box-only run extension), forced
# on this host with -DCYL_SKIP_MAX_X86=1, checked against the scalar path by the segmentation tests
# (the default build takes AVX2 wherever the CPU has it, so this path would otherwise go untested).
SSSE3_LIB := libcyl/build/host-ssse3/libcyl.a
$(SSSE3_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-build
	$(MAKE) -C libcyl BUILD=build/host-ssse3 CFLAGS='-O2 -Werror -DCYL_SKIP_MAX_X86=1'

$(BUILD)/tests-ssse3/test_segment: tests/unit/test_segment.c $(wildcard tests/common/*.c tests/common/*.h) $(SSSE3_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) -DCYL_EXPECT_VECTOR_PATH='"ssse3"' $< $(wildcard tests/common/*.c) -o $@ $(SSSE3_LIB) -lcmocka -lm

ifeq ($(shell uname -m),x86_64)
TEST_EXTRA += $(BUILD)/tests-ssse3/test_segment
TEST_EXTRA_BINS += $(BUILD)/tests-ssse3/test_segment
endif
