# SPDX-License-Identifier: BSD-3-Clause
"""PNG plot of the estimate against ground truth with 95 % ellipses."""
from __future__ import annotations

import math

import numpy as np

CHI2_2_95 = 5.991464547107979   # chi-square 2 dof, 95 %


def ellipse_points(mean, cov, k2=CHI2_2_95, n=48):
    w, V = np.linalg.eigh(np.asarray(cov, float))
    w = np.sqrt(np.maximum(w, 0.0) * k2)
    a = np.linspace(0, 2 * math.pi, n)
    pts = V @ np.stack([w[0] * np.cos(a), w[1] * np.sin(a)])
    return pts.T + np.asarray(mean, float)[:2]


def _apply(R, t, poses):
    out = np.array(poses, float).copy()
    out[:, :2] = out[:, :2] @ R.T + t
    out[:, 2] = out[:, 2] + math.atan2(R[1, 0], R[0, 0])
    return out


def plot(path, ds, res, title, res_fixed=None, dead_reckoning=None, match=None, align=None,
         align_fixed=None):
    """align = (R, t): draw the estimate (poses, landmarks, ellipses) SE(2)-aligned onto the
    truth, as the aligned metrics see it; the unaligned trajectory is drawn faintly too."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 8))
    tr = [s.truth for s in ds.steps if s.truth is not None]
    if tr:
        tr = np.array(tr)
        ax.plot(tr[:, 0], tr[:, 1], color="0.55", lw=2.2, label="truth", zorder=1)
    if dead_reckoning is not None:
        ax.plot(dead_reckoning[:, 0], dead_reckoning[:, 1], color="tab:red", lw=0.7, alpha=0.6,
                label="dead reckoning", zorder=1)
    R0, t0 = (np.eye(2), np.zeros(2)) if align is None else align
    poses = _apply(R0, t0, res.poses)
    lms = np.asarray(res.lms, float).reshape(-1, 2) @ R0.T + t0
    tag = ", SE(2)-aligned" if align is not None else ""
    if align is not None:
        ax.plot(res.poses[:, 0], res.poses[:, 1], color="tab:blue", lw=0.6, alpha=0.35,
                label="estimate, unaligned", zorder=2)
    if res_fixed is not None:
        fp = res_fixed.poses if align_fixed is None else _apply(*align_fixed, res_fixed.poses)
        ax.plot(fp[:, 0], fp[:, 1], color="tab:orange", lw=0.9, ls="--",
                label="fixed covariance" + tag, zorder=2)
    ax.plot(poses[:, 0], poses[:, 1], color="tab:blue", lw=1.0,
            label="estimate (per-observation cov.)" + tag, zorder=3)
    if res.pose_cov is not None:
        step = max(1, len(res.poses) // 40)
        for i in range(0, len(res.poses), step):
            c = res.pose_cov[i][:2, :2]
            th = poses[i, 2]
            R = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
            e = ellipse_points(poses[i], R @ c @ R.T)
            ax.plot(e[:, 0], e[:, 1], color="tab:blue", lw=0.5, alpha=0.6, zorder=3)
    if ds.truth_landmarks:
        t = np.array([v[:2] for v in ds.truth_landmarks.values()])
        ax.scatter(t[:, 0], t[:, 1], marker="x", color="k", s=50, label="true landmarks", zorder=4)
    classes = sorted(set(res.lm_class))
    colours = {"orange": "tab:orange", "green": "tab:green", "barcode": "tab:purple",
               "tree": "tab:green"}
    cyc = ["tab:purple", "tab:cyan", "tab:olive", "tab:pink", "tab:brown"]
    for ci, c in enumerate(classes):
        col = colours.get(c, cyc[ci % len(cyc)])
        js = [j for j, k in enumerate(res.lm_class) if k == c]
        if not js:
            continue
        p = lms[js]
        ax.scatter(p[:, 0], p[:, 1], s=14, color=col, label=f"landmarks ({c}) + 95% ellipses",
                   zorder=5)
        if res.lm_cov is not None:
            for j in js:
                e = ellipse_points(lms[j], R0 @ res.lm_cov[j] @ R0.T)
                ax.plot(e[:, 0], e[:, 1], color=col, lw=0.9, zorder=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="best", fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
