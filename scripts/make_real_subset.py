#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Copy the small real-image subset that make test runs (tests/fixtures/real) from the full sets.

Deterministic: RoboCup ball, every 4th training image (2019-2023, name order) and every 20th test
image (2024 on); FRC cones and cubes, the 10 training images of the full benchmark and every 4th
image of test/. Images and labels are copied byte for byte with the sets' licence and attribution
files. Usage: scripts/make_real_subset.py [--shared DIR] [--out DIR]
"""
import argparse
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import realeval  # noqa: E402


def label_of(img):
    d, f = os.path.split(img)
    return os.path.join(os.path.dirname(d), "labels", os.path.splitext(f)[0] + ".txt")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--shared", default=os.environ.get("CYL_SHARED", "../shared"))
    ap.add_argument("--out", default="tests/fixtures/real")
    a = ap.parse_args()
    sets = realeval.splits(a.shared)
    pick = {
        "ball": {"train": sets["ball"]["train"][::4], "test": sets["ball"]["test"][::20]},
        "frc": {"train": sets["frc"]["train"], "test": sets["frc"]["test"][::4]},
    }
    real = os.path.join(a.shared, "data", "real")
    src_dirs = {"ball": os.path.join(real, "robocup_msl_ball"), "frc": os.path.join(real, "frc_cones_cubes")}
    notices = {"ball": ["LICENSE", "SOURCE.txt", "README.upstream.md", "obj.names"],
               "frc": ["SOURCE.txt", "README.dataset.txt", "README.roboflow.txt", "data.yaml"]}
    for s, parts in pick.items():
        out = os.path.join(a.out, s)
        if os.path.isdir(out):
            shutil.rmtree(out)
        os.makedirs(os.path.join(out, "images"))
        os.makedirs(os.path.join(out, "labels"))
        for n in notices[s]:
            shutil.copyfile(os.path.join(src_dirs[s], n), os.path.join(out, n))
        for part, imgs in parts.items():
            names = []
            for img in imgs:
                base = os.path.basename(img)
                shutil.copyfile(img, os.path.join(out, "images", base))
                shutil.copyfile(label_of(img), os.path.join(out, "labels", os.path.splitext(base)[0] + ".txt"))
                names.append("images/" + base)
            with open(os.path.join(out, part + ".list"), "w") as f:
                f.write("# written by scripts/make_real_subset.py\n" + "\n".join(names) + "\n")
        print(f"{s}: {len(parts['train'])} train, {len(parts['test'])} test images -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
