# SPDX-License-Identifier: BSD-3-Clause
"""Reader of gtsam's Victoria Park file (`gtsam.findExampleDataFile('victoria_park.txt')`, shipped
in the gtsam wheel as gtsam/Data/victoria_park.txt).

The file is parsed by gtsam.load2D itself (so its conventions are gtsam's): ODOMETRY lines become
BetweenFactorPose2 (increment + covariance), LANDMARK lines become BearingRangeFactor2D with the
noise model gtsam gives them. We convert the odometry chain to steps and the landmark factors to
(range, bearing) observations with their covariance permuted back to (range, bearing) order and
the landmark number as a known identity. There is no ground truth.
"""
from __future__ import annotations

import numpy as np

import gtsam

from .data import Dataset, Obs, Step

PERM = np.array([[0.0, 1.0], [1.0, 0.0]])


def default_path():
    return gtsam.findExampleDataFile("victoria_park.txt")


def read_victoria(path=None, max_poses=None) -> Dataset:
    path = path or default_path()
    graph, _ = gtsam.load2D(path)
    odo = {}
    obs = {}
    n_lm_factors = 0
    for k in range(graph.size()):
        f = graph.at(k)
        name = type(f).__name__
        if name == "BetweenFactorPose2":
            i, j = f.keys()
            if i in odo:
                raise ValueError(f"{path}: two odometry edges leave pose {i}")
            m = f.measured()
            odo[i] = (j, np.array([m.x(), m.y(), m.theta()]), f.noiseModel().covariance())
        elif name == "BearingRangeFactor2D":
            pk, lk = f.keys()
            br = f.measured()
            cov_br = f.noiseModel().covariance()
            cov_rb = PERM @ cov_br @ PERM
            sym = gtsam.Symbol(lk)
            obs.setdefault(pk, []).append(
                Obs(cls="tree", range_m=float(br.range()), bearing_rad=float(br.bearing().theta()),
                    cov=cov_rb, lm_id=int(sym.index()), where=f"{path}: factor {k}"))
            n_lm_factors += 1
    # pose numbers skip the numbers used by landmarks: follow the chain from the first pose
    targets = {v[0] for v in odo.values()}
    starts = [i for i in odo if i not in targets]
    if len(starts) != 1:
        raise ValueError(f"{path}: odometry is not a single chain ({len(starts)} starts)")
    cur = starts[0]
    steps = [Step(t=0.0, seq=cur, obs=obs.get(cur, []))]
    while cur in odo and (not max_poses or len(steps) < max_poses):
        nxt, d, c = odo[cur]
        steps.append(Step(t=float(len(steps)), seq=nxt, odom=d, odom_cov=c, obs=obs.get(nxt, [])))
        cur = nxt
    n = len(steps)
    ds = Dataset(name="Victoria Park (gtsam)", steps=steps, classes=["tree"], known_ids=True,
                 notes=[f"{path}: {len(odo) + 1} poses, {n_lm_factors} landmark observations"
                        + (f"; first {n} poses used" if max_poses else "")])
    return ds
