#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Fit the centroid's time-correlated bias (cylslam's --bias-gm, --bias-gm-tau, --white-scale) on
rendered drives with truth.

For each seed: cyl-render (a drive with a calibration error drawn once; the renderer prints the true
camera) -> cyl detect (the defaults consistency.py uses). Each kept observation (flags without
--reject-flags, default 0x320; confidence >= 0.5) is taken through libcyl's camera model (the cyl binding) at the TRUE
calibration, and its residual in the image -- the pixel offset that would put the observation on
the true landmark seen from the true pose -- is attributed to the landmark whose bearing it is
nearest. Residuals of 1 px or more are left out and counted: they are partial occlusions (a box
passing in front of a landmark moves its centroid by up to 8 px over 20-30 frames), not the drift
being fitted. Each landmark's residuals in time, per axis, are one sequence of
cylslam.centroid_noise's model (a constant bias with the frontend's prior, a Gauss-Markov drift,
white noise scaled from the frontend's), fitted by maximum likelihood.

Usage: scripts/fit_centroid_gm.py [--seeds 1-20] [--frames 1000] [--build DIR] [--work DIR]
                                  [--reject-flags MASK] [--noise-scale K]
  --seeds         the drives (default 1-20: the tuning seeds; never the held-out 101-120)
  --work          where the observation logs are kept between runs (default build/centroid_gm;
                  a subdirectory per noise scale other than 1)
  --reject-flags  observations with any of these flag bits are left out (default 0x320: the far
                  views kept; 0xf20 keeps only what cylslam run uses whole)
  --noise-scale   render with the scene's sensor noise times K (as consistency.py --noise-scale)
The last line is one JSON object with the fitted values and the cylslam options they make.
Exit codes: 0 fitted, 1 a tool failed, 2 bad command line.
"""
import argparse
import json
import math
import os
import re
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "slam_demo"))
from cylslam.camera_model import range_bearing_model  # noqa: E402
from cylslam.centroid_noise import Sequence, fit  # noqa: E402
from consistency import render_and_detect, seeds_arg  # noqa: E402  (the drives consistency.py runs)

TRUE_CAM = re.compile(r"true camera = calibration \+ error: fx (\S+) fy (\S+) cx (\S+) cy (\S+) px, "
                      r"tilt (\S+) yaw (\S+) deg, height (\S+) offset (\S+) m")
GROSS_PX = 1.0


def drive(build, work, seed, frames, scene=None):
    """(observation log path, true calibration error in jac_calib's order), rendering if needed."""
    d = os.path.join(work, f"seed{seed}")
    obs, cal = os.path.join(d, "observations.jsonl"), os.path.join(d, "true_calibration.json")
    if os.path.exists(obs) and os.path.exists(cal):
        with open(cal) as f:
            c = json.load(f)
        if c.get("frames") == frames:
            return obs, c["delta"]
    obs, err = render_and_detect(build, d, seed, frames, scene)
    m = TRUE_CAM.search(err)
    if not m:
        sys.stderr.write(f"cyl-render -s {seed}: no 'true camera' line in its output\n")
        sys.exit(1)
    fx, fy, cx, cy, tilt, yaw, h, s = (float(x) for x in m.groups())
    delta = [fx, fy, cx, cy, math.radians(tilt), math.radians(yaw), h, s]
    with open(cal, "w") as f:
        json.dump({"frames": frames, "delta": delta}, f)
    return obs, delta


def residuals(path, delta, reject=0x320):
    """{landmark id: rows (t, du, dv, var_u, var_v, bias_var_u, bias_var_v)} and the count of gross
    ones, over the observations with no flag bit of `reject`."""
    recs = [json.loads(line) for line in open(path)]
    rbm, why = range_bearing_model(recs[0])
    if rbm is None:
        sys.stderr.write(f"{path}: {why}\n")
        sys.exit(1)
    lms = {r["id"]: (r["x_m"], r["y_m"], r["class_id"]) for r in recs if r["type"] == "truth_landmark"}
    poses = {r["seq"]: (r["x_m"], r["y_m"], r["theta_rad"]) for r in recs if r["type"] == "truth_pose"}
    out, gross = {}, 0
    for o in recs:
        if o["type"] != "obs" or o["flags"] & reject or o["confidence"] < 0.5 or o["seq"] not in poses:
            continue
        e = rbm.eval(o["u_px"], o["v_px"], delta)
        if e is None:
            continue
        r_m, b_m, jac = e
        a = np.array([[jac[1][0], jac[1][1]], [jac[0][0], jac[0][1]]])   # d(bearing, range)/d(u, v)
        p = poses[o["seq"]]
        best = None
        for i, (x, y, c) in lms.items():
            if c != o["class_id"]:
                continue
            nu = np.array([(math.atan2(y - p[1], x - p[0]) - p[2] - b_m + math.pi) % (2 * math.pi) - math.pi,
                           math.hypot(x - p[0], y - p[1]) - r_m])
            d = np.linalg.solve(a, nu)
            if best is None or abs(d[0]) < abs(best[1][0]):
                best = (i, d)
        if best is None or abs(best[1][0]) > 20:
            continue
        i, d = best
        if abs(d[0]) >= GROSS_PX or abs(d[1]) >= GROSS_PX:
            gross += 1
            continue
        out.setdefault(i, []).append((o["t"], d[0], d[1], o["var_u_px2"], o["var_v_px2"], *o["bias_var_px2"]))
    return out, gross


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=seeds_arg, default=list(range(1, 21)))
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--build", default="build")
    ap.add_argument("--work", default=os.path.join("build", "centroid_gm"))
    ap.add_argument("--reject-flags", default="0x320")
    ap.add_argument("--noise-scale", type=float, default=1.0)
    a = ap.parse_args()
    if any(s > 100 for s in a.seeds):
        ap.error("--seeds: the held-out seeds (above 100) choose nothing")
    try:
        reject = int(a.reject_flags, 0)
    except ValueError:
        ap.error(f"--reject-flags {a.reject_flags!r}: not an integer (e.g. 0x320)")
    if not a.noise_scale > 0:
        ap.error(f"--noise-scale {a.noise_scale}: must be > 0")
    work, scene = a.work, None
    if a.noise_scale != 1.0:
        from consistency import noisy_scene
        work = os.path.join(a.work, f"noise_x{a.noise_scale:g}")
        os.makedirs(work, exist_ok=True)
        scene = noisy_scene(a.build, work, a.noise_scale)
    seqs = {"u": [], "v": []}
    n_gross = n_kept = 0
    for k, seed in enumerate(a.seeds):
        obs, delta = drive(a.build, work, seed, a.frames, scene)
        by_lm, gross = residuals(obs, delta, reject)
        n_gross += gross
        for rows in by_lm.values():
            r = np.array(sorted(rows))
            if len(r) < 5:
                continue
            n_kept += len(r)
            for ax, ci, vi, bi in (("u", 1, 3, 5), ("v", 2, 4, 6)):
                seqs[ax].append(Sequence(r[:, 0], r[:, ci], np.maximum(r[:, vi] - r[:, bi], 1e-6),
                                         float(np.median(r[:, bi]))))
        sys.stderr.write(f"\rseed {seed} ({k + 1}/{len(a.seeds)})")
    sys.stderr.write("\n")
    res = {}
    for ax, start in (("u", (0.1, 2.0, 1.0)), ("v", (0.15, 10.0, 1.0))):
        res[ax] = fit(seqs[ax], start=start)
        r = res[ax]
        print(f"{ax}: sigma {r['sigma_px']:.3f} px, tau {r['tau_s']:.2f} s, white x{r['white_scale']:.2f}; "
              f"log-likelihood {r['loglik']:.0f} against {r['loglik_white_only']:.0f} for white noise alone "
              f"(which wants the frontend's variance x{r['white_only_scale']:.2f})")
    opts = (f"--bias-gm {res['u']['sigma_px']:.3f},{res['v']['sigma_px']:.3f} "
            f"--bias-gm-tau {res['u']['tau_s']:.2f},{res['v']['tau_s']:.2f} "
            f"--white-scale {res['u']['white_scale']:.2f},{res['v']['white_scale']:.2f}")
    print(f"{n_kept} views of {len(seqs['u'])} landmark sequences on seeds {a.seeds[0]}-{a.seeds[-1]}; "
          f"{n_gross} residuals of {GROSS_PX:g} px or more left out")
    print(json.dumps({"seeds": a.seeds, "views": n_kept, "gross_left_out": n_gross,
                      "u": res["u"], "v": res["v"], "cylslam_options": opts}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
