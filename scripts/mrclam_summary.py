#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""The last line of `make mrclam`: one JSON object from the summaries of its runs (each written by
`cylslam mrclam --summary-out`): known association with the fixed noise model and its one-map run,
unknown association, known association with the learned noise model and its one-map run; with the
parameters of each run and where they came from.

usage: mrclam_summary.py OUT_DIR   (reads OUT_DIR/mrclam-{known,unknown,known-learned}.json)
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
    for name in ("known", "unknown", "known-learned"):
        path = os.path.join(out, f"mrclam-{name}.json")
        try:
            with open(path) as fh:
                runs[name] = json.loads(fh.read().strip().splitlines()[-1])
        except (OSError, ValueError, IndexError) as e:
            print(f"mrclam_summary: {path}: {e}", file=sys.stderr)
            return 3
    k, u, kl = runs["known"], runs["unknown"], runs["known-learned"]
    summary = {
        "known_aligned_rmse_max_m": k["aligned_rmse_max_m"],
        "known_landmark_anees_max": k["anees_landmarks_max"],
        "unknown_aligned_rmse_max_m": u["aligned_rmse_max_m"],
        "unknown_landmarks_min": u["landmarks_min"],
        "unknown_landmarks_max": u["landmarks_max"],
        "multi_aligned_rmse_max_m": k.get("multi_aligned_rmse_max_m"),
        "multi_landmark_rmse_m": k.get("multi_landmark_rmse_m"),
        "learned_known_aligned_rmse_max_m": kl["aligned_rmse_max_m"],
        "learned_known_landmark_anees_max": kl["anees_landmarks_max"],
        "learned_multi_aligned_rmse_max_m": kl.get("multi_aligned_rmse_max_m"),
        "learned_multi_landmark_rmse_m": kl.get("multi_landmark_rmse_m"),
        "learned_multi_landmark_anees": kl.get("multi_anees_landmarks"),
        "parameters": {
            "known": {**k["parameters"], "source": "the reader's fixed models (cylslam/mrclam.py), Huber 1.345"},
            "unknown": {**u["parameters"], "source": "odometry sigmas x4 chosen on Dataset 7 itself (slam_demo/README.md)"},
            "known-learned": {**kl["parameters"],
                              "source": "learned from Dataset 7's truth by `cylslam mrclam-noise` "
                                        "(cylslam/noise_model.py)"},
        },
    }
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
