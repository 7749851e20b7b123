# SPDX-License-Identifier: BSD-3-Clause
"""Reader and writer of the observation log (docs/formats.md, `cyl-observations` version 1).

Malformed lines. Default (strict): the reader stops at the first malformed line and raises
ObsLogError("FILE:LINE: reason"); nothing is estimated from a log that is not understood.
With skip_bad=True it skips each malformed line, keeps going, and reports how many it skipped and
where (Dataset.notes, printed in the summary): nothing is dropped silently either way.
Always tolerated: a last line without its newline that does not parse (an interrupted writer,
the format promises every *complete* record survives) -- reported, not used; blank lines;
records of an unknown `type` (skipped by the format's rule, counted in the notes); null
(non-finite) range/covariance fields on observations flagged no-range (0x100) or invalid (0x200),
which are never used.

A line is malformed when it is not a JSON object, lacks a required field, has a field of the
wrong type or a non-finite number, has a covariance that is not symmetric positive (semi-)definite,
or belongs to another frame than the `frame` line before it.

Frames become steps: each `frame` with an `odom` line is one pose; the first frame is the start
pose (its odom line, if any, has no previous pose and is ignored). In a log without odometry (a
camera alone) the observations of later frames are attached to the first pose (counted in the
notes). In a log with odometry a later frame without an `odom` line is a lost step of the robot's
motion (e.g. a malformed odom line skipped by skip_bad): an error naming it, or with bridge_gaps a
zero-motion step with large sigmas (BRIDGE_SIGMAS), reported in the notes.

Optional field (a proposed extension of the format): `"landmark_id": int` on an `obs` line for
sources that know identities; when every usable observation has one the back end may use known
association.
"""
from __future__ import annotations

import json
import math

import numpy as np

from .data import FLAG_INVALID, FLAG_NO_RANGE, Dataset, Obs, Step

FORMAT = "cyl-observations"
VERSION = 2            # what the writer below writes
READ_VERSIONS = (1, 2)  # version 2 adds each observation's blob box, bbox_px (not used here)


class ObsLogError(Exception):
    """A malformed observation log: message starts with FILE:LINE."""


def _finite(v):
    """True for a finite JSON number (an integer too large for a float is not)."""
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _num(rec, key, where, required=True, default=None):
    if key not in rec:
        if required:
            raise ObsLogError(f"{where}: missing field '{key}'")
        return default
    v = rec[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ObsLogError(f"{where}: field '{key}' must be a number, got {json.dumps(v)}")
    if not _finite(v):
        raise ObsLogError(f"{where}: field '{key}' is not finite")
    return float(v)


def _num_or_nan(rec, key, where):
    if key in rec and rec[key] is None:
        return float("nan")
    return _num(rec, key, where)


def _int(rec, key, where, required=True, default=None):
    if key not in rec:
        if required:
            raise ObsLogError(f"{where}: missing field '{key}'")
        return default
    v = rec[key]
    if isinstance(v, bool) or not isinstance(v, int):
        raise ObsLogError(f"{where}: field '{key}' must be an integer, got {json.dumps(v)}")
    return v


def _str(rec, key, where):
    v = rec.get(key)
    if not isinstance(v, str) or not v:
        raise ObsLogError(f"{where}: field '{key}' must be a non-empty string")
    return v


def _numlist(rec, key, n, where, layout=""):
    """rec[key] as n floats; `layout` (e.g. " (xx xy ...)") ends the error message."""
    v = rec.get(key)
    if (not isinstance(v, list) or len(v) != n or
            not all(isinstance(x, (int, float)) and not isinstance(x, bool) and _finite(x) for x in v)):
        raise ObsLogError(f"{where}: field {key!r} must be a list of {n} finite numbers{layout}")
    return [float(x) for x in v]


def _check_cov(m, where, what, rtol=1e-12):
    """Symmetric and positive semi-definite: no eigenvalue below -rtol * max(1, largest)."""
    if not np.allclose(m, m.T):
        raise ObsLogError(f"{where}: {what} covariance is not symmetric")
    with np.errstate(all="ignore"):
        ev = np.linalg.eigvalsh(m)
    if not np.all(np.isfinite(ev)):   # entries near 1e308: eigenvalues overflow
        raise ObsLogError(f"{where}: {what} covariance is out of range")
    if ev.min() < -rtol * max(1.0, ev.max()):
        raise ObsLogError(f"{where}: {what} covariance is not positive semi-definite "
                          f"(eigenvalues {ev.tolist()})")


# Sigmas of the zero-motion step that --bridge-gaps puts where an odometry step was lost (x, y in
# m, theta in rad): ten times a step of the synthetic drive (0.02 m, 0.03 rad), so the lost motion
# is well inside them.
BRIDGE_SIGMAS = (0.2, 0.2, 0.3)


class _Builder:
    def __init__(self, path):
        self.path = path
        self.steps = []
        self.truth_lm = {}
        self.cur = None          # dict of the frame being read
        self.last_seq = None     # seq of the last frame line (frames without odom included)
        self.n_no_odom = 0
        self.n_first_odom = 0
        self.gaps = []           # (line, seq) of later frames without an odom line
        self.unknown_types = {}

    def flush_frame(self):
        f = self.cur
        if f is None:
            return
        self.cur = None
        if f["n_obs"] is not None and not f["had_skips"] and f["n_obs"] != len(f["obs"]):
            raise ObsLogError(f"{self.path}:{f['line']}: frame seq {f['seq']} announces "
                              f"n_obs={f['n_obs']} but {len(f['obs'])} obs lines follow")
        if not self.steps:
            if f["odom"] is not None:
                self.n_first_odom += 1
            self.steps.append(Step(t=f["t"], seq=f["seq"], obs=f["obs"], truth=f["truth"]))
            return
        if f["odom"] is None:   # resolved by finish(): no odometry at all, or a lost step
            self.gaps.append((f["line"], f["seq"]))
            self.steps.append(Step(t=f["t"], seq=f["seq"], obs=f["obs"], truth=f["truth"]))
            return
        self.steps.append(Step(t=f["t"], seq=f["seq"], odom=f["odom"][0], odom_cov=f["odom"][1],
                               obs=f["obs"], truth=f["truth"]))

    def finish(self, bridge_gaps, notes):
        """Frames after the first without an odom line. In a log without any odometry (a camera
        alone) their observations join the previous pose. In a log with odometry each is a lost
        step of the robot's motion: an error naming it, or with bridge_gaps a zero-motion step
        whose sigmas (BRIDGE_SIGMAS) cover any motion between two frames."""
        if not self.gaps:
            return
        has_odom = any(s.odom is not None for s in self.steps[1:])
        if has_odom and self.gaps[-1][1] == self.steps[-1].seq:
            # the log ends with a frame whose odom line was never written (an interrupted writer,
            # or a --max-frames cut before this was fixed): an incomplete last frame, dropped
            last = self.steps.pop()
            notes.append(f"{self.path}:{self.gaps[-1][0]}: the last frame (seq {last.seq}) has no odom line: "
                         f"dropped as incomplete, with its {len(last.obs)} observation(s)")
            self.gaps.pop()
            if not self.gaps:
                return
        if not has_odom:
            merged = [self.steps[0]]
            for s in self.steps[1:]:
                merged[-1].obs.extend(s.obs)
            self.steps = merged
            self.n_no_odom = len(self.gaps)
            return
        where = "; ".join(f"{self.path}:{ln} (frame seq {sq})" for ln, sq in self.gaps[:10])
        more = f" and {len(self.gaps) - 10} more" if len(self.gaps) > 10 else ""
        if not bridge_gaps:
            raise ObsLogError(f"{self.path}:{self.gaps[0][0]}: frame seq {self.gaps[0][1]} has no odom line in a "
                              f"log with odometry: a step of the robot's motion is lost ({len(self.gaps)} "
                              f"such frame(s): {where}{more}); --bridge-gaps spans each with a zero-motion step "
                              f"of sigmas {BRIDGE_SIGMAS[0]} m, {BRIDGE_SIGMAS[1]} m, {BRIDGE_SIGMAS[2]} rad")
        for s in self.steps[1:]:
            if s.odom is None:
                s.odom = np.zeros(3)
                s.odom_cov = np.diag(np.square(BRIDGE_SIGMAS))
        notes.append(f"bridged {len(self.gaps)} lost odometry step(s) with zero motion and sigmas "
                     f"{BRIDGE_SIGMAS[0]} m, {BRIDGE_SIGMAS[1]} m, {BRIDGE_SIGMAS[2]} rad: {where}{more}")

    def _frame_of(self, rec, where, kind):
        seq = _int(rec, "seq", where)
        if self.cur is None:
            raise ObsLogError(f"{where}: '{kind}' line before any 'frame' line")
        if seq != self.cur["seq"]:
            raise ObsLogError(f"{where}: '{kind}' line has seq {seq} but the current frame "
                              f"(line {self.cur['line']}) is seq {self.cur['seq']}")
        return self.cur

    def record(self, rec, where, lineno):
        typ = rec.get("type")
        if typ == "frame":
            seq = _int(rec, "seq", where)
            t = _num(rec, "t", where)
            n_obs = _int(rec, "n_obs", where, required=False)
            self.flush_frame()
            if self.last_seq is not None and seq <= self.last_seq:
                raise ObsLogError(f"{where}: frame seq {seq} does not increase "
                                  f"(previous {self.last_seq})")
            self.last_seq = seq
            self.cur = dict(seq=seq, t=t, n_obs=n_obs, obs=[], odom=None, truth=None,
                            line=lineno, had_skips=False)
        elif typ == "obs":
            # validate completely before touching the frame
            cls = _str(rec, "class", where)
            flags = _int(rec, "flags", where, required=False, default=0)
            unusable = bool(flags & (FLAG_NO_RANGE | FLAG_INVALID))
            # a no-range / invalid observation may carry null (non-finite) range and covariance
            # fields (the frontend writes non-finite numbers as null); it is never used
            nb = _num_or_nan if unusable else _num
            r = nb(rec, "range_m", where)
            b = _num(rec, "bearing_rad", where) if not flags & FLAG_INVALID else nb(rec, "bearing_rad", where)
            crr = nb(rec, "cov_rr", where)
            crb = nb(rec, "cov_rb", where)
            cbb = nb(rec, "cov_bb", where)
            conf = _num(rec, "confidence", where, required=False, default=1.0)
            lm_id = _int(rec, "landmark_id", where, required=False)
            if r < 0:
                raise ObsLogError(f"{where}: negative range_m {r}")
            if not 0.0 <= conf <= 1.0:
                raise ObsLogError(f"{where}: confidence {conf} outside [0, 1]")
            cov = np.array([[crr, crb], [crb, cbb]])
            if not unusable:
                _check_cov(cov, where, "range/bearing")
            jm = cf = bv = None
            if not unusable and "jac_calib" in rec:   # optional (docs/formats.md)
                jm = np.array(_numlist(rec, "jac_calib", 16, where)).reshape(2, 8)
                c3 = _numlist(rec, "cov_frame", 3, where)
                cf = np.array([[c3[0], c3[1]], [c3[1], c3[2]]])
                _check_cov(cf, where, "cov_frame")
                if "bias_var_px2" in rec:
                    bv = np.array(_numlist(rec, "bias_var_px2", 2, where))
                    if (bv < 0).any():
                        raise ObsLogError(f"{where}: bias_var_px2 must be >= 0, got {bv.tolist()}")
            u = v = None
            if jm is not None and "u_px" in rec:
                u, v = _num(rec, "u_px", where), _num(rec, "v_px", where)
            fr = self._frame_of(rec, where, "obs")
            fr["obs"].append(Obs(cls=cls, range_m=r, bearing_rad=b, cov=cov, confidence=conf,
                                 flags=flags, lm_id=lm_id, where=where, jac_calib=jm, cov_frame=cf,
                                 bias_var_px2=bv, u_px=u, v_px=v, grouped="landmark_model" in rec))
        elif typ == "odom":
            d = np.array([_num(rec, k, where) for k in ("dx_m", "dy_m", "dtheta_rad")])
            xx, xy, xt, yy, yt, tt = _numlist(rec, "cov", 6, where, " (xx xy xt yy yt tt)")
            cov = np.array([[xx, xy, xt], [xy, yy, yt], [xt, yt, tt]], float)
            _check_cov(cov, where, "odometry")
            fr = self._frame_of(rec, where, "odom")
            if fr["odom"] is not None:
                raise ObsLogError(f"{where}: second 'odom' line for frame seq {fr['seq']}")
            # singular is only an error when used (the first frame's odom line is not)
            if self.steps and np.linalg.eigvalsh(cov).min() <= 0:
                raise ObsLogError(f"{where}: odometry covariance is singular")
            fr["odom"] = (d, cov)
        elif typ == "truth_pose":
            p = np.array([_num(rec, k, where) for k in ("x_m", "y_m", "theta_rad")])
            fr = self._frame_of(rec, where, "truth_pose")
            fr["truth"] = p
        elif typ == "truth_landmark":
            i = _int(rec, "id", where)
            cls = _str(rec, "class", where)
            x, y = _num(rec, "x_m", where), _num(rec, "y_m", where)
            if i in self.truth_lm:
                raise ObsLogError(f"{where}: truth_landmark id {i} given twice")
            self.truth_lm[i] = (x, y, cls)
        elif typ == "header":
            raise ObsLogError(f"{where}: second header line")
        elif isinstance(typ, str):
            self.unknown_types[typ] = self.unknown_types.get(typ, 0) + 1
        else:
            raise ObsLogError(f"{where}: missing or non-string 'type'")


def read_obslog(path, skip_bad=False, bridge_gaps=False) -> Dataset:
    """Read an observation log into a Dataset. Raises ObsLogError (strict) or skips bad lines.
    path "-" reads standard input to its end (e.g. behind `cyl detect ... --out -`); messages then
    name it "<stdin>"."""
    if path == "-":
        import sys
        return parse_obslog(sys.stdin.buffer.read(), "<stdin>", skip_bad, bridge_gaps)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as e:
        raise ObsLogError(f"{path}: cannot read ({e.strerror})") from None
    return parse_obslog(raw, path, skip_bad, bridge_gaps)


def parse_obslog(raw: bytes, path="<bytes>", skip_bad=False, bridge_gaps=False) -> Dataset:
    """Parse the bytes of an observation log; `path` only names it in messages."""
    lines = raw.split(b"\n")
    truncated_tail = bool(lines and lines[-1] != b"")
    if not truncated_tail:
        lines = lines[:-1]
    header = None
    calib_cov = None
    b = _Builder(path)
    skipped = []
    notes = []
    n = len(lines)
    for i, bline in enumerate(lines):
        lineno = i + 1
        where = f"{path}:{lineno}"
        last_unterminated = truncated_tail and i == n - 1
        try:
            try:
                text = bline.decode("utf-8")
            except UnicodeDecodeError as e:
                raise ObsLogError(f"{where}: not UTF-8 ({e.reason} at byte {e.start})")
            if not text.strip():
                continue
            try:
                rec = json.loads(text)
            except json.JSONDecodeError as e:
                raise ObsLogError(f"{where}: not valid JSON ({e.msg} at column {e.colno})")
            except ValueError as e:      # e.g. an integer of more than 4300 digits
                raise ObsLogError(f"{where}: not valid JSON ({e})")
            except RecursionError:
                raise ObsLogError(f"{where}: not valid JSON (nested too deeply)")
            if not isinstance(rec, dict):
                raise ObsLogError(f"{where}: not a JSON object")
            if header is None:
                if rec.get("type") != "header":
                    raise ObsLogError(f"{where}: first line must be the header "
                                      "(type 'header')")
                if rec.get("format") != FORMAT:
                    raise ObsLogError(f"{where}: format {rec.get('format')!r}, expected {FORMAT!r}")
                if rec.get("version") not in READ_VERSIONS:
                    raise ObsLogError(f"{where}: unsupported version {rec.get('version')!r} "
                                      f"(this reader knows versions {', '.join(map(str, READ_VERSIONS))})")
                calib_cov = _check_header(rec, where)
                header = rec
                continue
            b.record(rec, where, lineno)
        except ObsLogError as err:
            if last_unterminated and not isinstance(err, _Fatal):
                notes.append(f"ignored the truncated last line {where} (interrupted writer?)")
                break
            if skip_bad and header is not None:
                skipped.append(str(err))
                if b.cur is not None:
                    b.cur["had_skips"] = True
                continue
            raise
    if header is None:
        raise ObsLogError(f"{path}:1: empty log (no header line)")
    b.flush_frame()
    if not b.steps:
        raise ObsLogError(f"{path}: no frames")
    b.finish(bridge_gaps, notes)
    if skipped:
        notes.append(f"skipped {len(skipped)} malformed line(s); first: {skipped[0]}")
        notes.extend(f"  skipped: {s}" for s in skipped[1:10])
        if len(skipped) > 10:
            notes.append(f"  ... and {len(skipped) - 10} more")
    if b.n_no_odom:
        notes.append(f"{b.n_no_odom} frame(s) without odometry: observations attached to the "
                     "previous pose")
    for k, v in sorted(b.unknown_types.items()):
        notes.append(f"skipped {v} record(s) of unknown type {k!r}")
    classes = header.get("classes") or sorted({o.cls for s in b.steps for o in s.obs})
    obs_all = [o for s in b.steps for o in s.obs]
    known = bool(obs_all) and all(o.lm_id is not None for o in obs_all)
    ds = Dataset(name=str(header.get("source", path)), steps=b.steps, truth_landmarks=b.truth_lm,
                 classes=list(classes), notes=notes, known_ids=known)
    ds.n_skipped = len(skipped)
    ds.header = header
    ds.calib_cov = calib_cov
    return ds


def _check_header(rec, where):
    """The header's optional fields have the types docs/formats.md gives them (checked once here,
    so that nothing downstream meets a string where it expects an object). Returns the 8x8
    camera.calib_cov, or None when absent. A null camera or calib_cov counts as absent."""
    if "source" in rec and not isinstance(rec["source"], str):
        raise ObsLogError(f"{where}: header field 'source' must be a string")
    cl = rec.get("classes")
    if cl is not None and (not isinstance(cl, list) or not all(isinstance(c, str) for c in cl)):
        raise ObsLogError(f"{where}: header field 'classes' must be a list of strings")
    cam = rec.get("camera")
    if cam is None:
        return None
    if not isinstance(cam, dict):
        raise ObsLogError(f"{where}: header field 'camera' must be an object")
    if cam.get("calib_cov") is None:
        return None
    m = np.array(_numlist(cam, "calib_cov", 64, where), float).reshape(8, 8)
    # written with 17 digits; older logs have 10, which can tip a rank-deficient block (a fixed
    # aspect ratio makes fx, fy fully correlated) a little below zero
    _check_cov(m, where, "camera.calib_cov", rtol=1e-9)
    return m


class _Fatal(ObsLogError):
    pass


class ObsLogWriter:
    """Writes a log line by line, flushing after each frame (as the frontend does)."""

    def __init__(self, path, source, classes, model="synthetic", estimator="synthetic",
                 camera=None):
        self.fh = open(path, "w")
        self._w(dict(type="header", format=FORMAT, version=VERSION, source=source, model=model,
                     estimator=estimator, classes=list(classes), camera=camera or {}))

    def _w(self, rec):
        self.fh.write(json.dumps(rec, separators=(",", ":")) + "\n")

    def truth_landmark(self, i, cls, class_id, x, y, diameter=0.1, height=0.3):
        self._w(dict(type="truth_landmark", id=i, **{"class": cls}, class_id=class_id,
                     x_m=x, y_m=y, diameter_m=diameter, height_m=height))

    def frame(self, seq, t, obs, odom=None, truth=None):
        """obs: list of dicts with the obs fields (without type/seq/t)."""
        self._w(dict(type="frame", seq=seq, t=t, n_obs=len(obs)))
        for o in obs:
            self._w(dict(type="obs", seq=seq, t=t, **o))
        if odom is not None:
            d, c = odom
            self._w(dict(type="odom", seq=seq, t=t, dx_m=d[0], dy_m=d[1], dtheta_rad=d[2],
                         cov=[c[0][0], c[0][1], c[0][2], c[1][1], c[1][2], c[2][2]]))
        if truth is not None:
            self._w(dict(type="truth_pose", seq=seq, t=t, x_m=truth[0], y_m=truth[1],
                         theta_rad=truth[2]))
        self.fh.flush()

    def close(self):
        self.fh.close()

    def __enter__(self):
        return self

    def __exit__(self, *a):
        self.close()
