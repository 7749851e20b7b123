# SPDX-License-Identifier: BSD-3-Clause
# libcyl uncertainty model: C++ calibration loader, the paper tool, OpenCV tests.
#   make paper       the paper's Tables 6, 8, 9 beside ours; last line JSON
# Test programs added to `make test`: build/tests/test_undistort_cv, build/tests/test_calibration.

# The calibration reader comes from the frontend library (mk/frontend.mk, included after this file:
# hence the literal path).
UNC_FE_OBJ := $(BUILD)/frontend/libfrontend.a
UNC_CV_CFLAGS = $$(pkg-config --cflags opencv4)
UNC_CV_LIBS = $$(pkg-config --libs opencv4) -lyaml-cpp -ljpeg

$(BUILD)/cyl_paper: frontend/tools/cyl_paper.cpp $(UNC_FE_OBJ) lib
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(UNC_CV_CFLAGS) $< $(UNC_FE_OBJ) -o $@ $(LIBCYL_A) $(UNC_CV_LIBS) -lm

$(BUILD)/tests/test_undistort_cv: tests/cv/test_undistort_cv.cpp $(UNC_FE_OBJ) lib $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(UNC_CV_CFLAGS) -DUNC_CALIB_DIR=\"$(CURDIR)/calib_data\" $< $(UNC_FE_OBJ) -o $@ $(LIBCYL_A) $(UNC_CV_LIBS) \
	  -lgtest -lgtest_main -pthread -lm

$(BUILD)/tests/test_calibration: tests/cv/test_calibration.cpp $(UNC_FE_OBJ) lib $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $(UNC_CV_CFLAGS) -DUNC_CALIB_DIR=\"$(CURDIR)/calib_data\" $< $(UNC_FE_OBJ) -o $@ $(LIBCYL_A) $(UNC_CV_LIBS) \
	  -lgtest -lgtest_main -pthread -lm

TEST_EXTRA += $(BUILD)/tests/test_undistort_cv $(BUILD)/tests/test_calibration
TEST_EXTRA_BINS += $(BUILD)/tests/test_undistort_cv $(BUILD)/tests/test_calibration

# make bench-uncertainty: cyl_observe time per frame vs cyl_segment (target <= 10%). Its last
# line is a JSON fragment meant for scripts/bench.sh's BENCH_EXTRA_JSON.
$(BUILD)/bench_uncertainty: bench/bench_uncertainty.cpp bench/bench_frames.hpp tests/common/synth_frames.c tests/common/rng.c lib
	@mkdir -p $(dir $@)
	$(CC) $(TEST_CFLAGS) -O3 -c tests/common/synth_frames.c -o $(BUILD)/unc_synth_frames.o
	$(CC) $(TEST_CFLAGS) -O3 -c tests/common/rng.c -o $(BUILD)/unc_rng.o
	$(CXX) $(CXXFLAGS_ALL) -Ibench -O3 $< $(BUILD)/unc_synth_frames.o $(BUILD)/unc_rng.o -o $@ $(LIBCYL_A) -lm

.PHONY: bench-uncertainty
bench-uncertainty: $(BUILD)/bench_uncertainty
	@$(BUILD)/bench_uncertainty
