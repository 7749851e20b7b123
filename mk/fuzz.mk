# SPDX-License-Identifier: BSD-3-Clause
# Fuzzing with libFuzzer (Debian's clang): targets in tests/fuzz/, seed corpora in
# tests/fuzz/corpus/<target>/ (committed). Findings are written to build/fuzz/findings/.
#   make fuzz-smoke            each target for FUZZ_SECONDS (default 60) -- part of CI
#   make fuzz FUZZ_SECONDS=600 the long runs before a release
DEBS_FUZZ := clang libclang-rt-14-dev
FUZZ_SECONDS ?= 60
FUZZ_DIR := build/fuzz
FUZZ_FLAGS := -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all
FUZZ_LIB := libcyl/build/fuzz/libcyl.a
FUZZ_TARGETS := fuzz_table fuzz_detect fuzz_rawlog fuzz_calib fuzz_obslog

$(FUZZ_LIB): $(wildcard libcyl/src/*.c libcyl/src/*.h libcyl/include/cyl/*.h) $(STAMP)/debs-fuzz
	$(MAKE) -C libcyl BUILD=build/fuzz CC=clang \
	  CFLAGS='-g -O1 -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all'
$(FUZZ_DIR)/%: tests/fuzz/%.c $(FUZZ_LIB)
	@mkdir -p $(dir $@)
	clang -std=c99 $(FUZZ_FLAGS) -Ilibcyl/include $< -o $@ $(FUZZ_LIB) -lm
$(FUZZ_DIR)/%: tests/fuzz/%.cpp $(FUZZ_LIB) frontend/src/rawlog.cpp frontend/src/output_file.cpp frontend/src/calibration.cpp $(STAMP)/debs-cv
	@mkdir -p $(dir $@)
	clang++ -std=c++17 $(FUZZ_FLAGS) -Ilibcyl/include -Ifrontend/include $(CV_FLAGS) $< \
	  frontend/src/rawlog.cpp frontend/src/output_file.cpp frontend/src/calibration.cpp -o $@ $(FUZZ_LIB) $(CV_LIBS) -lm

# The observation-log reader is Python (slam_demo/cylslam/obslog.py): its target runs under atheris,
# libFuzzer's engine for Python, installed into the project venv.
$(FUZZ_DIR)/fuzz_obslog: tests/fuzz/fuzz_obslog.py tests/fuzz/requirements.txt $(VENV)/.stamp $(STAMP)/debs-fuzz
	$(VENV)/bin/pip install -q -r tests/fuzz/requirements.txt
	@mkdir -p $(dir $@)
	touch $@

fuzz-build: $(addprefix $(FUZZ_DIR)/,$(FUZZ_TARGETS))
fuzz-smoke fuzz: fuzz-build
	VENV=$(VENV) scripts/fuzz.sh $(FUZZ_SECONDS) $(FUZZ_TARGETS)
.PHONY: fuzz fuzz-smoke fuzz-build
