#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The slam_demo pytest suite in the project venv (make slam-venv creates it), after building the
# cyl binding in place (build/python), which the back end's exact camera model calls.
cd "$(dirname "$0")/.." && python/build.sh >/dev/null && exec .venv/bin/python -m pytest -q -p no:cacheprovider slam_demo/tests "$@"
