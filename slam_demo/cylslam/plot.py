# SPDX-License-Identifier: BSD-3-Clause
"""PNG plots: the estimate against ground truth with 95 % ellipses; a noise model's correlation in
time against the lag bins it was fitted to."""
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


MAGNIFICATIONS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)


def ellipse_magnification(covs, extent_m, target=0.015):
    """The factor the 95 % ellipses are drawn at so that they can be seen: the smallest of
    MAGNIFICATIONS that makes the median ellipse's semi-major axis at least `target` of the
    plot's extent (1 when they are large enough already). The legend states it."""
    covs = [np.asarray(c, float)[:2, :2] for c in covs if c is not None]
    if not covs or not extent_m > 0:
        return 1
    semi = np.median([math.sqrt(max(np.linalg.eigvalsh(c)[-1], 0.0) * CHI2_2_95) for c in covs])
    for m in MAGNIFICATIONS:
        if m * semi >= target * extent_m:
            return m
    return MAGNIFICATIONS[-1]


def _times(m):
    return ", true size" if m == 1 else f", drawn x{m}"


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

    fig, ax = plt.subplots(figsize=(11.5, 8))
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
    pts = [poses[:, :2], lms]
    if tr is not None and len(tr):
        pts.append(np.asarray(tr)[:, :2])
    allp = np.concatenate([p for p in pts if len(p)])
    extent = float(np.max(np.ptp(allp, axis=0))) if len(allp) > 1 else 1.0
    if res.pose_cov is not None:
        step = max(1, len(res.poses) // 40)
        idx = list(range(0, len(res.poses), step))
        mp = ellipse_magnification([res.pose_cov[i] for i in idx], extent)
        for k, i in enumerate(idx):
            c = res.pose_cov[i][:2, :2]
            th = res.poses[i, 2]
            R = R0 @ np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
            e = ellipse_points(poses[i], (mp * mp) * (R @ c @ R.T))
            ax.plot(e[:, 0], e[:, 1], color="tab:blue", lw=0.5, alpha=0.6, zorder=3,
                    label=f"pose 95% ellipses{_times(mp)}" if k == 0 else None)
    if ds.truth_landmarks:
        t = np.array([v[:2] for v in ds.truth_landmarks.values()])
        ax.scatter(t[:, 0], t[:, 1], marker="x", color="k", s=50, label="true landmarks", zorder=4)
    classes = sorted(set(res.lm_class))
    ml = ellipse_magnification(res.lm_cov if res.lm_cov is not None else [], extent)
    colours = {"orange": "tab:orange", "green": "tab:green", "barcode": "tab:purple",
               "tree": "tab:green"}
    cyc = ["tab:purple", "tab:cyan", "tab:olive", "tab:pink", "tab:brown"]
    for ci, c in enumerate(classes):
        col = colours.get(c, cyc[ci % len(cyc)])
        js = [j for j, k in enumerate(res.lm_class) if k == c]
        if not js:
            continue
        p = lms[js]
        ell = f" + 95% ellipses{_times(ml)}" if res.lm_cov is not None else ""
        ax.scatter(p[:, 0], p[:, 1], s=14, color=col, label=f"landmarks ({c}){ell}", zorder=5)
        if res.lm_cov is not None:
            for j in js:
                e = ellipse_points(lms[j], (ml * ml) * (R0 @ res.lm_cov[j] @ R0.T))
                ax.plot(e[:, 0], e[:, 1], color=col, lw=0.9, zorder=5)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    # the legend beside the axes, never over the data
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, fontsize=7)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)


def correlation_plot(model):
    """PNG bytes: the noise model's correlation in time (provenance's lag bins, the empirical
    correlation of the whitened errors) against the fitted curves, one panel per stream: range and
    bearing (two exponentials), odometry x, y, theta (two exponentials, the batch's states; one, the
    online inflation)."""
    import io

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .noise_model import NoiseModel
    pv = model.provenance
    lags = np.asarray(pv.get("correlation_lags_s") or [], float)
    odom = (model.odom_corr, model.odom_corr_inflation)
    panels = [("range", "range", "correlation_range", (model.corr, None)),
              ("bearing", "bearing", "correlation_bearing", (model.corr, None)),
              ("odometry x", "x", "odometry_correlation_x", odom),
              ("odometry y", "y", "odometry_correlation_y", odom),
              ("odometry theta", "theta", "odometry_correlation_theta", odom)]
    fig, axes = plt.subplots(1, 5, figsize=(17, 3.4), sharex=True)
    t = np.geomspace(max(lags.min(), 0.05) if len(lags) else 0.1, max(lags.max(), 1.0) * 1.5 if len(lags) else 200, 200)
    for ax, (title, comp, key, (fit, one)) in zip(axes, panels):
        emp = np.array([np.nan if v is None else v for v in pv.get(key, [])], float)
        if len(emp) == len(lags) and len(lags):
            ax.plot(lags, emp, "o", ms=4, color="k", label="measured (lag bins)")
        if fit is not None:
            ax.plot(t, NoiseModel.correlation_at(fit[comp], t), "-", color="tab:blue",
                    label="two exponentials" + (" (states)" if one is not None else ""))
        if one is not None:
            ax.plot(t, NoiseModel.correlation_at(one[comp], t), "--", color="tab:orange",
                    label="one exponential (online inflation)")
        ax.set_xscale("log")
        ax.axhline(0.0, color="0.7", lw=0.8)
        ax.set_title(title)
        ax.set_xlabel("lag s")
    axes[0].set_ylabel("correlation of whitened errors")
    axes[2].legend(loc="upper right", fontsize=8)
    fig.suptitle(f"noise model correlation in time ({pv.get('source', 'unknown source')})", fontsize=10)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    return buf.getvalue()
