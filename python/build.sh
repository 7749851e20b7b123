#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Build the Python binding in place for the repository's own use: the cffi extension into
# build/python/cyl with the package's modules linked in beside it (PYTHONPATH=build/python).
set -euo pipefail
cd "$(dirname "$0")/.."
mkdir -p build/python/cyl
for f in python/cyl/*.py; do
  [ "$(basename "$f")" = _build.py ] || ln -sf "../../../$f" "build/python/cyl/$(basename "$f")"
done
CYL_CFFI_TMPDIR=build/python .venv/bin/python python/cyl/_build.py
