# SPDX-License-Identifier: BSD-3-Clause
# Calibration tools (docs/calibration.md):
#   build/cyl-calibrate   intrinsics (Ceres, full covariance) and the robot mount's extrinsics
#   build/cyl-train       colour-table training (command line and interactive window; learn
#                         from labelled images)
#   build/cyl-score       a colour table against labelled held-out images
#   make calib-check      our calibration vs cv::calibrateCamera on OpenCV's sample images, the
#                         Monte Carlo of the sigmas; last line a JSON object
# Library sources in frontend/src/calib/ -> build/calib/libcalibtools.a (not part of libfrontend.a).
# FRONTEND_A and the synth objects are defined in mk/frontend.mk, which is included after this
# file: prerequisites below use the literal paths.
DEBS_CALIB := libceres-dev libeigen3-dev libgoogle-glog-dev libgflags-dev libgtest-dev
DEBS_CALIBGUI := xvfb xdotool imagemagick

CALIB_SRCS := $(sort $(wildcard frontend/src/calib/*.cpp))
CALIB_OBJS := $(CALIB_SRCS:frontend/src/calib/%.cpp=$(BUILD)/calib/%.o)
CALIB_A := $(BUILD)/calib/libcalibtools.a
CALIB_FE_A := $(BUILD)/frontend/libfrontend.a
CALIB_SYNTH_OBJS := $(patsubst frontend/src/synth/%.cpp,$(BUILD)/frontend/synth/%.o,$(sort $(wildcard frontend/src/synth/*.cpp)))
CALIB_HDRS := $(wildcard frontend/include/cylfe/*.hpp) $(wildcard libcyl/include/cyl/*.h)
CALIB_CXXFLAGS = $(CXXFLAGS_ALL) -I/usr/include/eigen3 $(CV_FLAGS)
CALIB_LIBS = $(CALIB_A) $(CALIB_SYNTH_OBJS) $(CALIB_FE_A) $(LIBCYL_A) -lceres -lglog -lgflags $(CV_LIBS) -lpthread -lm
CALIB_DEPS := $(CALIB_A) $(CALIB_FE_A) $(CALIB_SYNTH_OBJS) lib

$(BUILD)/calib/%.o: frontend/src/calib/%.cpp $(CALIB_HDRS) $(wildcard frontend/src/calib/*.hpp) | $(STAMP)/debs-calib $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CALIB_CXXFLAGS) -c $< -o $@

$(CALIB_A): $(CALIB_OBJS)
	rm -f $@.tmp && ar rcs $@.tmp $^ && mv $@.tmp $@

$(BUILD)/cyl-calibrate: frontend/tools/cyl_calibrate.cpp $(CALIB_DEPS)
	$(CXX) $(CALIB_CXXFLAGS) $< -o $@.tmp $(CALIB_LIBS) && mv $@.tmp $@

$(BUILD)/cyl-train: frontend/tools/cyl_train.cpp $(CALIB_DEPS)
	$(CXX) $(CALIB_CXXFLAGS) $< -o $@.tmp $(CALIB_LIBS) && mv $@.tmp $@

$(BUILD)/cyl-score: frontend/tools/cyl_score.cpp $(CALIB_DEPS)
	$(CXX) $(CALIB_CXXFLAGS) $< -o $@.tmp $(CALIB_LIBS) && mv $@.tmp $@

calib-tools: $(BUILD)/cyl-calibrate $(BUILD)/cyl-train $(BUILD)/cyl-score
.PHONY: calib-tools

# ---- colour learning on real labelled images (docs/colour-learning.md) -------------------------
# make realeval: the full benchmark on the real image sets outside the repository (SHARED, default
# ../shared); make test runs its small committed form (tests/fixtures/real).
SHARED ?= ../shared
realeval: $(BUILD)/cyl $(BUILD)/cyl-render $(BUILD)/cyl-train $(BUILD)/cyl-score
	@python3 scripts/realeval.py --shared $(SHARED) --build $(BUILD)
.PHONY: realeval
TEST_EXTRA += $(BUILD)/cyl-score $(BUILD)/cyl-train $(BUILD)/cyl
TEST_EXTRA_BINS += tests/frontend/test_colour_learning.sh:$(BUILD)

# ---- tests and the check ------------------------------------------------------------------------
CALIB_TESTFLAGS = $(CALIB_CXXFLAGS) -Itests/calib -DCALIB_FIXTURES=\"$(CURDIR)/tests/fixtures/opencv_left\"
$(BUILD)/calib/calib_testlib.o: tests/calib/calib_testlib.cpp tests/calib/calib_testlib.hpp $(CALIB_HDRS) | $(STAMP)/debs-calib $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CALIB_TESTFLAGS) -c $< -o $@

$(BUILD)/calib/calib_check: tests/calib/calib_check.cpp $(BUILD)/calib/calib_testlib.o $(CALIB_DEPS)
	$(CXX) $(CALIB_TESTFLAGS) $< $(BUILD)/calib/calib_testlib.o -o $@.tmp $(CALIB_LIBS) && mv $@.tmp $@

# make calib-check: the comparison with OpenCV, a 1000-run Monte Carlo of the intrinsic sigmas and
# 100 mount renders; the last line is a JSON object (docs/calibration.md).
calib-check: $(BUILD)/calib/calib_check
	@$(BUILD)/calib/calib_check
.PHONY: calib-check

# GoogleTest programs tests/calib/test_*.cpp (they run the built tools too)
CALIB_TEST_SRCS := $(sort $(wildcard tests/calib/test_*.cpp))
CALIB_TEST_BINS := $(CALIB_TEST_SRCS:tests/calib/%.cpp=$(BUILD)/tests/calib_%)
$(BUILD)/tests/calib_%: tests/calib/%.cpp $(BUILD)/calib/calib_testlib.o $(CALIB_DEPS) $(BUILD)/cyl-calibrate $(BUILD)/cyl-train
	@mkdir -p $(dir $@)
	$(CXX) $(CALIB_TESTFLAGS) -DCALIB_BIN=\"$(CURDIR)/$(BUILD)\" $< $(BUILD)/calib/calib_testlib.o -o $@.tmp \
	  $(CALIB_LIBS) -lgtest -lgtest_main -pthread && mv $@.tmp $@
TEST_EXTRA += $(CALIB_TEST_BINS)
TEST_EXTRA_BINS += $(CALIB_TEST_BINS)
calib-test: $(CALIB_TEST_BINS)
	@scripts/run-tests.sh $(CALIB_TEST_BINS)
.PHONY: calib-test

# The interactive trainer under Xvfb (scripted mouse and keys, screenshots checked).
TEST_EXTRA += $(STAMP)/debs-calibgui $(BUILD)/cyl-train
TEST_EXTRA_BINS += tests/calib/gui_test.sh:$(BUILD)
TEST_EXTRA += $(BUILD)/cyl-score
calib-gui-test: $(STAMP)/debs-calibgui $(BUILD)/cyl-train $(BUILD)/cyl-score
	@tests/calib/gui_test.sh $(BUILD)
.PHONY: calib-gui-test

# make calib-data: regenerate calib_data/opencv_sample*.yaml (cyl-calibrate intrinsics on OpenCV's
# sample images) and calib_data/synthetic_mount*.yaml (cyl-calibrate mount on 10 floor renders).
$(BUILD)/calib/make_floor_renders: tests/calib/make_floor_renders.cpp $(BUILD)/calib/calib_testlib.o $(CALIB_DEPS)
	$(CXX) $(CALIB_TESTFLAGS) $< $(BUILD)/calib/calib_testlib.o -o $@.tmp $(CALIB_LIBS) && mv $@.tmp $@
calib-data: $(BUILD)/cyl-calibrate $(BUILD)/calib/make_floor_renders
	$(BUILD)/cyl-calibrate intrinsics -o calib_data/opencv_sample.yaml --ros calib_data/opencv_sample_ros.yaml \
	  --camera-name opencv_sample_left tests/fixtures/opencv_left/left*.jpg
	rm -rf $(BUILD)/calib/floor && mkdir -p $(BUILD)/calib/floor
	$(BUILD)/calib/make_floor_renders $(BUILD)/calib/floor 10 1
	$(BUILD)/cyl-calibrate mount --camera $(BUILD)/calib/floor/intrinsics.yaml --square 0.07 \
	  --board-centre 1.0,0 --board-axis 90 --landmark-height 0.30 --offset 0.10 --offset-sigma 0.00255 \
	  -o calib_data/synthetic_mount.yaml --ros calib_data/synthetic_mount_ros.yaml --camera-name synthetic \
	  $(BUILD)/calib/floor/startup*.png
.PHONY: calib-data
