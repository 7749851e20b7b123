#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""make multirobot: several rendered robots, one map.

Three robots drive through the multiband scene (six striped cones, eight colour-coded cylinders;
docs/synthetic.md), each on its own path: the figure-eight from the scene's start (phase 0.3 rad),
the same figure-eight entered a third of the way round, and an ellipse (2.0 x 1.2 m). Each drive
is rendered with its own seed, detected by `cyl detect` with the landmark models read off the
scene (scripts/multiband.py), and mapped: every robot alone, then all in one graph with shared
landmarks, the start poses of robots 2 and 3 unknown (cylslam/multi.py). Only observations that
carry an identity (the codes read) enter the one-map graph; the cones, alike, do not.

Prints per robot the RMSE in the joint frame (one SE(2) alignment of all robots to truth) and alone,
and the landmark RMSE and ANEES; last line JSON. Seeds 101-103 (never used for a choice).
"""
import argparse
import json
import os
import re
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "slam_demo"))
from consistency import run  # noqa: E402
from multiband import prepare  # noqa: E402

PATHS = (("figure-eight from the scene's start", {}),
         ("figure-eight, a third of the way round", {"phase0": 0.3 + 2.0944}),
         ("ellipse 2.0 x 1.2 m", {"type": "ellipse", "a_m": 2.0, "b_m": 1.2, "phase0": 1.0}))


def scene_variant(text, changes):
    """The scene file's text with trajectory fields replaced."""
    for k, v in changes.items():
        pat = re.compile(rf"^(\s+{k}:\s*).*$", re.M)
        if not pat.search(text):
            raise SystemExit(f"multirobot: the scene file has no trajectory field {k}")
        text = pat.sub(lambda m: m.group(1) + (str(v) if isinstance(v, str) else repr(float(v))), text, count=1)
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=None, help="output folder (default BUILD/multirobot)")
    ap.add_argument("--frames", type=int, default=700)
    ap.add_argument("--version", action="version", version="multirobot.py (libcyl project)")
    a = ap.parse_args()
    from cylslam import metrics
    from cylslam.backend import Params, Slam
    from cylslam.multi import evaluate_multi, run_multi
    from cylslam.obslog import read_obslog
    out = a.out or os.path.join(a.build, "multirobot")
    os.makedirs(out, exist_ok=True)
    render = os.path.join(a.build, "cyl-render")
    t0 = time.time()
    base, cam, table, cfg, _, _ = prepare(render, out)
    with open(base) as f:
        text = f.read()
    datasets, labels = [], []
    for k, (what, changes) in enumerate(PATHS):
        seed = 101 + k
        d = os.path.join(out, f"robot{k + 1}")
        os.makedirs(d, exist_ok=True)
        scene = os.path.join(d, "scene.yaml")
        with open(scene, "w") as f:
            f.write(scene_variant(text, changes))
        raw, log = os.path.join(d, "drive.cylraw"), os.path.join(d, "observations.jsonl")
        sys.stderr.write(f"multirobot: robot {k + 1} ({what}, seed {seed}): render, detect\n")
        run([render, "-S", scene, "-s", str(seed), "-n", str(a.frames), "-o", raw, "-q"])
        run([os.path.join(a.build, "cyl"), "detect", raw, "--table", table, "--calib", cam, "--config", cfg,
             "--out", log, "--quiet"])
        os.remove(raw)
        datasets.append(read_obslog(log))
        labels.append(k + 1)
    p = Params(assoc="known", robust="none")
    # each robot alone with the identities it read (mixed: the cones gated), for comparison
    alone = {}
    for lab, ds in zip(labels, datasets):
        res = Slam(Params(assoc="mixed")).run(ds)
        alone[lab] = metrics.evaluate(ds, res)
    res = run_multi(datasets, labels, p)
    m = evaluate_multi(datasets, labels, res)
    for n in res.notes:
        print(f"note: {n}")
    print(f"One map from {len(res.robots)} rendered robots (multiband scene, {a.frames} frames each; coded "
          f"landmarks only): {res.stats['poses']} poses, {res.stats['observations_used']} observations, "
          f"{res.stats['landmarks']} landmarks, {res.stats['t_total_s']:.1f} s")
    print("| robot | path | RMSE in the joint frame m | RMSE alone (one map) m | mapped alone (mixed) m |")
    print("|---|---|---|---|---|")
    for k, lab in enumerate(labels):
        r = m["robots"].get(str(lab))
        if r is None:
            print(f"| {lab} | {PATHS[k][0]} | left out | | {alone[lab]['ate_m']:.4f} |")
            continue
        print(f"| {lab} | {PATHS[k][0]} | {r['aligned_rmse_joint_frame_m']:.4f} | {r['own_aligned_rmse_m']:.4f} | "
              f"{alone[lab]['ate_m']:.4f} |")
    print(f"landmarks: RMSE {m.get('landmark_rmse_aligned_m', float('nan')):.4f} m in the joint frame, "
          f"ANEES {m.get('anees_landmarks', float('nan')):.2f}; {time.time() - t0:.0f} s in all")
    per = [m["robots"][str(lab)]["aligned_rmse_joint_frame_m"] for lab in res.robots]
    print(json.dumps({"robots": len(labels), "robots_mapped": len(res.robots), "frames": a.frames,
                      "multi_aligned_rmse_max_m": round(max(per), 5),
                      "multi_landmark_rmse_m": round(m.get("landmark_rmse_aligned_m", float("nan")), 5),
                      "multi_landmark_anees": round(m.get("anees_landmarks", float("nan")), 3),
                      "alone_aligned_rmse_max_m": round(max(v["ate_m"] for v in alone.values()), 5)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
