# SPDX-License-Identifier: BSD-3-Clause
# slam_demo (cylslam): the Python SLAM back end. Included by the top Makefile.
#   make slam-venv     the project-local venv .venv/ (gtsam==4.3.0, numpy, matplotlib, pytest)
#   make slam-test     the slam_demo pytest suite (also part of `make test`)
#   make slam-synth    synthetic log -> SLAM -> plots, metrics, acceptance check (out/slam/synth)
#   make mrclam        MRCLAM Dataset 7, all 5 robots: the learned noise model with known and unknown
#                      association (--exclusion --reassoc 20 --starts 1,0.5,2) and one map of all robots; the fixed
#                      model's known association, checked (out/slam/mrclam*); last line JSON
#   make mrclam-noise  learn the noise model from Dataset 7's truth, with the held-out robot check
#   make victoria      gtsam's Victoria Park file (out/slam/victoria)
#   make slam-run LOG=FILE.jsonl [SLAM_ARGS=...]   SLAM on any observation log (out/slam/<name>)
# MRCLAM_DIR points at the UTIAS MRCLAM data set (not used by `make test`).

DEBS_PY    := python3-venv python3-pip
PYTHON3    ?= python3
VENV_PY    := $(VENV)/bin/python
MRCLAM_DIR ?= ../shared/data/mrclam/MRCLAM_Dataset7
SLAM_OUT   ?= out/slam
CYLSLAM    := PYTHONPATH=slam_demo $(VENV_PY) -m cylslam

$(VENV)/.stamp: slam_demo/requirements.txt $(STAMP)/debs-py
	$(PYTHON3) -m venv $(VENV)
	$(VENV)/bin/pip install -q -r slam_demo/requirements.txt
	touch $@

TEST_EXTRA += $(VENV)/.stamp
TEST_EXTRA_BINS += pytest:slam_demo/run_tests.sh
# pure Python: nothing in it for the sanitizers
SAN_SKIP += pytest:slam_demo/run_tests.sh

.PHONY: slam-venv slam-test slam-synth mrclam mrclam-noise victoria slam-run
slam-venv: $(VENV)/.stamp

slam-test: $(VENV)/.stamp
	$(VENV_PY) -m pytest -q -p no:cacheprovider slam_demo/tests

slam-synth: $(VENV)/.stamp
	@mkdir -p $(SLAM_OUT)
	$(CYLSLAM) synth $(SLAM_OUT)/synth.jsonl --frames 1200 --seed 7
	$(CYLSLAM) run $(SLAM_OUT)/synth.jsonl --out $(SLAM_OUT)/synth --check

# the learned noise model in every mode (known, unknown, one map), and the fixed model's known
# association with its check (<= 0.15 m per robot, as before the model was learned)
mrclam: $(VENV)/.stamp
	@mkdir -p $(SLAM_OUT)
	$(CYLSLAM) mrclam --dir $(MRCLAM_DIR) --robot all --assoc known --multi --out $(SLAM_OUT)/mrclam-fixed-known \
	  --summary-out $(SLAM_OUT)/mrclam-fixed-known.json --check-rmse 0.15 --check-time 30
	$(CYLSLAM) mrclam --dir $(MRCLAM_DIR) --robot all --assoc known --noise learned --multi \
	  --out $(SLAM_OUT)/mrclam-known --summary-out $(SLAM_OUT)/mrclam-known.json
	$(CYLSLAM) mrclam --dir $(MRCLAM_DIR) --robot all --assoc unknown --noise learned \
	  --exclusion --reassoc 20 --starts 1,0.5,2 \
	  --out $(SLAM_OUT)/mrclam-unknown --summary-out $(SLAM_OUT)/mrclam-unknown.json
	@$(VENV_PY) scripts/mrclam_summary.py $(SLAM_OUT)

# the noise model learned from MRCLAM Dataset 7's residuals against its truth (the shipped
# slam_demo/cylslam/models/mrclam_noise.json was written by this, from ../shared's Dataset 7)
mrclam-noise: $(VENV)/.stamp
	@mkdir -p $(SLAM_OUT)
	$(CYLSLAM) mrclam-noise --dir $(MRCLAM_DIR) --slam-check --out $(SLAM_OUT)/mrclam_noise.json \
	  --plot $(SLAM_OUT)/mrclam_noise_correlation.png

victoria: $(VENV)/.stamp
	$(CYLSLAM) victoria --out $(SLAM_OUT)/victoria

slam-run: $(VENV)/.stamp
	@test -n "$(LOG)" || { echo "usage: make slam-run LOG=FILE.jsonl [SLAM_ARGS=...]"; exit 2; }
	$(CYLSLAM) run $(LOG) --out $(SLAM_OUT)/$(basename $(notdir $(LOG))) $(SLAM_ARGS)

# the Python binding of the core (python/cyl, cffi): built in place and tested in make test;
# make pip-check installs the repository into a fresh venv the way a newcomer does (needs PyPI)
TEST_EXTRA += $(BUILD)/cyl $(BUILD)/cyl-render
TEST_EXTRA_BINS += pytest:python/run_tests.sh
# cffi builds its extension without the sanitizer flags
SAN_SKIP += pytest:python/run_tests.sh
pip-check:
	@scripts/pip-check.sh
.PHONY: pip-check

# make bag-demo: make demo's drive written as a ROS bag and read back with cyl-robotlog
# (scripts/bag-demo.sh; BAG_STORAGE=mcap|sqlite3|ros1, BAG_JPEG=1); last line JSON
bag-demo: $(BUILD)/cyl $(BUILD)/cyl-render $(VENV)/.stamp
	@python/build.sh >/dev/null
	@BUILD=$(BUILD) scripts/bag-demo.sh
.PHONY: bag-demo
