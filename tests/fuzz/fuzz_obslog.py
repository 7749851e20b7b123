#!/usr/bin/env python3
"""libFuzzer target (through atheris) for the observation-log reader, cylslam.obslog.

Every input is parsed twice, strict and with skip_bad=True. The reader's contract
(slam_demo/cylslam/obslog.py, docs/formats.md):
  - it either returns a Dataset or raises ObsLogError whose message starts with the log's name;
    any other exception (KeyError, TypeError, RecursionError, numpy's LinAlgError, ...) is a bug;
  - a returned Dataset has at least one step, strictly increasing frame seq, and every usable
    observation (not flagged no-range or invalid) has a finite range >= 0, a finite bearing, a
    confidence in [0, 1] and a finite symmetric positive semi-definite covariance; every odometry
    covariance after the first step is finite, symmetric and positive definite.
Run by scripts/fuzz.sh (make fuzz-smoke / make fuzz) with the seed corpus
tests/fuzz/corpus/fuzz_obslog/ and the dictionary tests/fuzz/fuzz_obslog.dict.
"""
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


def _psd(m, strict=False):
    if not np.all(np.isfinite(m)):
        return False
    if not np.allclose(m, m.T):
        return False
    ev = np.linalg.eigvalsh(m)
    return ev.min() > 0 if strict else ev.min() >= -1e-12 * max(1.0, ev.max())


def _check(ds):
    assert ds.steps, "Dataset without steps"
    seqs = [s.seq for s in ds.steps]
    assert all(a < b for a, b in zip(seqs, seqs[1:])), f"seq not increasing: {seqs}"
    for k, s in enumerate(ds.steps):
        if k > 0:
            assert s.odom is not None and s.odom.shape == (3,), "step without odometry"
            assert np.all(np.isfinite(s.odom)), "non-finite odometry"
            assert _psd(s.odom_cov, strict=True), f"bad odometry covariance {s.odom_cov}"
        for o in s.obs:
            if o.flags & (FLAG_NO_RANGE | FLAG_INVALID):
                continue
            assert math.isfinite(o.range_m) and o.range_m >= 0, f"bad range {o.range_m}"
            assert math.isfinite(o.bearing_rad), f"bad bearing {o.bearing_rad}"
            assert 0.0 <= o.confidence <= 1.0, f"bad confidence {o.confidence}"
            assert o.cov.shape == (2, 2) and _psd(o.cov), f"bad covariance {o.cov}"
            if o.jac_calib is not None:
                assert o.jac_calib.shape == (2, 8) and np.all(np.isfinite(o.jac_calib))
                assert _psd(o.cov_frame), f"bad cov_frame {o.cov_frame}"
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


def main():
    np.seterr(all="ignore")  # overflow in eigvalsh of huge finite numbers is not a reader bug
    atheris.Setup(sys.argv, TestOneInput)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
