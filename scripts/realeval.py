#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""make realeval: colour learning and detection on real labelled images (docs/colour-learning.md).

One recipe for every set (cyl-train learn and cyl-score with their defaults, no per-set tuning):
  * RoboCup MSL ball (yellow/orange ball; yellow seats, shirts and orange robot covers as
    distractors): learn on the images dated 2019-2023 (22), test on those from 2024 on (119);
  * FRC cones and cubes (yellow cone, blue cube; a blue backpack as distractor): learn on 10
    images of valid/ (every 12th from the 6th, in name order), test on all of test/.
  * the hard rendered scene (cyl-render --scene hard: floor and wall in hues near the landmarks',
    coloured clutter, an illumination gradient, cast shadows, exposure and white-balance drift):
    learn on frame 0 (its truth boxes, and the landmarks' size for the expected-size gate), test on
    the other frames; recall and false blobs of the detector's observations (cyl-score with the
    scene's camera; also without it) against the truth boxes, and the bearing error of cyl
    detect's observations against the true landmarks.
Prints each set's training report and scores, then one JSON line with the figures.

Usage: scripts/realeval.py [--shared DIR] [--build DIR] [--out DIR] [--subset DIR] [--train-option 'OPT V']
  --shared DIR  the folder holding data/real (default ../shared, or $CYL_SHARED)
  --train-option 'OPT V'  an option for every cyl-train learn, e.g. '--weak-alone-area 1000' (repeatable)
  --subset DIR  run on a small committed subset instead (its own train/test lists): the CI form
Exit codes: 0 ok, 1 data missing or a tool failed, 2 bad command line.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

FRC_TRAIN_EVERY, FRC_TRAIN_FIRST = 12, 5   # 0-based index of the first training image


def ball_year(path):
    return int(os.path.basename(path)[:4])


def _images(d):
    return sorted(os.path.join(d, f) for f in os.listdir(d) if f.lower().endswith((".jpg", ".jpeg", ".png")))


def splits(shared):
    """Train/test (and, for tuning, FRC's held-back valid images) of both real sets."""
    real = os.path.join(os.path.abspath(shared), "data", "real")
    ball = _images(os.path.join(real, "robocup_msl_ball", "images"))
    valid = _images(os.path.join(real, "frc_cones_cubes", "valid", "images"))
    test = _images(os.path.join(real, "frc_cones_cubes", "test", "images"))
    frc_train = [p for i, p in enumerate(valid) if i % FRC_TRAIN_EVERY == FRC_TRAIN_FIRST]
    return {
        "ball": {"train": [p for p in ball if ball_year(p) <= 2023], "test": [p for p in ball if ball_year(p) >= 2024]},
        "frc": {"train": frc_train, "tune": [p for p in valid if p not in frc_train], "test": test},
    }


def subset_splits(d):
    """A committed subset: DIR/<set>/{train,test}.list with paths relative to DIR/<set>."""
    out = {}
    for s in ("ball", "frc"):
        out[s] = {}
        for part in ("train", "test"):
            lst = os.path.join(d, s, part + ".list")
            with open(lst) as f:
                out[s][part] = [os.path.join(os.path.abspath(d), s, line.strip()) for line in f if line.strip() and not line.startswith("#")]
    return out


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if p.returncode != 0:
        sys.stderr.write(" ".join(cmd) + " failed:\n" + p.stderr)
        sys.exit(1)
    return p.stdout


# the rendered scene's landmarks (cylinders of both classes), diameter and height, m
HARD_LANDMARK_SIZE = "0.10,0.30"


def class_args(classes):
    """--class NAME=LABEL for each (name, label)."""
    out = []
    for c, label in classes:
        out += ["--class", f"{c}={label}"]
    return out


def score(build, table, config, classes, test_list, calib=None, boxes=None):
    """cyl-score on the images of test_list: (its text lines, the JSON of its last line)."""
    out = run([os.path.join(build, "cyl-score"), "-q", "--table", table, "--config", config]
              + (["--calib", calib] if calib else []) + (["--boxes", boxes] if boxes else [])
              + class_args(classes) + [test_list])
    lines = out.strip().splitlines()
    return lines[:-1], json.loads(lines[-1])


def pooled_recall(classes, key="recall_iou50"):
    """One recall over the boxes of several classes of a cyl-score result."""
    boxes = sum(c["boxes"] for c in classes.values())
    return sum(c[key] * c["boxes"] for c in classes.values()) / max(boxes, 1)


def learn_and_score(build, out, name, train, test, classes, learn_extra=(), calib=None):
    table = os.path.join(out, name + ".cylt")
    config = os.path.join(out, name + "-detector.yaml")
    report = os.path.join(out, name + "-training.json")
    tl, sl = os.path.join(out, name + "-train.list"), os.path.join(out, name + "-test.list")
    with open(tl, "w") as f:
        f.write("\n".join(train) + "\n")
    with open(sl, "w") as f:
        f.write("\n".join(test) + "\n")
    run([os.path.join(build, "cyl-train"), "learn", "-q", "-o", table, "--report", report, "--config-out", config]
        + class_args(classes) + list(learn_extra) + [tl])
    with open(report) as f:
        rep = json.load(f)
    print(f"== {name}: learned on {len(train)} images, tested on {len(test)}")
    for c in rep["classes"]:
        print(f"   training report {c['name']}: recall {100 * c['recall']:.1f}% of labelled px, background claimed "
              f"{100 * c['background_claimed']:.3f}%, largest frame share {100 * c['max_frame_share']:.2f}%")
        wa = c.get("weak_alone")
        if wa:
            print(f"   weak blobs alone {'on from ' + str(wa['min_area_px']) + ' px' if wa['min_area_px'] else 'off'} "
                  f"(training images: boxes found {wa['train_boxes_found_off']} -> {wa['train_boxes_found_on']}, "
                  f"false blobs {wa['train_fp_per_image_off']:.2f} -> {wa['train_fp_per_image_on']:.2f} per image)")
        for w in c["warnings"]:
            print(f"   warning: {w}")
    text, res = score(build, table, config, classes, sl, calib, os.path.join(out, name + "-boxes.csv"))
    print("   " + "\n   ".join(text))
    return res


def bearing_errors(obslog):
    """|observed - true| bearing of each observation, against the true landmark of its class
    nearest in bearing (from the frame's true pose), for observations within 0.2 rad of one."""
    lms, obs, errs = [], {}, []
    poses = {}
    with open(obslog) as f:
        for line in f:
            r = json.loads(line)
            if r["type"] == "truth_landmark":
                lms.append(r)
            elif r["type"] == "truth_pose":
                poses[r["seq"]] = r
            elif r["type"] == "obs" and not (r["flags"] & 0x320):
                obs.setdefault(r["seq"], []).append(r)
    for seq, ol in obs.items():
        p = poses.get(seq)
        if p is None:
            continue
        for o in ol:
            # the camera's bearing is from the robot centre, as the observation's
            best = None
            for lm in lms:
                if lm["class_id"] != o["class_id"]:
                    continue
                dx, dy = lm["x_m"] - p["x_m"], lm["y_m"] - p["y_m"]
                b = math.atan2(dy, dx) - p["theta_rad"]
                d = abs(math.atan2(math.sin(o["bearing_rad"] - b), math.cos(o["bearing_rad"] - b)))
                if best is None or d < best:
                    best = d
            if best is not None and best < 0.2:
                errs.append(best)
    return errs


def hard_synth(build, out, frames, seed=3, extra=()):
    d = os.path.join(out, "hard")
    os.makedirs(d, exist_ok=True)
    raw = os.path.join(d, "drive.cylraw")
    run([os.path.join(build, "cyl-render"), "-S", "hard", "-n", str(frames), "-s", str(seed), "-q", "-o", raw,
         "--labels", d])
    imgs = sorted(os.path.join(d, "images", f) for f in os.listdir(os.path.join(d, "images")))
    classes = [("orange", 0), ("green", 1)]
    cam = os.path.join(d, "camera.yaml")
    run([os.path.join(build, "cyl-render"), "-S", "hard", "--write-camera", cam])
    # the landmarks' size goes into the detector config (the expected-size gate at the measured
    # range), and the scene's camera lets cyl-score score the detector's observations
    table, config = os.path.join(out, "hard.cylt"), os.path.join(out, "hard-detector.yaml")
    sc = learn_and_score(build, out, "hard", imgs[:1], imgs[1:], classes,
                         [a for c, _ in classes for a in ("--size", f"{c}={HARD_LANDMARK_SIZE}")] + list(extra), cam)["classes"]
    # the same without the camera: the blobs the camera-free gates keep, as on the real sets
    nc = score(build, table, config, classes, os.path.join(out, "hard-test.list"))[1]["classes"]
    log = os.path.join(d, "obs.jsonl")
    # the config carries the landmarks' size
    run([os.path.join(build, "cyl"), "detect", raw, "--table", table, "--calib", cam, "--config", config,
         "--quiet", "--out", log])
    errs = sorted(bearing_errors(log))
    res = {
        "hard_synth_frames": frames - 1,
        "hard_synth_recall": pooled_recall(sc),
        "hard_synth_recall_centroid": pooled_recall(sc, "recall_centroid"),
        "hard_synth_fp_per_frame": sum(c["fp_per_image"] for c in sc.values()),
        "hard_synth_recall_no_camera": pooled_recall(nc),
        "hard_synth_fp_per_frame_no_camera": sum(c["fp_per_image"] for c in nc.values()),
        "hard_synth_bearing_err_median_deg": math.degrees(errs[len(errs) // 2]) if errs else None,
        "hard_synth_bearing_err_p95_deg": math.degrees(errs[int(0.95 * (len(errs) - 1))]) if errs else None,
        "hard_synth_observations_matched": len(errs),
    }
    print(f"   without the camera (no size gate): recall {res['hard_synth_recall_no_camera']:.3f}, "
          f"false blobs per frame {res['hard_synth_fp_per_frame_no_camera']:.2f}")
    print(f"   bearing error of {len(errs)} matched observations: median {res['hard_synth_bearing_err_median_deg']} deg, "
          f"95% {res['hard_synth_bearing_err_p95_deg']} deg")
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default=os.environ.get("CYL_SHARED", "../shared"))
    ap.add_argument("--build", default="build")
    ap.add_argument("--out", default=None, help="keep tables, reports and per-box CSVs here")
    ap.add_argument("--subset", default=None)
    ap.add_argument("--train-option", action="append", default=[], metavar="'OPT VALUE'",
                    help="pass an option to every cyl-train learn (repeatable; e.g. '--split-axes both'): "
                         "how an option that is not a default was measured")
    ap.add_argument("--hard-frames", type=int, default=None,
                    help="frames of the hard rendered scene (default 150; 40 with --subset)")
    a = ap.parse_args()
    if a.subset:
        sets = subset_splits(a.subset)
    else:
        real = os.path.join(a.shared, "data", "real")
        if not os.path.isdir(real):
            sys.stderr.write(f"realeval: {real} not found: the real image sets are outside the repository; pass "
                             "--shared DIR (the folder holding data/real) or run the committed subset with --subset\n")
            return 1
        sets = splits(a.shared)
    tmp = None
    out = os.path.abspath(a.out) if a.out else None   # list files name images relative to their folder
    if out is None:
        tmp = tempfile.TemporaryDirectory()
        out = tmp.name
    os.makedirs(out, exist_ok=True)
    extra = [w for opt in a.train_option for w in opt.split()]
    ball = learn_and_score(a.build, out, "ball", sets["ball"]["train"], sets["ball"]["test"], [("ball", 0)], extra)
    frc = learn_and_score(a.build, out, "frc", sets["frc"]["train"], sets["frc"]["test"], [("cone", 0), ("cube", 1)], extra)
    hard = hard_synth(a.build, out, a.hard_frames or (40 if a.subset else 150), extra=extra)
    b, co, cu = ball["classes"]["ball"], frc["classes"]["cone"], frc["classes"]["cube"]
    res = {
        "data": "subset" if a.subset else "full", "train_options": extra,
        "ball_recall_iou50": b["recall_iou50"], "ball_recall_iou50_min12px": b["recall_iou50_min12px"],
        "ball_recall_centroid": b["recall_centroid"], "ball_recall_centroid_min12px": b["recall_centroid_min12px"],
        "cone_recall_iou50": co["recall_iou50"], "cone_recall_centroid": co["recall_centroid"],
        "cube_recall_iou50": cu["recall_iou50"], "cube_recall_centroid": cu["recall_centroid"],
        "fp_per_image": {"ball": b["fp_per_image"], "cone": co["fp_per_image"], "cube": cu["fp_per_image"]},
        "fp_per_image_max": max(b["fp_per_image"], co["fp_per_image"], cu["fp_per_image"]),
        "flooded_frames": {"ball": b["flooded_frames"], "cone": co["flooded_frames"], "cube": cu["flooded_frames"]},
        "segment_us_per_mpx": {"ball": round(ball["median_us_per_mpx"], 1), "frc": round(frc["median_us_per_mpx"], 1)},
        **hard,
    }
    print(json.dumps(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
