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
