# SPDX-License-Identifier: BSD-3-Clause
# The C++ frontend: frontend/src/*.cpp -> $(BUILD)/frontend/libfrontend.a; tools in frontend/tools/.
FRONTEND_SRCS := $(sort $(wildcard frontend/src/*.cpp))
FRONTEND_OBJS := $(FRONTEND_SRCS:frontend/src/%.cpp=$(BUILD)/frontend/%.o)
FRONTEND_A := $(BUILD)/frontend/libfrontend.a
FRONTEND_HDRS := $(wildcard frontend/include/cylfe/*.hpp)
CV_FLAGS = $(shell pkg-config --cflags opencv4 2>/dev/null)
# what the frontend links: OpenCV, yaml-cpp for calibration files (frontend/src/calibration.cpp) and
# libjpeg(-turbo) for MJPG cameras (frontend/src/mjpeg.cpp)
CV_LIBS = $(shell pkg-config --libs opencv4 2>/dev/null) -lyaml-cpp -ljpeg
# what `cyl` links: OpenCV's core and imgproc only. Image and video files and windows go through
# the plugin libcyl-media.so (frontend/include/cylfe/media.hpp), loaded when first used, so the
# robot's case (camera or raw log in, observations out) loads no codec, video or GUI stack.
CV_LIBS_CORE = -lopencv_imgproc -lopencv_core -lyaml-cpp -ljpeg
MEDIA_SO := $(BUILD)/libcyl-media.so
MEDIA_LIBS = -lopencv_highgui -lopencv_videoio -lopencv_imgcodecs -lopencv_core

$(MEDIA_SO): frontend/src/media_plugin/media_plugin.cpp frontend/include/cylfe/media.hpp | $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) -fPIC -shared -fvisibility=hidden $< -o $@ $(MEDIA_LIBS)

$(BUILD)/frontend/%.o: frontend/src/%.cpp $(FRONTEND_HDRS) $(wildcard libcyl/include/cyl/*.h) | $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) -c $< -o $@

# every program on the frontend finds the media plugin beside it (or one folder up, for tests)
$(FRONTEND_A): $(FRONTEND_OBJS) | $(MEDIA_SO)
	rm -f $@.tmp && ar rcs $@.tmp $^ && mv $@.tmp $@

# ---- V4L2 against the kernel's vivid driver, under qemu (part of make test) --------------
DEBS_VIVID := qemu-system-x86 busybox-static cpio kmod xz-utils binutils
VIVID_SRCS := tests/v4l2/vivid_test.cpp frontend/src/v4l2.cpp frontend/src/mjpeg.cpp frontend/src/rawlog.cpp \
  frontend/src/output_file.cpp
# Static, so the VM needs nothing else; under SAN=1 dynamic (the sanitizer runtimes are shared
# libraries) and scripts/vivid-test.sh copies its libraries into the VM.
ifeq ($(SAN),1)
VIVID_LINK :=
else
VIVID_LINK := -static
endif
$(BUILD)/vivid_test: $(VIVID_SRCS) $(FRONTEND_HDRS) lib
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(VIVID_LINK) $(VIVID_SRCS) -o $@ $(LIBCYL_A) -ljpeg -lm
TEST_EXTRA += $(STAMP)/debs-vivid $(BUILD)/vivid_test
TEST_EXTRA_BINS += scripts/vivid-test.sh:$(BUILD)/vivid_test
vivid-test: $(STAMP)/debs-vivid $(BUILD)/vivid_test
	scripts/vivid-test.sh $(BUILD)/vivid_test
.PHONY: vivid-test

# ---- the cyl tool -------------------------------------------------------------------------
FE_SYNTH_SRCS := $(sort $(wildcard frontend/src/synth/*.cpp))
FE_SYNTH_OBJS := $(FE_SYNTH_SRCS:frontend/src/synth/%.cpp=$(BUILD)/frontend/synth/%.o)
$(BUILD)/frontend/synth/%.o: frontend/src/synth/%.cpp $(wildcard frontend/src/synth/*.hpp) $(FRONTEND_HDRS) $(wildcard libcyl/include/cyl/*.h) | $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) -c $< -o $@
$(BUILD)/cyl: frontend/tools/cyl.cpp $(FE_SYNTH_OBJS) $(FRONTEND_A) lib
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) $< -o $@ $(FE_SYNTH_OBJS) $(FRONTEND_A) $(LIBCYL_A) $(CV_LIBS_CORE) -lm
tools: $(BUILD)/cyl
.PHONY: tools

# ---- frontend unit tests (GoogleTest) ------------------------------------------------------
FE_TEST_SRCS := $(sort $(wildcard tests/frontend/test_*.cpp))
FE_TEST_BINS := $(FE_TEST_SRCS:tests/frontend/%.cpp=$(BUILD)/tests/fe_%)
$(BUILD)/tests/fe_%: tests/frontend/%.cpp $(wildcard tests/frontend/*.hpp) $(FE_SYNTH_OBJS) $(FRONTEND_A) lib
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) $< -o $@ $(FE_SYNTH_OBJS) $(FRONTEND_A) $(LIBCYL_A) $(CV_LIBS) -lgtest -lgtest_main -pthread -lm
TEST_EXTRA += $(FE_TEST_BINS)
TEST_EXTRA_BINS += $(FE_TEST_BINS)

# ---- make bench: end-to-end replay ------------------------------------------------
$(BUILD)/bench_replay: bench/bench_replay.cpp $(FE_SYNTH_OBJS) $(FRONTEND_A) lib
	$(CXX) $(CXXFLAGS_ALL) $(CV_FLAGS) -O2 $< -o $@ $(FE_SYNTH_OBJS) $(FRONTEND_A) $(LIBCYL_A) $(CV_LIBS) -lm

# ---- the cyl tool as a user meets it (exit codes, bad input, SIGINT) --------------------------
TEST_EXTRA += $(BUILD)/cyl $(BUILD)/cyl-render $(BUILD)/cyl-synth-validate $(BUILD)/cyl_paper
TEST_EXTRA_BINS += tests/frontend/test_cli.sh:$(BUILD)/cyl
# every writer of every tool against a device node, a FIFO and symlinks (only regular files are replaced)
TEST_EXTRA += $(BUILD)/cyl-train $(BUILD)/cyl-calibrate
TEST_EXTRA_BINS += tests/frontend/test_output_safety.sh:$(BUILD)

# ---- make soak: 10,000 synthetic frames in one process; peak RSS at the end must equal its
# peak at frame 1,000 (scripts/soak.sh) ----------------------------------------------
soak: $(BUILD)/cyl
	@BUILD=$(BUILD) scripts/soak.sh
.PHONY: soak
TEST_EXTRA_BINS += tests/frontend/test_bad_input.sh:$(BUILD)/cyl
