#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The Python binding's tests: build the cffi extension with the project venv into build/python
# (the package's sources are linked in beside it), then pytest python/tests (make test runs this;
# CYL_BUILD names the C tools' folder).
set -euo pipefail
cd "$(dirname "$0")/.."
python/build.sh
exec env PYTHONPATH=build/python .venv/bin/python -m pytest -q -p no:cacheprovider python/tests "$@"
