# SPDX-License-Identifier: BSD-3-Clause
"""Command line: python -m cylslam {run,synth,mrclam,victoria,excerpt} --help

Exit codes: 0 success; 1 an acceptance check asked for with --check failed; 2 usage error;
3 input error (missing file, malformed log: the message names file and line); 4 the outputs
cannot be written (the message names the path).
The last line printed on stdout by run / mrclam / victoria is one JSON object.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import sys
import time

import numpy as np

EXIT_OK, EXIT_CHECK, EXIT_USAGE, EXIT_INPUT, EXIT_OUTPUT = 0, 1, 2, 3, 4
FIXED_GRID = (0.25, 0.5, 1.0, 2.0, 4.0)


class Progress:
    """A one-line progress bar on stderr (only when enabled: default when stderr is a tty)."""

    def __init__(self, label, enabled):
        self.label = label
        self.enabled = enabled
        self.last = 0.0

    def __call__(self, i, n):
        if not self.enabled:
            return
        now = time.monotonic()
        if i != n and now - self.last < 0.1:
            return
        self.last = now
        w = 30
        k = int(w * i / max(n, 1))
        sys.stderr.write(f"\r{self.label} [{'#' * k}{'.' * (w - k)}] {i}/{n}")
        if i == n:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _scales(text):
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: comma-separated numbers expected")
    if not v or any(not (x > 0 and math.isfinite(x)) for x in v):
        raise argparse.ArgumentTypeError(f"{text!r}: every scale must be a finite number > 0")
    return v


def _pair(text):
    """'a,b' -> (a, b) floats (a command-line value of two numbers)."""
    try:
        a, b = (float(x) for x in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers 'a,b', got '{text}'")
    return (a, b)


def _reassoc_conflict(args):
    """The run's parameters break a constraint of Params.check: the message, True."""
    try:
        _params(args).check()
    except ValueError as e:
        print(f"cylslam: error: {e}", file=sys.stderr)
        return True
    return False


def _params(args, **over):
    from .backend import Params
    p = Params(assoc=args.assoc, conf_min=args.conf_min, gate_p=args.gate, new_p=args.new_gate,
               cand_radius=args.cand_radius, init_max_sigma=args.init_max_sigma, robust=args.robust, huber_k=args.huber_k,
               merged_var_scale=getattr(args, "merged_var_scale", 1.0),
               anchor=args.anchor, batch=not args.no_batch, reject_flags=int(args.reject_flags, 0),
               exclusion=getattr(args, "exclusion", False), joint=getattr(args, "assoc_method", "") == "jcbb",
               merge_every=getattr(args, "merge_every", 0), init_views=getattr(args, "init_views", 1),
               reassoc=getattr(args, "reassoc", 0), starts=tuple(getattr(args, "starts", None) or (1.0,)),
               calib_states=getattr(args, "calib_states", False),
               lm_bias=getattr(args, "lm_bias", "auto"),
               bias_gm_sigma_px=tuple(getattr(args, "bias_gm", None) or Params.bias_gm_sigma_px),
               bias_gm_tau_s=tuple(getattr(args, "bias_gm_tau", None) or Params.bias_gm_tau_s),
               white_scale=tuple(getattr(args, "white_scale", None) or Params.white_scale),
               bias_gm_cauchy_k=getattr(args, "bias_gm_cauchy", Params.bias_gm_cauchy_k),
               calib_model=getattr(args, "calib_model", "linear"),
               far_bearing=getattr(args, "far_bearing", False),
               far_bearing_var_scale=getattr(args, "far_bearing_scale", Params.far_bearing_var_scale),
               far_bearing_every_s=getattr(args, "far_bearing_every", Params.far_bearing_every_s),
               far_robust=getattr(args, "far_robust", Params.far_robust),
               far_init=(getattr(args, "far_init_default", False) and getattr(args, "far_bearing", False)
                         if getattr(args, "far_init", None) is None else args.far_init),
               far_init_parallax_deg=getattr(args, "far_init_parallax", Params.far_init_parallax_deg),
               far_init_views=getattr(args, "far_init_views", Params.far_init_views),
               far_init_window=getattr(args, "far_init_window", Params.far_init_window),
               far_init_range_scale=getattr(args, "far_init_range_scale", Params.far_init_range_scale),
               far_init_clear_m=getattr(args, "far_init_clear", Params.far_init_clear_m),
               max_range_rel_sigma=(None if getattr(args, "max_range_rel_sigma", None) in (None, 0)
                                    else args.max_range_rel_sigma))
    for k, v in over.items():
        setattr(p, k, v)
    return p


def dead_reckoning(ds):
    from .data import compose
    start = np.array(ds.steps[0].truth if ds.steps[0].truth is not None else np.zeros(3), float)
    out = [start]
    for s in ds.steps[1:]:
        out.append(compose(out[-1], s.odom))
    return np.array(out)


def _clean(m):
    return {k: v for k, v in m.items() if not k.startswith("_")}


def _r(v, n=4):
    if isinstance(v, float):
        return round(v, n) if math.isfinite(v) else None
    if isinstance(v, list):
        return [_r(x, n) for x in v]
    if isinstance(v, dict):
        return {k: _r(x, n) for k, x in v.items()}
    return v


def _used_whole(res, p):
    """The main run's observations used for range and bearing, not those kept for their bearing
    alone (--far-bearing), whose range variance no factor uses. May be empty: with --far-init a
    landmark can start from bearings and never be seen near."""
    from .backend import bearing_only
    return [o for (_, o, _) in res.assoc if not bearing_only(o, p)]


def mean_obs_cov(res, p):
    """The mean of the main run's observation covariances (of those it used whole)."""
    return np.mean([o.cov for o in _used_whole(res, p)], axis=0)


def mean_frame_cov(res, p):
    """The mean of the frame covariances the main run's factors used (less the part a landmark's
    bias state carries; of the observations used whole), or None when it had no calibration states."""
    obs = _used_whole(res, p)
    if not p.calib_states or any(o.cov_frame is None for o in obs):
        return None
    return np.mean([o.cov_frame - (o.jac_calib[:, 2:4] @ np.diag(o.bias_var_px2) @ o.jac_calib[:, 2:4].T
                                   if o.bias_var_px2 is not None and p.lm_bias != "none" else 0.0)
                    for o in obs], axis=0)


def process(ds, args, label, outdir):
    """Main run + fixed-covariance run + metrics + outputs. Returns the summary dict."""
    from . import metrics
    from .backend import Slam
    prog = Progress(label, args.progress)
    live = None
    if getattr(args, "rerun", None) or getattr(args, "rerun_spawn", False):
        from .live import LiveView
        live = LiveView(save_path=args.rerun, spawn=args.rerun_spawn, images=args.rerun_images)
    res = Slam(_params(args), progress=prog, on_step=live.step if live else None).run(ds)
    if live:
        live.final(ds, res)
        live.close()
    m = metrics.evaluate(ds, res)
    summary = {"name": ds.name, "steps": len(ds.steps), "observations": ds.n_obs()}
    summary.update(_clean(m))
    summary["stats"] = res.stats
    has_truth = ds.has_truth()
    if has_truth:
        dr = dead_reckoning(ds)
        idx = [i for i, s in enumerate(ds.steps) if s.truth is not None]
        tr = np.array([ds.steps[i].truth for i in idx])
        summary["ate_dead_reckoning_unaligned_m"], summary["ate_dead_reckoning_m"], _ = \
            metrics.ate(dr[idx], tr)
    else:
        dr = None
    res_fixed = None
    align_fixed = None
    if args.fixed_cov != "none" and res.assoc and not _used_whole(res, _params(args)):
        summary["fixed_cov_failed"] = ("no observation was used for range and bearing (every landmark "
                                       "started from far bearings): no covariance to fix")
    elif args.fixed_cov != "none" and res.assoc:
        # grid/mean: the whole covariance replaced, no calibration states in the fixed runs.
        # frame-grid: the fixed runs keep the calibration and bias states and replace each
        # observation's frame covariance, the per-observation noise estimate, by one matrix: the
        # comparison is then of that estimate alone.
        mean = mean_frame_cov(res, _params(args)) if args.fixed_cov == "frame-grid" else None
        if args.fixed_cov == "frame-grid" and mean is None:
            raise ValueError("--fixed-cov frame-grid needs --calib-states and frame covariances in the log")
        key_cov = "fixed_frame_cov" if mean is not None else "fixed_cov"
        if mean is None:
            mean = mean_obs_cov(res, _params(args))
        scales = FIXED_GRID if (args.fixed_cov in ("grid", "frame-grid") and has_truth) else (1.0,)
        best = None
        why = []
        grid_ate = {}   # every scale's ATE (None: failed or mapped nothing), for a choice made elsewhere
        for sc in scales:
            grid_ate[f"{sc:g}"] = None
            try:
                rf = Slam(_params(args, **{key_cov: mean * sc}, covariances=(len(scales) == 1)),
                          progress=Progress(f"{label} fixed x{sc:g}", args.progress)).run(ds)
            except RuntimeError as e:   # GTSAM: an ill-posed system (e.g. a landmark seen once)
                why.append(f"x{sc:g}: solver failed ({str(e).splitlines()[0][:80]})")
                continue
            mf = metrics.evaluate(ds, rf) if has_truth else {}
            # A run that maps no landmark is not a baseline: its "ATE" is dead reckoning's.
            if has_truth and mf.get("landmark_rmse_m") is None:
                why.append(f"x{sc:g}: mapped no landmark")
                continue
            key = grid_ate[f"{sc:g}"] = mf.get("ate_m", 0.0)
            if best is None or key < best[0]:
                best = (key, sc, rf, mf)
        what = ("the mean per-observation frame covariance (calibration and bias states kept)"
                if key_cov == "fixed_frame_cov" else "the mean per-observation covariance")
        summary["fixed_cov_tuning"] = ("grid over " + ",".join(f"{s:g}" for s in scales) + " x " + what +
                                       ", best ATE among the runs that map landmarks"
                                       if len(scales) > 1 else what)
        if has_truth and len(scales) > 1:
            summary["fixed_cov_grid_ate_m"] = grid_ate
        if best is None:
            summary["fixed_cov_failed"] = (f"none of the {len(scales)} fixed covariances gave a map: "
                                           + "; ".join(why))
        else:
            _, sc, res_fixed, mf = best
            if len(scales) > 1:   # marginals for the chosen one only
                res_fixed = Slam(_params(args, **{key_cov: mean * sc}), progress=None).run(ds)
                mf = metrics.evaluate(ds, res_fixed)
            align_fixed = mf.get("_align")
            summary["fixed_cov_rb"] = (mean * sc).tolist()
            summary["fixed_cov_scale"] = sc
            for k in ("ate_m", "ate_unaligned_m", "landmark_rmse_m", "anees_landmarks", "anees_poses",
                      "association_errors"):
                if k in mf:
                    name = f"{k[:-2]}_fixed_cov_m" if k.endswith("_m") else f"{k}_fixed_cov"
                    summary[name] = mf[k]
    if outdir:
        os.makedirs(outdir, exist_ok=True)
        write_outputs(outdir, ds, res, m)
        from .plot import plot
        if not args.no_plot:
            t = ds.name + (f": ATE (aligned) {summary['ate_m']:.3f} m, unaligned "
                           f"{summary['ate_unaligned_m']:.3f} m" if "ate_m" in summary else "")
            if "ate_fixed_cov_m" in summary:
                t += f" (fixed cov. {summary['ate_fixed_cov_m']:.3f} m)"
            plot(os.path.join(outdir, "plot.png"), ds, res, t, res_fixed=res_fixed,
                 dead_reckoning=dr, align=m.get("_align"), align_fixed=align_fixed)
        with open(os.path.join(outdir, "summary.json"), "w") as fh:
            json.dump(_r(summary, 6), fh, indent=1)
        summary["outputs"] = outdir
    return summary


def _tum_line(t, x, y, th):
    return f"{t:.9f} {x:.9f} {y:.9f} 0 0 0 {math.sin(th / 2):.12f} {math.cos(th / 2):.12f}\n"


def _kitti_line(x, y, th):
    c, s = math.cos(th), math.sin(th)
    return f"{c:.12g} {-s:.12g} 0 {x:.9f} {s:.12g} {c:.12g} 0 {y:.9f} 0 0 1 0\n"


def write_trajectory_files(outdir, ds, res):
    """TUM (`t x y z qx qy qz qw`) and KITTI (3x4 row-major) files of the estimate and, when the
    log has it, the truth, for evo (`evo_ape tum truth.tum trajectory.tum -a`); landmarks.tum lists
    the landmark map with the landmark's index as its timestamp."""
    with open(os.path.join(outdir, "trajectory.tum"), "w") as ft, \
            open(os.path.join(outdir, "trajectory_kitti.txt"), "w") as fk:
        for i, s in enumerate(ds.steps):
            ft.write(_tum_line(s.t, *res.poses[i]))
            fk.write(_kitti_line(*res.poses[i]))
    steps = [s for s in ds.steps if s.truth is not None]
    if steps:
        with open(os.path.join(outdir, "truth.tum"), "w") as ft, \
                open(os.path.join(outdir, "truth_kitti.txt"), "w") as fk:
            for s in steps:
                ft.write(_tum_line(s.t, *s.truth))
                fk.write(_kitti_line(*s.truth))
    with open(os.path.join(outdir, "landmarks.tum"), "w") as fh:
        for j in range(len(res.lms)):
            fh.write(_tum_line(float(j), res.lms[j, 0], res.lms[j, 1], 0.0))


def write_outputs(outdir, ds, res, m):
    write_trajectory_files(outdir, ds, res)
    with open(os.path.join(outdir, "trajectory.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["step", "seq", "t", "x_m", "y_m", "theta_rad", "cov_xx", "cov_xy", "cov_xt",
                    "cov_yy", "cov_yt", "cov_tt", "true_x_m", "true_y_m", "true_theta_rad"])
        for i, s in enumerate(ds.steps):
            c = res.pose_cov[i] if res.pose_cov is not None else np.full((3, 3), np.nan)
            tr = s.truth if s.truth is not None else (math.nan,) * 3
            w.writerow([i, s.seq, f"{s.t:.6f}", *(f"{v:.6f}" for v in res.poses[i]),
                        *(f"{v:.6g}" for v in (c[0, 0], c[0, 1], c[0, 2], c[1, 1], c[1, 2], c[2, 2])),
                        *(f"{v:.6f}" for v in tr)])
    match = m.get("_match", {})
    nobs = np.bincount([j for (_, _, j) in res.assoc], minlength=len(res.lms))
    with open(os.path.join(outdir, "landmarks.csv"), "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["landmark", "class", "known_id", "true_id", "x_m", "y_m", "cov_xx", "cov_xy",
                    "cov_yy", "n_obs", "true_x_m", "true_y_m"])
        for j in range(len(res.lms)):
            c = res.lm_cov[j] if res.lm_cov is not None else np.full((2, 2), np.nan)
            tid = match.get(j)
            tp = ds.truth_landmarks[tid][:2] if tid is not None else (math.nan, math.nan)
            w.writerow([j, res.lm_class[j], "" if res.lm_ids[j] is None else res.lm_ids[j],
                        "" if tid is None else tid, f"{res.lms[j, 0]:.6f}", f"{res.lms[j, 1]:.6f}",
                        f"{c[0, 0]:.6g}", f"{c[0, 1]:.6g}", f"{c[1, 1]:.6g}", int(nobs[j]),
                        f"{tp[0]:.6f}", f"{tp[1]:.6f}"])


def print_summary(s, out=sys.stdout):
    def f(k, unit="", nd=3):
        v = s.get(k)
        return "-" if v is None else (f"{v:.{nd}f}{unit}" if isinstance(v, float) else f"{v}{unit}")
    st = s.get("stats", {})
    print(f"== {s['name']}: {s['steps']} poses, {s['observations']} observations", file=out)
    print(f"   used {st.get('used')}, dropped: flags {st.get('dropped_flags')}, no range "
          f"{st.get('dropped_no_range')}, confidence {st.get('dropped_confidence')}, ambiguous "
          f"{st.get('dropped_ambiguous')}, imprecise {st.get('dropped_imprecise')}, far "
          f"{st.get('dropped_far')}; landmarks "
          f"{st.get('n_landmarks')} "
          f"({st.get('association')} association)", file=out)
    print(f"   time: iSAM2 {st.get('t_isam_s')} s, batch LM {st.get('t_batch_s')} s, total "
          f"{st.get('t_total_s')} s", file=out)
    if "ate_m" in s:
        print(f"   position RMSE: aligned {f('ate_m', ' m')}, unaligned {f('ate_unaligned_m', ' m')}"
              f"; iSAM2 before batch {f('ate_isam_m', ' m')}; dead reckoning "
              f"{f('ate_dead_reckoning_m', ' m')} aligned, {f('ate_dead_reckoning_unaligned_m', ' m')}"
              " unaligned", file=out)
    if "landmark_rmse_m" in s:
        print(f"   landmarks: RMSE {f('landmark_rmse_m', ' m')} (aligned "
              f"{f('landmark_rmse_aligned_m', ' m')}), matched {s.get('landmarks_matched')}/"
              f"{s.get('landmarks_true')}, estimated {s.get('landmarks_estimated')}, association "
              f"errors {s.get('association_errors')}", file=out)
    if "anees_landmarks" in s or "anees_poses" in s:
        bl = s.get("anees_landmarks_bounds95") or [math.nan, math.nan]
        bp = s.get("anees_poses_bounds95") or [math.nan, math.nan]
        print(f"   ANEES landmarks {f('anees_landmarks')} (95% bounds {bl[0]:.3f}-{bl[1]:.3f}), "
              f"poses {f('anees_poses')} ({bp[0]:.3f}-{bp[1]:.3f}) (means of the marginal NEES)", file=out)
    if "anees_landmarks_joint" in s or "anees_poses_joint" in s:
        bl = s.get("anees_landmarks_joint_bounds95") or [math.nan, math.nan]
        bp = s.get("anees_poses_joint_bounds95") or [math.nan, math.nan]
        print(f"   joint ANEES landmarks {f('anees_landmarks_joint')} ({bl[0]:.3f}-{bl[1]:.3f}), "
              f"poses {f('anees_poses_joint')} ({bp[0]:.3f}-{bp[1]:.3f}) (errors whitened together: "
              "the test for correlated estimates)", file=out)
    if "fixed_cov_failed" in s:
        print(f"   fixed covariance ({s.get('fixed_cov_tuning')}): FAILED: {s['fixed_cov_failed']}", file=out)
    elif "ate_fixed_cov_m" in s or "fixed_cov_rb" in s:
        print(f"   fixed covariance ({s.get('fixed_cov_tuning')}): ATE {f('ate_fixed_cov_m', ' m')}, "
              f"landmark RMSE {f('landmark_rmse_fixed_cov_m', ' m')}, ANEES landmarks "
              f"{f('anees_landmarks_fixed_cov')}, association errors "
              f"{f('association_errors_fixed_cov')}", file=out)
    if s.get("outputs"):
        print(f"   outputs: {s['outputs']}/(trajectory.csv, landmarks.csv, trajectory.tum, summary.json, plot.png)",
              file=out)


LAST_KEYS = ("ate_m", "ate_unaligned_m", "landmark_rmse_m", "anees_landmarks", "anees_poses",
             "anees_landmarks_joint", "anees_poses_joint",
             "association_errors", "ate_fixed_cov_m", "landmark_rmse_fixed_cov_m",
             "anees_landmarks_fixed_cov", "fixed_cov_failed", "ate_dead_reckoning_m", "landmarks_estimated")


def last_line(s, extra=None):
    d = {k: s.get(k) for k in LAST_KEYS}
    d["time_s"] = s.get("stats", {}).get("t_total_s")
    if extra:
        d.update(extra)
    return json.dumps(_r(d, 4))


def add_common(sp, assoc_default="auto", robust_default="none", fixed_default="grid",
               max_range_rel_sigma_default=0.0, reject_default="0xb20", far_bearing_default=False,
               far_bearing_every_default=0.0, far_init_default=False,
               far_robust_default="none", merged_var_scale_default=1.0):
    g = sp.add_argument_group("back end")
    g.add_argument("--assoc", choices=["auto", "known", "unknown", "mixed"], default=assoc_default,
                   help="data association: known identities, unknown (Mahalanobis gating), mixed "
                        "(identities where observations carry one, gating elsewhere), or auto = known when "
                        "every observation carries an identity, mixed when some do (default %(default)s)")
    g.add_argument("--conf-min", type=float, default=0.5,
                   help="drop observations with confidence below this (default %(default)s)")
    g.add_argument("--gate", type=float, default=0.99,
                   help="association gate probability, chi-square 2 dof (default %(default)s)")
    g.add_argument("--new-gate", type=float, default=0.9999,
                   help="new landmark only if beyond this chi-square probability of every "
                        "landmark; between --gate and this: dropped as ambiguous (default %(default)s)")
    g.add_argument("--assoc-method", choices=["hungarian", "jcbb"], default="hungarian",
                   help="unknown association: the assignment of least total distance among "
                        "individually gated pairs, or joint compatibility branch and bound (the most "
                        "pairings whose joint innovation passes the gate) (default %(default)s)")
    g.add_argument("--exclusion", action="store_true",
                   help="unknown association: an observation whose compatible landmarks are all "
                        "taken by other observations of its frame starts a landmark (one landmark "
                        "gives one observation a frame) instead of being dropped as ambiguous")
    g.add_argument("--init-views", type=int, default=1, metavar="K",
                   help="unknown association: a landmark starts once K views from distinct steps agree "
                        "on its point (a candidate buffer; views not confirmed within 50 steps are "
                        "dropped and counted) (default %(default)s: at once)")
    g.add_argument("--merge-every", type=int, default=0, metavar="N",
                   help="unknown association: every N steps, merge two landmarks of a class never "
                        "seen in one frame whose difference passes the gate (default 0: never)")
    g.add_argument("--reassoc", type=int, default=0, metavar="N",
                   help="unknown association: after the batch solve, pair every observation again at "
                        "the whole run's estimate, merge duplicate landmarks and solve again, up to N "
                        "passes or until no pairing changes (default 0: none; not with --calib-states)")
    g.add_argument("--starts", type=_scales, default=None, metavar="S1,S2,...",
                   help="unknown association with --reassoc: one online pass per value, its odometry "
                        "sigmas times the value for its gating only; after re-association under the "
                        "nominal sigmas the pass whose solution has the least penalised negative "
                        "log-likelihood is kept (default: 1, one pass)")
    g.add_argument("--cand-radius", type=float, default=2.0,
                   help="m, Euclidean pre-selection of association candidates, plus 3 sigma of "
                        "the observation (default %(default)s)")
    g.add_argument("--reject-flags", default=reject_default,
                   help="drop observations with any of these flag bits (default %(default)s; 0xb20 is "
                        "the format's rule: cut, no range, invalid, partly hidden; 0x400 adds the "
                        "frontend's non-linear flag, sigma_r/r > 0.055, 0x010 merged blobs)")
    g.add_argument("--init-max-sigma", type=float, default=0.5,
                   help="m, no new landmark from an observation whose planar sigma is larger "
                        "(default %(default)s)")
    g.add_argument("--robust", choices=["none", "huber", "cauchy"], default=robust_default,
                   help="robust kernel on observation factors (default " +
                        (robust_default or "the learned noise model's with --noise learned, else huber") + ")")
    g.add_argument("--huber-k", "--robust-k", dest="huber_k", type=float, default=1.345,
                   help="the kernel's threshold on the whitened residual (default %(default)s)")
    g.add_argument("--anchor", choices=["truth", "origin"], default="truth",
                   help="gauge: first pose at the true start pose when known, else origin "
                        "(default %(default)s)")
    g.add_argument("--no-batch", action="store_true", help="skip the final batch LM pass")
    g.add_argument("--max-range-rel-sigma", type=float, default=max_range_rel_sigma_default,
                   help="drop observations whose range sigma exceeds this times their range: far "
                        "from the camera the range varies as 1/tan of the depression and its "
                        "distribution, and a calibration error's effect, are far from linear "
                        "(0 = keep all; default %(default)s)")
    g.add_argument("--merged-var-scale", type=float, default=merged_var_scale_default, metavar="S",
                   help="a merged blob's frame covariance (flag 0x010: more than one 4-connected "
                        "component, most landmarks at high sensor noise) times S (default %(default)s)")
    g.add_argument("--far-bearing", action=argparse.BooleanOptionalAction, default=far_bearing_default,
                   help="keep an observation dropped only as far (the non-linear flag 0x400 among "
                        "--reject-flags, or --max-range-rel-sigma) for its bearing alone: with "
                        "--calib-states its image column; it starts no landmark (default: %s)"
                        % ("on" if far_bearing_default else "off"))
    from .backend import Params
    g.add_argument("--far-bearing-scale", type=float, default=Params.far_bearing_var_scale, metavar="S",
                   help="with --far-bearing and --calib-states: that bearing's variance (the "
                        "frame's) times S (default %(default)s)")
    g.add_argument("--far-bearing-every", type=float, default=far_bearing_every_default, metavar="T",
                   help="with --far-bearing: of one landmark's far bearings one at most every T s, "
                        "the others dropped (0: all; default %(default)s)")
    g.add_argument("--far-robust", choices=("none", "huber", "cauchy"), default=far_robust_default,
                   help="with --far-bearing: the robust kernel on the bearing-only factors (scale "
                        "--huber-k; --robust, when set, covers them too) (default %(default)s)")
    # None: the command's default, and off with --no-far-bearing (an explicit --far-init there is
    # the usage error Params.check names)
    g.add_argument("--far-init", action=argparse.BooleanOptionalAction, default=None,
                   help="with --far-bearing: a landmark seen only far away starts from its bearings "
                        "(a track of far views whose rays, at the poses' estimates, meet with "
                        "--far-init-parallax degrees of spread; no range enters a factor) "
                        "(default: %s)" % ("on with --far-bearing" if far_init_default else "off"))
    sp.set_defaults(far_init_default=far_init_default)
    g.add_argument("--far-init-parallax", type=float, default=Params.far_init_parallax_deg, metavar="DEG",
                   help="with --far-init: the spread of a track's rays that starts it (default %(default)s)")
    g.add_argument("--far-init-views", type=int, default=Params.far_init_views, metavar="N",
                   help="with --far-init: and at least N views from distinct steps (default %(default)s)")
    g.add_argument("--far-init-window", type=int, default=Params.far_init_window, metavar="STEPS",
                   help="with --far-init: a track not seen for STEPS steps is dropped (default %(default)s)")
    g.add_argument("--far-init-range-scale", type=float, default=Params.far_init_range_scale, metavar="K",
                   help="with --far-init: a far view joins a track inside the gate of its "
                        "range-bearing point, the range's sigma times K (default %(default)s)")
    g.add_argument("--far-init-clear", type=float, default=Params.far_init_clear_m, metavar="M",
                   help="with --far-init: a track triangulated within M m of a mapped landmark of "
                        "its class is dropped (default %(default)s)")
    g.add_argument("--calib-states", action="store_true",
                   help="estimate the camera calibration's error (fx fy cx cy tilt yaw h s) as one "
                        "state for the run: each observation's factor uses its frame covariance and "
                        "calibration Jacobian instead of its full covariance (our logs; "
                        "docs/uncertainty.md)")
    g.add_argument("--calib-model", choices=["linear", "exact"], default="linear",
                   help="with --calib-states, how an observation depends on the calibration error: "
                        "linear (the log's jac_calib at the nominal calibration) or exact (libcyl's camera "
                        "model evaluated at the estimated calibration through the cyl Python binding, the "
                        "residual taken in the image; needs the header camera's distortion and u_px, v_px; "
                        "docs/uncertainty.md, \"Far observations\") (default %(default)s)")
    g.add_argument("--lm-bias", choices=["auto", "state", "none"], default="auto",
                   help="with --calib-states: the centroid's residual bias (the log's bias_var_px2) "
                        "as one state per landmark shared by its observations (state), or as white "
                        "noise in each frame like the rest of cov_frame (none); auto: state where "
                        "the log has the field (default %(default)s)")
    g.add_argument("--bias-gm", type=_pair, default=None, metavar="SU,SV",
                   help="with a bias state: the centroid's time-correlated bias, px (u, v), as a "
                        "Gauss-Markov state per observation chained along each landmark's views")
    g.add_argument("--bias-gm-tau", type=_pair, default=None, metavar="TU,TV",
                   help="its correlation times, s (u, v; default 3,10)")
    g.add_argument("--bias-gm-cauchy", type=float, default=0.0, metavar="K",
                   help="with --bias-gm: a Cauchy kernel of scale K on the drift's whitened steps, for "
                        "jumps such as a landmark sliding behind something (0: none; default %(default)s)")
    g.add_argument("--white-scale", type=_pair, default=None, metavar="KU,KV",
                   help="with --bias-gm: the frame's white centroid variance times these (default 1,1)")
    g.add_argument("--fixed-cov", choices=["grid", "mean", "frame-grid", "none"], default=fixed_default,
                   help="side-by-side run with ONE fixed observation covariance: the mean of the "
                        "per-observation covariances (mean), or the best of 0.25..4 x that mean by "
                        "ATE (grid, needs truth; these runs have no calibration states), or, with "
                        "--calib-states, the best of 0.25..4 x the mean frame covariance in place of "
                        "each observation's, calibration and bias states kept (frame-grid: the "
                        "per-observation noise estimate compared alone), or none (default %(default)s)")
    o = sp.add_argument_group("output")
    o.add_argument("--out", default=None, help="output directory (CSV, JSON, PNG)")
    o.add_argument("--no-plot", action="store_true", help="do not write plot.png")
    o.add_argument("--rerun", metavar="FILE.rrd", default=None,
                   help="live view with rerun (rerun-sdk), saved headless to FILE.rrd: robot, trajectory, "
                        "observations, landmarks with 95%% ellipses as the run goes, then the final map")
    o.add_argument("--rerun-spawn", action="store_true", help="open the rerun viewer and show the run live")
    o.add_argument("--rerun-images", metavar="DIR", default=None,
                   help="the overlay images of `cyl detect --overlay DIR` (frame_<seq>.png), shown per step")
    o.add_argument("--progress", dest="progress", action="store_true", default=sys.stderr.isatty(),
                   help="progress bar on stderr (default: when stderr is a terminal)")
    o.add_argument("--no-progress", dest="progress", action="store_false")


def cmd_synth(args):
    from .synth import generate
    info = generate(args.output, frames=args.frames, seed=args.seed, n_landmarks=args.landmarks,
                    clutter=args.clutter)
    print(f"wrote {args.output}: {info}")
    return EXIT_OK


def cmd_run(args):
    from .obslog import ObsLogError, read_obslog
    try:
        ds = read_obslog(args.log, skip_bad=args.skip_bad, bridge_gaps=args.bridge_gaps)
    except (ObsLogError, OSError) as e:
        print(f"cylslam: error: {e}", file=sys.stderr)
        return EXIT_INPUT
    for n in ds.notes:
        print(f"note: {n}")
    if _reassoc_conflict(args):
        return EXIT_USAGE
    if args.fixed_cov == "frame-grid" and not args.calib_states:
        print("cylslam: error: --fixed-cov frame-grid needs --calib-states", file=sys.stderr)
        return EXIT_USAGE
    out = args.out or os.path.join("out", "slam", "stdin" if args.log == "-" else
                                   os.path.splitext(os.path.basename(args.log))[0])
    try:   # before the run: a folder that cannot be made fails now, not after the work
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        print(f"cylslam: error: {out}: cannot create the output folder: {e.strerror}", file=sys.stderr)
        return EXIT_OUTPUT
    try:
        s = process(ds, args, "slam", out)
    except ValueError as e:
        print(f"cylslam: error: {e}", file=sys.stderr)
        return EXIT_INPUT
    except OSError as e:
        print(f"cylslam: error: {e.filename or out}: cannot write the outputs: {e.strerror}", file=sys.stderr)
        return EXIT_OUTPUT
    s["skipped_lines"] = getattr(ds, "n_skipped", 0)
    print_summary(s)
    rc = EXIT_OK
    if args.check:
        fails = check_synthetic(s)
        for f in fails:
            print(f"CHECK FAILED: {f}")
        if not fails:
            print("checks passed: ANEES landmarks within 95% bounds, per-frame ATE < fixed, "
                  "0 association errors")
        rc = EXIT_CHECK if fails else EXIT_OK
    print(last_line(s, {"skipped_lines": s["skipped_lines"]}))
    return rc


def check_synthetic(s):
    fails = []
    a, b = s.get("anees_landmarks"), s.get("anees_landmarks_bounds95")
    if a is None or not (b[0] <= a <= b[1]):
        fails.append(f"landmark ANEES {a} outside {b}")
    if "fixed_cov_failed" in s:
        pass  # the baseline mapped nothing: nothing to beat (reported as failed)
    elif s.get("ate_fixed_cov_m") is None or not s["ate_m"] < s["ate_fixed_cov_m"]:
        fails.append(f"ATE {s.get('ate_m')} not below fixed-cov ATE {s.get('ate_fixed_cov_m')}")
    if s.get("association_errors") != 0:
        fails.append(f"{s.get('association_errors')} association errors")
    return fails


def cmd_mrclam(args):
    from .mrclam import MrclamError, read_mrclam
    from .noise_model import NoiseModel, NoiseModelError
    robots = [1, 2, 3, 4, 5] if args.robot == "all" else [int(args.robot)]
    rows = []
    model = None
    if _reassoc_conflict(args):
        return EXIT_USAGE
    if args.noise != "learned" and args.noise_model is not None:
        print("cylslam: error: --noise-model needs --noise learned", file=sys.stderr)
        return EXIT_USAGE
    if args.noise != "learned" and args.odom_corr is not None:
        print("cylslam: error: --odom-corr needs --noise learned (the fixed models have no correlation)",
              file=sys.stderr)
        return EXIT_USAGE
    args.odom_corr = args.odom_corr or "state"
    if args.summary_out and not os.path.isdir(os.path.dirname(os.path.abspath(args.summary_out))):
        print(f"cylslam: error: --summary-out {args.summary_out}: no such directory", file=sys.stderr)
        return EXIT_OUTPUT
    if args.noise == "learned":
        from .noise_model import DEFAULT_PATH
        args.noise_model = args.noise_model or DEFAULT_PATH
        try:
            model = NoiseModel.load(args.noise_model)
        except NoiseModelError as e:
            print(f"cylslam: error: {e}", file=sys.stderr)
            return EXIT_INPUT
    if args.robust is None:   # the learned model's kernel, else Huber
        args.robust, args.huber_k = model.factor_kernel() if model else ("huber", args.huber_k)
    datasets = []
    for rb in robots:
        try:
            ds = read_mrclam(args.dir, rb, duration=args.duration, noise=args.noise,
                             odom_scale=args.odom_scale, model=model, odom_corr=args.odom_corr)
        except MrclamError as e:
            print(f"cylslam: error: {e}", file=sys.stderr)
            return EXIT_INPUT
        for n in ds.notes:
            print(f"note: {n}")
        out = os.path.join(args.out, f"robot{rb}") if args.out else None
        s = process(ds, args, f"robot {rb}", out)
        s["duration_s"] = ds.duration_s
        print_summary(s)
        rows.append((rb, s))
        datasets.append(ds)
    print()
    print(f"MRCLAM {os.path.basename(os.path.normpath(args.dir))}, {args.assoc} association, "
          f"noise {args.noise}" + (f" ({args.noise_model})" if model else "") +
          f", robust {args.robust}" + (f" k {args.huber_k:.3g}" if args.robust != "none" else "") +
          f", odometry sigmas x{args.odom_scale:g}")
    print("| robot | duration s | poses | obs used | RMSE aligned m | RMSE unaligned m | "
          "dead reckoning unaligned m | landmark RMSE m | ANEES lm | ANEES poses | assoc. errors | "
          "fixed-cov RMSE m | time s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for rb, s in rows:
        st = s["stats"]
        print(f"| {rb} | {s['duration_s']:.0f} | {s['steps']} | {st['used']} | {s['ate_m']:.3f} | "
              f"{s['ate_unaligned_m']:.3f} | {s.get('ate_dead_reckoning_unaligned_m', math.nan):.3f} | "
              f"{s.get('landmark_rmse_m', math.nan):.3f} | {s.get('anees_landmarks', math.nan):.2f} | "
              f"{s.get('anees_poses', math.nan):.2f} | {s.get('association_errors')} | "
              f"{s.get('ate_fixed_cov_m', math.nan):.3f} | {st['t_total_s']:.2f} |")
    worst = max(rows, key=lambda r: r[1]["ate_m"])[1]
    rc = EXIT_OK
    if args.check_rmse is not None:
        bad = [rb for rb, s in rows if not s["ate_m"] <= args.check_rmse]
        slow = [rb for rb, s in rows if args.check_time and s["stats"]["t_total_s"] > args.check_time]
        if bad or slow:
            print(f"CHECK FAILED: robots over {args.check_rmse} m: {bad}; over time: {slow}")
            rc = EXIT_CHECK
        else:
            print(f"checks passed: every robot's aligned RMSE <= {args.check_rmse} m")
    per = {str(rb): _r({k: s.get(k) for k in LAST_KEYS} | {"time_s": s["stats"]["t_total_s"]}, 4)
           for rb, s in rows}
    agg = {k: worst.get(k) for k in LAST_KEYS}
    agg["association_errors"] = sum((s.get("association_errors") or 0) for _, s in rows)
    agg["time_s"] = max(s["stats"]["t_total_s"] for _, s in rows)
    agg["worst_robot"] = max(rows, key=lambda r: r[1]["ate_m"])[0]
    agg["robots"] = per
    agg["aligned_rmse_max_m"] = max(s["ate_m"] for _, s in rows)
    lm_anees = [s.get("anees_landmarks") for _, s in rows if s.get("anees_landmarks") is not None]
    agg["anees_landmarks_max"] = max(lm_anees) if lm_anees else None
    n_lm = [s.get("landmarks_estimated") for _, s in rows if s.get("landmarks_estimated") is not None]
    agg["landmarks_min"], agg["landmarks_max"] = (min(n_lm), max(n_lm)) if n_lm else (None, None)
    agg["parameters"] = {"assoc": args.assoc, "noise": args.noise,
                         "noise_model": args.noise_model if model else None, "robust": args.robust,
                         "robust_k": args.huber_k if args.robust != "none" else None,
                         "odom_scale": args.odom_scale, "gate": args.gate, "new_gate": args.new_gate,
                         "exclusion": args.exclusion, "assoc_method": args.assoc_method,
                         "reassoc": args.reassoc, "starts": list(args.starts or (1.0,)),
                         "odom_corr": args.odom_corr if model else None}
    if args.multi:
        agg.update(multi_robot(args, datasets, robots))
        if args.check_rmse is not None:
            if not agg["multi_aligned_rmse_max_m"] <= args.check_rmse:
                print(f"CHECK FAILED: one map: a robot's RMSE in the joint frame is "
                      f"{agg['multi_aligned_rmse_max_m']:.3f} m > {args.check_rmse} m")
                rc = EXIT_CHECK
            else:
                print(f"checks passed: one map: every robot's RMSE in the joint frame <= {args.check_rmse} m")
    line = json.dumps(_r(agg, 4))
    if args.summary_out:
        from .noise_model import write_text_safely
        try:
            write_text_safely(args.summary_out, line + "\n")
        except NoiseModelError as e:
            print(line)
            print(f"cylslam: error: {e}", file=sys.stderr)
            return EXIT_OUTPUT
    print(line)
    return rc


def multi_robot(args, dss, robots):
    """All robots in one graph with shared landmarks (cylslam/multi.py), from the data sets the
    single-robot runs read; prints a table and returns the multi_* keys of the last line."""
    from .multi import evaluate_multi, run_multi
    res = run_multi(dss, robots, _params(args, assoc="known"), progress=Progress("one map", args.progress))
    for n in res.notes:
        print(f"note: {n}")
    m = evaluate_multi(dss, robots, res)
    print()
    print(f"One map from robots {','.join(map(str, res.robots))} (known association, shared landmarks, start "
          f"poses of robots after the first unknown): {res.stats['poses']} poses, "
          f"{res.stats['observations_used']} observations, {res.stats['landmarks']} landmarks, "
          f"{res.stats['t_total_s']:.1f} s")
    print("| robot | RMSE in the joint frame m | RMSE aligned alone m | RMSE unaligned m | joint ANEES poses |")
    print("|---|---|---|---|---|")
    for lab in res.robots:
        r = m["robots"][str(lab)]
        print(f"| {lab} | {r['aligned_rmse_joint_frame_m']:.3f} | {r['own_aligned_rmse_m']:.3f} | "
              f"{r['unaligned_rmse_m']:.3f} | {r['anees_poses_joint']:.2f} |")
    print(f"landmarks: RMSE {m.get('landmark_rmse_aligned_m', math.nan):.3f} m in the joint frame "
          f"({m.get('landmark_rmse_m', math.nan):.3f} m unaligned), ANEES {m.get('anees_landmarks', math.nan):.2f}, "
          f"joint ANEES {m.get('anees_landmarks_joint', math.nan):.2f}")
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        with open(os.path.join(args.out, "one_map.json"), "w") as fh:
            json.dump(_r({"stats": res.stats, "notes": res.notes, **m}, 6), fh, indent=1)
        with open(os.path.join(args.out, "one_map_landmarks.csv"), "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["id", "x_m", "y_m", "cov_xx", "cov_xy", "cov_yy"])
            for i in sorted(res.lms):
                c = res.lm_cov[i]
                w.writerow([i, f"{res.lms[i][0]:.6f}", f"{res.lms[i][1]:.6f}", f"{c[0, 0]:.6g}", f"{c[0, 1]:.6g}",
                            f"{c[1, 1]:.6g}"])
        for lab in res.robots:
            with open(os.path.join(args.out, f"one_map_robot{lab}.tum"), "w") as fh:
                ds = dss[robots.index(lab)]
                for st, q in zip(ds.steps, res.poses[lab]):
                    fh.write(_tum_line(st.t, *q))
    per = [m["robots"][str(lab)]["aligned_rmse_joint_frame_m"] for lab in res.robots]
    return {"multi_robots": res.robots, "multi_aligned_rmse_max_m": max(per),
            "multi_landmark_rmse_m": m.get("landmark_rmse_aligned_m"),
            "multi_landmark_rmse_unaligned_m": m.get("landmark_rmse_m"),
            "multi_anees_landmarks": m.get("anees_landmarks"), "multi_time_s": res.stats["t_total_s"]}


def cmd_mrclam_noise(args):
    from .mrclam import MrclamError, read_mrclam
    from . import noise_model as nm
    try:
        robots = [int(x) for x in args.robots.split(",")]
    except ValueError:
        print(f"cylslam: error: --robots: expected numbers separated by commas, got {args.robots!r}", file=sys.stderr)
        return EXIT_USAGE
    if args.slam_check and args.no_cross_check:
        print("cylslam: error: --slam-check is part of the held-out check (drop --no-cross-check)", file=sys.stderr)
        return EXIT_USAGE
    def read_robot(rb, mdl):
        return read_mrclam(args.dir, rb, model=mdl)

    try:
        model, rep = nm.fit(lambda mdl: [read_robot(r, mdl) for r in robots],
                            f"{os.path.basename(os.path.normpath(args.dir))}, robots {','.join(map(str, robots))}")
    except (MrclamError, nm.NoiseModelError) as e:
        print(f"cylslam: error: {e}", file=sys.stderr)
        return EXIT_INPUT
    print(f"{len(rep['residuals'])} measurement residuals, {len(rep['odometry_residuals'])} odometry steps")
    print("| measurement kernel | a_r m | b_r | a_b rad | b_b rad m | k | BIC |")
    print("|---|---|---|---|---|---|---|")
    for k, v in rep["measurement"].items():
        kk = "-" if v["kernel_k"] is None else f"{v['kernel_k']:.3f}"
        print(f"| {k}{' (chosen)' if k == rep['chosen'] else ''} | {v['a_r_m']:.4f} | {v['b_r']:.4f} | "
              f"{v['a_b_rad']:.5f} | {v['b_b_rad_m']:.5f} | {kk} | {v['bic']:.1f} |")
    print(f"odometry: a command acts {model.cmd_delay_s:.3f} s after its stamp; the robots drive "
          f"{model.cmd_scale[0]:.3f} and turn {model.cmd_scale[1]:.3f} times what they are commanded (the "
          "commands are shifted and scaled so before integration)")
    print("| odometry component | k_t (per sqrt s) | k_d (per m) | k_a (per rad) |")
    print("|---|---|---|---|")
    for c in ("x", "y", "theta"):
        o = model.odom[c]
        print(f"| {c} | {o['k_t']:.3g} | {o['k_d']:.3g} | {o['k_a']:.3g} |")
    for what, use, corr in (("measurement errors, per robot and landmark",
                             "each variance is multiplied by the sum of its correlations", model.corr),
                            ("odometry step errors, per robot",
                             "the batch carries them as Gauss-Markov states", model.odom_corr),
                            ("odometry step errors, one exponential",
                             "online (iSAM2) each step's variance is multiplied by the sum of its correlations",
                             model.odom_corr_inflation)):
        if corr:
            print(f"correlation in time of the {what} (rho(dt) = a1 exp(-dt/tau1) + a2 exp(-dt/tau2); {use}):")
            for comp, c in corr.items():
                print(f"  {comp}: a1 {c['a1']:.3f} tau1 {c['tau1_s']:.3g} s, a2 {c['a2']:.3f} tau2 {c['tau2_s']:.3g} s")
    own = nm.check(model, rep["datasets"])
    print("on the fitting data:", json.dumps(_r(own, 3)))
    summary = {"kernel": model.kernel, "kernel_k": model.kernel_k, **{k: model.meas[k] for k in model.meas},
               "speed_scale": model.cmd_scale[0], "turn_scale": model.cmd_scale[1],
               "command_delay_s": model.cmd_delay_s,
               "fit_check": own}
    if args.out:   # before the held-out check, which may fail on its own
        try:
            model.save(args.out)
        except nm.NoiseModelError as e:
            print(f"cylslam: error: {e}", file=sys.stderr)
            return EXIT_OUTPUT
        print(f"wrote {args.out}")
    if args.plot:
        from .plot import correlation_plot
        try:
            nm.write_text_safely(args.plot, correlation_plot(model))
        except nm.NoiseModelError as e:
            print(f"cylslam: error: {e}", file=sys.stderr)
            return EXIT_OUTPUT
        print(f"wrote {args.plot}")
    # the held-out check: the robots in two halves (1,3,5 / 2,4 for all five), each fitted on one
    # half and judged on the other
    halves = (tuple(robots[0::2]), tuple(robots[1::2]))
    if not args.no_cross_check and not halves[1]:
        print("note: one robot: no held-out check")
    elif not args.no_cross_check:
        try:
            cc = nm.cross_check(read_robot, [halves, halves[::-1]])
        except (MrclamError, nm.NoiseModelError) as e:
            print(f"cylslam: error: held-out check: {e}", file=sys.stderr)
            return EXIT_INPUT
        summary["held_out"] = []
        for train, test, m2, ch in cc:
            print(f"fit on robots {train} ({m2.kernel}), judged on {test}:", json.dumps(_r(ch, 3)))
            row = {"train": train, "test": test, **ch}
            if args.slam_check:
                from .backend import Params, Slam
                from . import metrics
                row["slam"] = {}
                for rb in test:
                    ds = read_robot(rb, m2)
                    robust, k = m2.factor_kernel()
                    res = Slam(Params(assoc="known", robust=robust, huber_k=k)).run(ds)
                    mm = metrics.evaluate(ds, res)
                    row["slam"][str(rb)] = {k: mm.get(k) for k in ("ate_m", "anees_landmarks", "anees_poses",
                                                                  "landmark_rmse_m")}
                    print(f"  SLAM (known association) on held-out robot {rb}: aligned RMSE {mm['ate_m']:.3f} m, "
                          f"landmark ANEES {mm['anees_landmarks']:.2f}, pose ANEES {mm['anees_poses']:.2f}")
            summary["held_out"].append(row)
    print(json.dumps(_r(summary, 4)))
    return EXIT_OK


def cmd_victoria(args):
    from .victoria import read_victoria
    try:
        ds = read_victoria(args.file, max_poses=args.max_poses)
    except (OSError, ValueError, RuntimeError) as e:
        print(f"cylslam: error: {e}", file=sys.stderr)
        return EXIT_INPUT
    for n in ds.notes:
        print(f"note: {n}")
    s = process(ds, args, "victoria", args.out)
    print_summary(s)
    print(last_line(s, {"landmarks": s["stats"]["n_landmarks"], "poses": s["steps"]}))
    return EXIT_OK


def cmd_excerpt(args):
    from .mrclam import write_excerpt
    write_excerpt(args.src, args.dst, args.robot, args.seconds)
    print(f"wrote the first {args.seconds} s of robot {args.robot} from {args.src} to {args.dst}")
    return EXIT_OK


def build_parser():
    ap = argparse.ArgumentParser(prog="python -m cylslam",
                                 description="Landmark SLAM (GTSAM) with per-observation covariance. "
                                             "Exit codes: 0 ok, 1 check failed, 2 usage, 3 input error, "
                                             "4 cannot write the outputs.")
    from . import __version__
    ap.add_argument("--version", action="version", version=f"cylslam {__version__}")
    sub = ap.add_subparsers(dest="cmd", required=True)

    sp = sub.add_parser("run", help="SLAM on an observation log (docs/formats.md)",
                        description="Run the back end on a cyl-observations JSON Lines log; with "
                                    "truth lines, print metrics. Last stdout line: JSON.")
    sp.add_argument("log", help="observation log (.jsonl); - reads standard input to its end, e.g. behind "
                    "`cyl detect SOURCE --out -`")
    sp.add_argument("--bridge-gaps", action="store_true",
                    help="a frame without its odom line in a log with odometry (a lost step of the "
                         "robot's motion) is an error; with this, a zero-motion step with large sigmas "
                         "spans it (reported)")
    sp.add_argument("--skip-bad", action="store_true",
                    help="skip malformed lines (counted and listed) instead of stopping at the first")
    sp.add_argument("--check", action="store_true",
                    help="exit 1 unless landmark ANEES is within its 95%% bounds, ATE < fixed-cov "
                         "ATE and there are no association errors")
    # 0x400: observations the frontend flags non-linear are dropped. Chosen on the synthetic drive's
    # tuning seeds 1-20 (landmark ANEES inside its 95% bounds on 16 of 20, against 9 keeping them;
    # docs/uncertainty.md); the same rule as --max-range-rel-sigma 0.055.
    # --far-bearing, one a landmark every 0.5 s at the frame's variance: chosen on the tuning seeds
    # 1-20 and seeds 1-6 at sensor noise x2 and x0.5 (thinned every 0.25, 0.5 or 1 s, both joint
    # ANEES inside on 24 of those 32 drives, against 25 dropping the far views and 20 using every
    # one, which over-states the poses at x2; of the three intervals the lowest median ATE;
    # docs/uncertainty.md, "Far observations for their bearing alone")
    # 0x800 (partly hidden), --far-init (landmarks seen only far start from their bearings, rays
    # spread over 5 degrees) and --far-robust cauchy: chosen together on the same 32 tuning drives
    # (drives meeting all three per-drive criteria -- both joint ANEES inside, ATE below the best
    # fixed covariance -- 17, against 14 for the defaults before; docs/uncertainty.md, "Landmarks
    # seen only far away")
    # --merged-var-scale 2: chosen on the same 32 tuning drives among 1, 1.5, 2, 3, 4 by the same
    # rule (both joint ANEES inside on 26, against 23 at 1; all three criteria on 20, against 16);
    # docs/uncertainty.md, "Merged blobs"
    add_common(sp, reject_default="0xf20", far_bearing_default=True, far_bearing_every_default=0.5,
               far_init_default=True, far_robust_default="cauchy", merged_var_scale_default=2.0)
    sp.set_defaults(func=cmd_run)

    sp = sub.add_parser("synth", help="write a synthetic observation log with ground truth",
                        description="Synthetic drive (figure-eight), landmarks in 2 colours, clutter, "
                                    "range-dependent per-observation covariance; see cylslam/synth.py.")
    sp.add_argument("output", help="log to write (.jsonl)")
    sp.add_argument("--frames", type=int, default=1200)
    sp.add_argument("--seed", type=int, default=7)
    sp.add_argument("--landmarks", type=int, default=16)
    sp.add_argument("--clutter", type=float, default=0.15, help="clutter probability per frame")
    sp.set_defaults(func=cmd_synth)

    sp = sub.add_parser("mrclam", help="SLAM on UTIAS MRCLAM robots",
                        description="One or all robots of an MRCLAM data set directory; prints a "
                                    "per-robot table. Last stdout line: JSON (worst robot + per robot).")
    sp.add_argument("--dir", default=os.environ.get("MRCLAM_DIR", "../shared/data/mrclam/MRCLAM_Dataset7"),
                    help="data set directory (default $MRCLAM_DIR or %(default)s)")
    sp.add_argument("--robot", default="all", help="1-5 or all (default %(default)s)")
    sp.add_argument("--duration", type=float, default=None, help="only the first S seconds")
    sp.add_argument("--noise", choices=["range", "fixed", "learned"], default="range",
                    help="noise model: range-dependent sigma_r = 0.03 r + 0.02 m, or fixed sigma_r = 0.1 m, "
                         "both with sigma_b = 0.01 rad and the reader's odometry sigmas; or learned: "
                         "measurement and odometry sigmas and the measurement kernel from --noise-model "
                         "(default %(default)s)")
    sp.add_argument("--noise-model", default=None,
                    help="a model written by `mrclam-noise` (with --noise learned; default: the one fitted "
                         "on Dataset 7 and shipped with cylslam, cylslam/models/mrclam_noise.json)")
    sp.add_argument("--odom-scale", type=float, default=1.0,
                    help="multiply the odometry sigmas by this (default %(default)s)")
    sp.add_argument("--odom-corr", choices=["state", "inflate"], default=None,
                    help="with --noise learned, how the model's odometry correlation in time is used: state "
                         "(the batch solution carries each step's correlated error as a Gauss-Markov state "
                         "shared by neighbouring steps) or inflate (each step's variance multiplied by its "
                         "correlation sum, as iSAM2 uses it online) (default state)")
    sp.add_argument("--multi", action="store_true",
                    help="also map all the robots together: one graph, shared landmarks, the start poses "
                         "of all robots but the first unknown (known association)")
    sp.add_argument("--check-rmse", type=float, default=None,
                    help="exit 1 unless every robot's aligned RMSE is <= this (with --multi: in the joint "
                         "frame too)")
    sp.add_argument("--summary-out", default=None, metavar="FILE",
                    help="also write the last line (JSON) to FILE")
    sp.add_argument("--check-time", type=float, default=None,
                    help="with --check-rmse: exit 1 if a robot's run takes longer (s)")
    add_common(sp, assoc_default="known", robust_default=None, fixed_default="mean")
    sp.set_defaults(func=cmd_mrclam)

    sp = sub.add_parser("mrclam-noise", help="learn the range/bearing and odometry noise from MRCLAM truth",
                        description="Fit the noise model (cylslam/noise_model.py) on the residuals of "
                                    "an MRCLAM data set against its Vicon truth: sigmas as functions of "
                                    "range and motion, the measurement kernel chosen by BIC; then check "
                                    "it on held-out robots (fit on 1,3,5, judge on 2,4, and the reverse). "
                                    "Last stdout line: JSON.")
    sp.add_argument("--dir", default=os.environ.get("MRCLAM_DIR", "../shared/data/mrclam/MRCLAM_Dataset7"),
                    help="data set directory (default $MRCLAM_DIR or %(default)s)")
    sp.add_argument("--out", default=None, help="write the model (JSON) here")
    sp.add_argument("--robots", default="1,2,3,4,5", help="robots to fit on (default %(default)s)")
    sp.add_argument("--no-cross-check", action="store_true", help="skip the held-out robot check")
    sp.add_argument("--plot", default=None, metavar="FILE.png",
                    help="also draw the fitted correlation in time against the measured lag bins (PNG)")
    sp.add_argument("--slam-check", action="store_true",
                    help="in the held-out check, also map each held-out robot with the model fitted without it "
                         "(known association) and print its RMSE and ANEES")
    sp.set_defaults(func=cmd_mrclam_noise)

    sp = sub.add_parser("victoria", help="SLAM on gtsam's Victoria Park file (no truth)",
                        description="Reads victoria_park.txt with gtsam.load2D (the copy in the "
                                    "gtsam wheel by default).")
    sp.add_argument("--file", default=None, help="path (default: the gtsam wheel's copy)")
    sp.add_argument("--max-poses", type=int, default=None, help="only the first N poses")
    add_common(sp, assoc_default="known", robust_default="huber", fixed_default="none")
    sp.set_defaults(func=cmd_victoria)

    sp = sub.add_parser("excerpt", help="copy the first seconds of one MRCLAM robot (test fixture)")
    sp.add_argument("src")
    sp.add_argument("dst")
    sp.add_argument("--robot", type=int, default=1)
    sp.add_argument("--seconds", type=float, default=120.0)
    sp.set_defaults(func=cmd_excerpt)
    return ap


def main(argv=None):
    ap = build_parser()
    args = ap.parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
