# SPDX-License-Identifier: BSD-3-Clause
"""cylslam: landmark SLAM back end for libcyl observation logs (and MRCLAM / Victoria Park).

Modules: data (common in-memory model), obslog (docs/formats.md JSON Lines reader/writer),
mrclam, victoria (readers), synth (synthetic logs), backend (GTSAM graph, iSAM2, association),
metrics, plot, cli (python -m cylslam).
"""
__version__ = "0.9.0"  # = CYL_VERSION_STRING of libcyl/include/cyl/version.h (tested)
