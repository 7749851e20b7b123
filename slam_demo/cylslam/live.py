# SPDX-License-Identifier: BSD-3-Clause
"""A live view of the SLAM run with rerun (`rerun-sdk`): as the run goes, the robot, its
trajectory, each frame's observations (a ray from the robot to where the observation puts the
landmark) and the landmark map with 95 % ellipses; at the end the final (batch) trajectory and map
with their ellipses and the ground truth. With `images` (the folder `cyl detect --overlay DIR`
wrote: frame_<seq>.png), each frame's overlay (classified pixels, boxes, ranges, ellipses) beside it.

Headless it saves a recording (`.rrd`) that the rerun viewer opens later; `spawn` opens the viewer.

Entities: camera/overlay, world/robot, world/trajectory, world/observations, world/landmarks,
world/landmark_ellipses, final/trajectory, final/landmarks, final/landmark_ellipses,
final/pose_ellipses, truth/trajectory, truth/landmarks. Timelines: step (sequence) and time (s).
"""
from __future__ import annotations

import math
import os

import numpy as np

from .plot import ellipse_points

ENTITIES = ("camera/overlay", "world/robot", "world/trajectory", "world/observations", "world/landmarks",
            "world/landmark_ellipses", "final/trajectory", "final/landmarks", "final/landmark_ellipses",
            "final/pose_ellipses", "truth/trajectory", "truth/landmarks")


class LiveView:
    def __init__(self, save_path=None, spawn=False, images=None, landmark_every=10, name="cylslam"):
        try:
            import rerun as rr
        except ImportError:
            raise SystemExit("cylslam: the live view needs rerun-sdk (pip install rerun-sdk)") from None
        self.rr = rr
        self.rec = rr.RecordingStream(name)
        if save_path:
            self.rec.save(save_path)
        if spawn:
            self.rec.spawn(connect=not save_path)
        self.images = images
        self.every = max(1, int(landmark_every))
        self.traj = []

    def _time(self, i, t):
        self.rec.set_time("step", sequence=int(i))
        self.rec.set_time("time", duration=float(t))

    def step(self, i, seq, t, pose, used, isam, lms_init):
        rr = self.rr
        self._time(i, t)
        x, y, th = (float(v) for v in pose)
        self.traj.append((x, y))
        self.rec.log("world/robot", rr.Arrows2D(origins=[[x, y]], vectors=[[0.3 * math.cos(th), 0.3 * math.sin(th)]],
                                               colors=[[40, 90, 220]]))
        self.rec.log("world/trajectory", rr.LineStrips2D([self.traj], colors=[[40, 90, 220]]))
        rays = []
        for o, _j in used:
            a = th + o.bearing_rad
            rays.append([[x, y], [x + o.range_m * math.cos(a), y + o.range_m * math.sin(a)]])
        self.rec.log("world/observations", rr.LineStrips2D(rays, colors=[[230, 120, 20]]) if rays else rr.Clear(recursive=False))
        if self.images:
            p = os.path.join(self.images, f"frame_{int(seq):06d}.png")
            if os.path.exists(p):
                self.rec.log("camera/overlay", rr.EncodedImage(path=p))
        if lms_init and (i % self.every == 0 or used):
            from .backend import L     # the back end's landmark keys, not a second definition
            pts, ells = [], []
            for j in range(len(lms_init)):
                try:
                    pt = isam.calculateEstimatePoint2(L(j))
                except (RuntimeError, IndexError):
                    continue              # not yet in the solver (added at its next update)
                pts.append([float(pt[0]), float(pt[1])])
                if i % self.every == 0:
                    try:
                        c = isam.marginalCovariance(L(j))
                        ells.append(ellipse_points(pts[-1], c).tolist())
                    except (RuntimeError, IndexError):
                        pass
            if pts:
                self.rec.log("world/landmarks", rr.Points2D(pts, radii=0.05, colors=[[230, 120, 20]]))
            if ells:
                self.rec.log("world/landmark_ellipses", rr.LineStrips2D(ells, colors=[[230, 120, 20]]))

    def final(self, ds, res):
        rr = self.rr
        n = len(res.poses)
        self._time(n - 1, ds.steps[-1].t if ds.steps else 0.0)
        self.rec.log("final/trajectory", rr.LineStrips2D([res.poses[:, :2].tolist()], colors=[[20, 60, 160]]))
        if len(res.lms):
            self.rec.log("final/landmarks", rr.Points2D(np.asarray(res.lms)[:, :2].tolist(), radii=0.06,
                                                        labels=[str(c) for c in res.lm_class]))
            if res.lm_cov is not None:
                self.rec.log("final/landmark_ellipses", rr.LineStrips2D(
                    [ellipse_points(res.lms[j], res.lm_cov[j]).tolist() for j in range(len(res.lms))]))
        if res.pose_cov is not None:
            step = max(1, n // 40)
            ells = []
            for i in range(0, n, step):
                th = res.poses[i, 2]
                R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
                ells.append(ellipse_points(res.poses[i], R @ res.pose_cov[i][:2, :2] @ R.T).tolist())
            self.rec.log("final/pose_ellipses", rr.LineStrips2D(ells, colors=[[20, 60, 160]]))
        tr = [s.truth[:2] for s in ds.steps if s.truth is not None]
        if tr:
            self.rec.log("truth/trajectory", rr.LineStrips2D([np.asarray(tr, float).tolist()], colors=[[128, 128, 128]]))
        if ds.truth_landmarks:
            self.rec.log("truth/landmarks", rr.Points2D([list(v[:2]) for v in ds.truth_landmarks.values()],
                                                        colors=[[0, 0, 0]], radii=0.04))
        self.rec.flush()

    def close(self):
        self.rec.flush()
        self.rec.disconnect()
