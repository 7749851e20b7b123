#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The last line of `make mrclam`: one JSON object from the summaries of its runs (each written by
`cylslam mrclam --summary-out`): with the learned noise model, known association with its one-map
run and unknown association (the same parameters in every mode); with the reader's fixed model,
known association with its one-map run (fixed_*). Each run's parameters are listed with their
source.

usage: mrclam_summary.py OUT_DIR   (reads OUT_DIR/mrclam-{known,unknown,fixed-known}.json)
"""
import json
import os
import sys


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if len(argv) == 2 else 2
    out = argv[1]
    runs = {}
    for name in ("known", "unknown", "fixed-known"):
        path = os.path.join(out, f"mrclam-{name}.json")
        try:
            with open(path) as fh:
                runs[name] = json.loads(fh.read().strip().splitlines()[-1])
        except (OSError, ValueError, IndexError) as e:
            print(f"mrclam_summary: {path}: {e}", file=sys.stderr)
            return 3
    try:
        summary = combine(runs)
    except (KeyError, TypeError) as e:
        print(f"mrclam_summary: {out}: a run's summary lacks {e} (written by another cylslam version?)",
              file=sys.stderr)
        return 3
    print(json.dumps(summary))
    return 0


def combine(runs):
    k, u, f = runs["known"], runs["unknown"], runs["fixed-known"]
    learned = "learned from the data set's truth by `cylslam mrclam-noise` (cylslam/noise_model.py)"
    summary = {
        "known_aligned_rmse_max_m": k["aligned_rmse_max_m"],
        "known_landmark_anees_max": k["anees_landmarks_max"],
        "unknown_aligned_rmse_max_m": u["aligned_rmse_max_m"],
        "unknown_landmarks_min": u["landmarks_min"],
        "unknown_landmarks_max": u["landmarks_max"],
        "multi_aligned_rmse_max_m": k["multi_aligned_rmse_max_m"],
        "multi_landmark_rmse_m": k["multi_landmark_rmse_m"],
        "multi_landmark_anees": k["multi_anees_landmarks"],
        "fixed_known_aligned_rmse_max_m": f["aligned_rmse_max_m"],
        "fixed_known_landmark_anees_max": f["anees_landmarks_max"],
        "fixed_multi_aligned_rmse_max_m": f["multi_aligned_rmse_max_m"],
        "fixed_multi_landmark_rmse_m": f["multi_landmark_rmse_m"],
        "parameters": {
            "known": {**k["parameters"], "source": learned},
            "unknown": {**u["parameters"], "source": learned + "; gates are chi-square probabilities; "
                        "exclusion, reassoc (a cap: passes stop when no pairing changes) and starts chosen on "
                        "Dataset 7 robots 1, 3, 5 (slam_demo/README.md)"},
            "fixed-known": {**f["parameters"], "source": "the reader's fixed models (cylslam/mrclam.py), Huber 1.345"},
        },
    }
    return summary


if __name__ == "__main__":
    sys.exit(main(sys.argv))
