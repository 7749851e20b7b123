#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The slam_demo pytest suite in the project venv (make slam-venv creates it).
cd "$(dirname "$0")/.." && exec .venv/bin/python -m pytest -q -p no:cacheprovider slam_demo/tests "$@"
