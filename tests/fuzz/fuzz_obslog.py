#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""libFuzzer target (through atheris) for the observation-log reader, cylslam.obslog.

Every input is parsed twice, strict and with skip_bad=True. The reader's contract
(slam_demo/cylslam/obslog.py, docs/formats.md):
  - it either returns a Dataset or raises ObsLogError whose message starts with the log's name;
    any other exception (KeyError, TypeError, RecursionError, numpy's LinAlgError, ...) is a bug;
  - a returned Dataset has at least one step, and every usable observation (not flagged no-range
    or invalid) has a finite range >= 0, a finite bearing, a confidence in [0, 1] and a finite
    symmetric positive semi-definite covariance; every odometry covariance after the first step
    is finite, symmetric and positive definite. These are checked here by other means than the
    reader's (2x2: diagonal and determinant; 3x3: Cholesky), so a flaw in its test shows;
  - when the strict parse succeeds, the `frame` lines of the input, read independently, have
    strictly increasing seq.
Run by scripts/fuzz.sh (make fuzz-smoke / make fuzz) with the seed corpus
tests/fuzz/corpus/fuzz_obslog/ and the dictionary tests/fuzz/fuzz_obslog.dict.
"""
import json
import math
import os
import sys

import atheris

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "slam_demo"))
with atheris.instrument_imports(include=["cylslam"]):
    from cylslam.data import FLAG_INVALID, FLAG_NO_RANGE
    from cylslam.obslog import ObsLogError, parse_obslog

import numpy as np

NAME = "fuzz.jsonl"


def _psd2(m):
    """2x2 symmetric PSD by its entries: a, c >= 0 and ac - b^2 >= 0 (relative tolerance)."""
    if m.shape != (2, 2) or not np.all(np.isfinite(m)):
        return False
    a, b, b2, c = float(m[0, 0]), float(m[0, 1]), float(m[1, 0]), float(m[1, 1])
    scale = max(abs(a), abs(c), 1.0)
    tol = 1e-9 * scale
    return (abs(b - b2) <= tol and a >= -tol and c >= -tol
            and a / scale * c / scale - (b / scale) ** 2 >= -1e-9)


def _pd3(m):
    """3x3 symmetric positive definite: a Cholesky factorisation exists."""
    if m.shape != (3, 3) or not np.all(np.isfinite(m)) or not np.allclose(m, m.T):
        return False
    try:
        np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        return False
    return True


def _frame_seqs(data):
    """seq of each well-formed `frame` line, read without the reader (the last line counts only
    when terminated: the format lets a reader ignore an interrupted last line)."""
    out = []
    lines = data.split(b"\n")
    for line in lines[:-1]:
        try:
            rec = json.loads(line)
        except (ValueError, RecursionError):
            continue
        if isinstance(rec, dict) and rec.get("type") == "frame" and isinstance(rec.get("seq"), int):
            out.append(rec["seq"])
    return out


def _check(ds):
    assert ds.steps, "Dataset without steps"
    for k, s in enumerate(ds.steps):
        if k > 0:
            assert s.odom is not None and s.odom.shape == (3,), "step without odometry"
            assert np.all(np.isfinite(s.odom)), "non-finite odometry"
            assert _pd3(s.odom_cov), f"bad odometry covariance {s.odom_cov}"
        for o in s.obs:
            if o.flags & (FLAG_NO_RANGE | FLAG_INVALID):
                continue
            assert math.isfinite(o.range_m) and o.range_m >= 0, f"bad range {o.range_m}"
            assert math.isfinite(o.bearing_rad), f"bad bearing {o.bearing_rad}"
            assert 0.0 <= o.confidence <= 1.0, f"bad confidence {o.confidence}"
            assert _psd2(o.cov), f"bad covariance {o.cov}"
            if o.jac_calib is not None:
                assert o.jac_calib.shape == (2, 8) and np.all(np.isfinite(o.jac_calib))
                assert _psd2(o.cov_frame), f"bad cov_frame {o.cov_frame}"
    if ds.calib_cov is not None:
        assert ds.calib_cov.shape == (8, 8) and np.all(np.isfinite(ds.calib_cov))


def TestOneInput(data: bytes):
    for skip_bad in (False, True):
        try:
            ds = parse_obslog(data, NAME, skip_bad=skip_bad)
        except ObsLogError as e:
            assert str(e).startswith(NAME), f"error message does not name the file: {e}"
            continue
        _check(ds)
        if not skip_bad:
            seqs = _frame_seqs(data)
            assert all(a < b for a, b in zip(seqs, seqs[1:])), f"frame seq not increasing: {seqs}"


def main():
    # numpy's overflow warnings (entries near 1e308) would flood the log; the reader must reject
    # such matrices on its own, and the checks above do not depend on eigvalsh
    np.seterr(all="ignore")
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
