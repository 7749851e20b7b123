# SPDX-License-Identifier: BSD-3-Clause
# The synthetic camera with ground truth and the paper's consistency experiments
# (docs/synthetic.md).
#   make render      render the default drive (1000 frames) into build/drive.cylraw
#   make validate    Tables 1-3, 6-7 and the confidence check; plots in build/validate/;
#                    last line a JSON summary
#   make synth-data  regenerate calib_data/synthetic.cylt and calib_data/synthetic_camera.yaml
# Test programs added to `make test`: build/tests/synth_test_* (tests/synth/test_*.cpp).

SYNTH_SRCS := $(sort $(wildcard frontend/src/synth/*.cpp))
ifeq ($(strip $(FE_SYNTH_OBJS)),)
# mk/frontend.mk does not compile frontend/src/synth: do it here.
SYNTH_OBJS := $(SYNTH_SRCS:frontend/src/synth/%.cpp=$(BUILD)/synth/%.o)
$(BUILD)/synth/%.o: frontend/src/synth/%.cpp $(wildcard frontend/src/synth/*.hpp) $(wildcard frontend/include/cylfe/*.hpp) \
		$(wildcard libcyl/include/cyl/*.h) | $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $$(pkg-config --cflags opencv4) -c $< -o $@
else
SYNTH_OBJS := $(FE_SYNTH_OBJS)
endif
SYNTH_A := $(BUILD)/synth/libsynth.a
SYNTH_FE_A := $(or $(FRONTEND_A),$(BUILD)/frontend/libfrontend.a)
SYNTH_CV = $$(pkg-config --cflags --libs opencv4) -lyaml-cpp -ljpeg

$(SYNTH_A): $(SYNTH_OBJS)
	@mkdir -p $(dir $@)
	rm -f $@.tmp && ar rcs $@.tmp $^ && mv $@.tmp $@

$(BUILD)/cyl-render: frontend/tools/cyl_render.cpp $(SYNTH_A) $(SYNTH_FE_A) lib $(STAMP)/debs-cv
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ $(SYNTH_A) $(SYNTH_FE_A) $(LIBCYL_A) $(SYNTH_CV) -lm

$(BUILD)/cyl-synth-validate: frontend/tools/cyl_synth_validate.cpp $(SYNTH_A) $(SYNTH_FE_A) lib $(STAMP)/debs-cv
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ $(SYNTH_A) $(SYNTH_FE_A) $(LIBCYL_A) $(SYNTH_CV) -lm

SYNTH_TEST_SRCS := $(sort $(wildcard tests/synth/test_*.cpp))
SYNTH_TEST_BINS := $(SYNTH_TEST_SRCS:tests/synth/%.cpp=$(BUILD)/tests/synth_%)
$(BUILD)/tests/synth_%: tests/synth/%.cpp $(SYNTH_A) $(SYNTH_FE_A) lib $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	$(CXX) $(CXXFLAGS_ALL) $< -o $@ $(SYNTH_A) $(SYNTH_FE_A) $(LIBCYL_A) \
	  $(SYNTH_CV) -lgtest -lgtest_main -pthread -lm

TEST_EXTRA += $(SYNTH_TEST_BINS)
TEST_EXTRA_BINS += $(SYNTH_TEST_BINS)

.PHONY: render validate synth-data
render: $(BUILD)/cyl-render
	$(BUILD)/cyl-render --scene default --frames 1000 --seed 7 --output $(BUILD)/drive.cylraw

validate: $(BUILD)/cyl-synth-validate
	@$(BUILD)/cyl-synth-validate --out $(BUILD)/validate

synth-data: $(BUILD)/cyl-render
	$(BUILD)/cyl-render --scene default --seed 1 --write-table calib_data/synthetic.cylt -q
	$(BUILD)/cyl-render --scene default --write-camera calib_data/synthetic_camera.yaml
	$(BUILD)/cyl-render --scene default --write-scene calib_data/synthetic_scene.yaml

# make consistency: held-out seeds 101-120 through render -> detect -> SLAM, the imaging sweep and the
# pixel-noise-only NEES (scripts/consistency.py; about 25 minutes); make test runs its --quick form.
consistency: $(BUILD)/cyl $(BUILD)/cyl-render $(BUILD)/cyl-synth-validate .venv/.stamp
	@.venv/bin/python scripts/consistency.py --build $(BUILD)
.PHONY: consistency
TEST_EXTRA += $(BUILD)/cyl $(BUILD)/cyl-render $(BUILD)/cyl-synth-validate .venv/.stamp
TEST_EXTRA_BINS += tests/synth/test_consistency_quick.sh:$(BUILD)
# statistics, not memory safety: 662 of the sanitizer run's 1,099 s of tests, while render, detect
# and the sweep's code run under the sanitizers in the other tests
SAN_SKIP += tests/synth/test_consistency_quick.sh:$(BUILD)

# make multiband: landmarks of several colours (striped cones, coded cylinders) on held-out drives of
# the multiband scene: one observation per landmark, identities, range bias, SLAM with and without
# identities (scripts/multiband.py; last line JSON); make test runs its --quick form.
multiband: $(BUILD)/cyl $(BUILD)/cyl-render .venv/.stamp
	@.venv/bin/python scripts/multiband.py --build $(BUILD) --check
.PHONY: multiband
# make multirobot: three rendered robots on different paths through the multiband scene, one map
# from their coded landmarks (scripts/multirobot.py; about 2.5 min)
multirobot: $(BUILD)/cyl $(BUILD)/cyl-render .venv/.stamp
	@.venv/bin/python scripts/multirobot.py --build $(BUILD)
.PHONY: multirobot
TEST_EXTRA_BINS += tests/synth/test_multiband_quick.sh:$(BUILD)
# statistics, not memory safety: grouping and observing run under the sanitizers in the unit tests
SAN_SKIP += tests/synth/test_multiband_quick.sh:$(BUILD)
