# SPDX-License-Identifier: BSD-3-Clause
"""The learned noise model: the fit recovers the parameters residuals were drawn with, BIC tells
a heavy-tailed kernel from a Gaussian one, the normalisers and radii match closed forms, the model
file is read strictly and written without replacing a device, and the CLI runs on the fixture."""
import json
import math
import os
import stat
import subprocess
import sys

import numpy as np
import pytest

from conftest import FIXTURES, HERE
from cylslam import noise_model as nm
from cylslam import mrclam
from cylslam.mrclam import read_mrclam

MR = os.path.join(FIXTURES, "mrclam")
ENV = dict(os.environ, PYTHONPATH=os.path.dirname(HERE))
TRUE = {"a_r_m": 0.04, "b_r": 0.025, "a_b_rad": 0.006, "b_b_rad_m": 0.015}


def _draw(kernel, k, n, rng):
    """Residuals (r, e_r, e_b) from the model's 2-D density: a direction uniform on the circle,
    a radius by inverting the radial CDF (Gaussian: Rayleigh; Cauchy: 1 - (1 + s^2/k^2)^(1 - k^2/2))."""
    r = rng.uniform(1.0, 6.0, n)
    u = rng.uniform(0.0, 1.0, n)
    if kernel == "gaussian":
        s = np.sqrt(-2.0 * np.log1p(-u))
    else:
        s = k * np.sqrt((1.0 - u) ** (1.0 / (1.0 - k * k / 2.0)) - 1.0)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    sr = np.sqrt(TRUE["a_r_m"] ** 2 + (TRUE["b_r"] * r) ** 2)
    sb = np.sqrt(TRUE["a_b_rad"] ** 2 + (TRUE["b_b_rad_m"] / r) ** 2)
    return np.stack([r, s * np.cos(phi) * sr, s * np.sin(phi) * sb], 1)


@pytest.mark.parametrize("kernel,k", [("gaussian", None), ("cauchy", 2.3)])
def test_fit_recovers_the_parameters_and_the_kernel(kernel, k):
    R = _draw(kernel, k, 6000, np.random.default_rng(11))
    per, chosen = nm.fit_measurements(R)
    assert chosen == kernel
    got = per[kernel]
    for key, want in TRUE.items():
        assert got[key] == pytest.approx(want, rel=0.12), key
    if k:
        assert got["kernel_k"] == pytest.approx(k, rel=0.1)


def test_odometry_fit_recovers_the_rates():
    rng = np.random.default_rng(5)
    n = 5000
    dt = rng.uniform(0.1, 0.5, n)
    d = rng.uniform(0.0, 0.1, n)
    a = rng.uniform(0.0, 0.3, n)
    want = np.array([[0.01, 0.05, 0.02], [0.002, 0.02, 0.01], [0.02, 0.2, 0.3]])
    var = np.stack([nm.ODOM_FLOOR ** 2 + want[c, 0] ** 2 * dt + (want[c, 1] * d) ** 2 + (want[c, 2] * a) ** 2
                    for c in range(3)], 1)
    O = np.column_stack([dt, d, a, rng.normal(0.0, 1.0, (n, 3)) * np.sqrt(var)])
    per, chosen = nm.fit_odometry(O, ("gaussian",))
    m = per["gaussian"]["model"]
    # the largest term of each component is well determined; the smaller ones within a factor
    assert m["x"]["k_d"] == pytest.approx(0.05, rel=0.15)
    assert m["y"]["k_d"] == pytest.approx(0.02, rel=0.15)
    assert m["theta"]["k_a"] == pytest.approx(0.3, rel=0.1)
    assert m["theta"]["k_d"] == pytest.approx(0.2, rel=0.25)


def test_normalisers_and_radii_match_closed_forms():
    k = 1.5
    huber = math.log(2 * math.pi * ((1 - math.exp(-k * k / 2)) + math.exp(-k * k / 2) * (k * k + 1) / (k * k)))
    assert nm.log_norm("huber", k, 2) == pytest.approx(huber, abs=1e-9)
    assert nm.log_norm("cauchy", 2.3, 2) == pytest.approx(math.log(2 * math.pi * 2.3 ** 2 / (2.3 ** 2 - 2)), abs=1e-9)
    assert nm.log_norm("cauchy", 1.2, 2) == math.inf          # k^2 <= 2: no density
    assert nm.log_norm_fast("cauchy", 2.3, 3) == pytest.approx(nm.log_norm("cauchy", 2.3, 3), abs=1e-5)
    assert nm.radius("gaussian", None, 0.95) == pytest.approx(math.sqrt(-2 * math.log(0.05)), rel=1e-6)
    assert nm.radius("cauchy", 2.3, 0.5) == pytest.approx(2.3 * math.sqrt(0.5 ** (1 / (1 - 2.3 ** 2 / 2)) - 1), rel=1e-6)


def _model():
    return nm.NoiseModel(dict(TRUE), {c: {"k_t": 0.01, "k_d": 0.05, "k_a": 0.1} for c in ("x", "y", "theta")},
                         "cauchy", 2.3, "gaussian", None, {"source": "test"})


def test_model_round_trip_and_strict_reading(tmp_path):
    p = str(tmp_path / "m.json")
    _model().save(p)
    m = nm.NoiseModel.load(p)
    assert m.kernel == "cauchy" and m.kernel_k == 2.3 and m.meas == TRUE and m.corr is None
    assert np.allclose(np.sqrt(np.diag(m.meas_cov(2.0))),
                       [math.hypot(0.04, 0.05), math.hypot(0.006, 0.0075)])
    j = json.load(open(p))
    for edit, field in ((lambda j: j["measurement"].update(extra=1), "measurement: unknown key(s) extra"),
                        (lambda j: j["odometry"]["x"].pop("k_t"), "odometry.x: missing key(s) k_t"),
                        (lambda j: j["measurement"].update(kernel="tukey"), "measurement.kernel"),
                        (lambda j: j["measurement"].update(kernel_k=None), "measurement.kernel_k"),
                        (lambda j: j["odometry"]["theta"].update(k_a=-1), "odometry.theta.k_a"),
                        (lambda j: j.update(version=9), "version 1"),
                        (lambda j: j["measurement"].update(a_r_m=float("inf")), "measurement.a_r_m"),
                        (lambda j: j["odometry"].update(speed_scale=True), "odometry.speed_scale"),
                        (lambda j: j["measurement"].update(kernel_k=0.01), "measurement.kernel_k"),
                        (lambda j: j["odometry"].update(kernel="cauchy", kernel_k=2.0), "odometry.kernel"),
                        (lambda j: j["odometry"].update(kernel_k=3.0), "odometry.kernel_k: must be null"),
                        (lambda j: j.update(provenance=[]), "provenance"),
                        (lambda j: j.update(extra=1), "top level: unknown key"),
                        (lambda j: j["measurement"].update(correlation={"range": {"a1": 0.8, "tau1_s": 1, "a2": 0.5,
                                                                                  "tau2_s": 2},
                                                                        "bearing": {"a1": 0, "tau1_s": 1, "a2": 0,
                                                                                    "tau2_s": 1}}),
                         "measurement.correlation.range: a1 \\+ a2")):
        jj = json.loads(json.dumps(j))
        edit(jj)
        q = str(tmp_path / "bad.json")
        open(q, "w").write(json.dumps(jj))
        with pytest.raises(nm.NoiseModelError, match=field.replace("(", r"\(").replace(")", r"\)")):
            nm.NoiseModel.load(q)
    # version 2 needs the inflation's correlation; version 1 has none, and its one correlation
    # serves both uses
    jj = json.loads(json.dumps(j))
    jj["odometry"].pop("inflation_correlation")
    q = str(tmp_path / "v2.json")
    open(q, "w").write(json.dumps(jj))
    with pytest.raises(nm.NoiseModelError, match="odometry: missing key.*inflation_correlation"):
        nm.NoiseModel.load(q)
    corr = {c: {"a1": 0.5, "tau1_s": 3.0, "a2": 0.1, "tau2_s": 60.0} for c in ("x", "y", "theta")}
    jj["odometry"]["correlation"] = corr
    jj["version"] = 1
    open(q, "w").write(json.dumps(jj))
    m1 = nm.NoiseModel.load(q)
    assert m1.odom_corr == corr and m1.odom_corr_inflation == corr
    jj["odometry"]["inflation_correlation"] = corr
    open(q, "w").write(json.dumps(jj))
    with pytest.raises(nm.NoiseModelError, match="odometry: unknown key.*inflation_correlation"):
        nm.NoiseModel.load(q)
    # a key twice in one object
    q = str(tmp_path / "dup.json")
    open(q, "w").write(open(p).read().replace('"b_r":', '"a_r_m": 1, "b_r":', 1))
    with pytest.raises(nm.NoiseModelError, match="'a_r_m' appears twice"):
        nm.NoiseModel.load(q)


def test_model_file_never_replaces_a_device_or_a_link(tmp_path):
    m = _model()
    if os.geteuid() == 0:   # only root could replace /dev/null
        m.save("/dev/null")
        assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    m.save(str(link))
    assert link.is_symlink() and json.loads(real.read_text())["measurement"]["kernel"] == "cauchy"
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    r = subprocess.Popen(["cat", str(fifo)], stdout=subprocess.PIPE)
    m.save(str(fifo))
    assert json.loads(r.communicate(timeout=10)[0])["format"] == nm.FORMAT
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    with pytest.raises(nm.NoiseModelError, match="is a directory"):
        m.save(str(tmp_path))


def test_the_shipped_model_reads_and_applies():
    m = nm.NoiseModel.load(nm.DEFAULT_PATH)
    ds = read_mrclam(MR, 2, model=m)
    # one landmark's measurements: the model's covariance times the stream's inflation factors
    lid = ds.steps[next(i for i, s in enumerate(ds.steps) if s.obs)].obs[0].lm_id
    stream = [o for s in ds.steps for o in s.obs if o.lm_id == lid]
    times = [float(o.where.split("t=")[1]) for o in stream]
    f = m.inflation(times)
    assert len(stream) > 10 and f.min() >= 1.0 and f.max() > 2.0
    for o, fi in zip(stream, f):
        assert np.allclose(o.cov, m.meas_cov(o.range_m, fi), rtol=1e-9)
    times = np.array([s.t for s in ds.steps])
    fo = m.odom_inflation(times)
    s = ds.steps[5]
    assert np.allclose(s.odom_cov, m.odom_cov(s.odom, s.t - ds.steps[4].t) * fo[5])


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "cylslam", *args], capture_output=True, text=True, env=ENV,
                          timeout=300)


def test_cli_fits_on_the_fixture_and_maps_with_the_model(tmp_path):
    out = str(tmp_path / "model.json")
    r = _cli("mrclam-noise", "--dir", MR, "--robots", "2", "--no-cross-check", "--out", out)
    assert r.returncode == 0, r.stderr
    last = json.loads(r.stdout.strip().splitlines()[-1])
    assert last["kernel"] in nm.KERNELS and last["fit_check"]["measurements"] > 100
    # one robot: no held-out check, said so; the model is written all the same
    os.unlink(out)
    png = str(tmp_path / "corr.png")
    r = _cli("mrclam-noise", "--dir", MR, "--robots", "2", "--out", out, "--plot", png)
    assert r.returncode == 0 and "no held-out check" in r.stdout and os.path.exists(out), r.stderr
    with open(png, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    # the plot is an output like the model: a directory is refused with its name
    r = _cli("mrclam-noise", "--dir", MR, "--robots", "2", "--no-cross-check", "--plot", str(tmp_path))
    assert r.returncode == 4 and "is a directory" in r.stderr
    # robots the folder does not hold: a clear error, not a traceback
    r = _cli("mrclam-noise", "--dir", MR, "--robots", "1,2")
    assert r.returncode == 3 and "Robot1_Odometry.dat" in r.stderr and "Traceback" not in r.stderr
    r = _cli("mrclam", "--dir", MR, "--robot", "2", "--noise", "learned", "--noise-model", out, "--no-plot")
    assert r.returncode == 0, r.stderr
    assert "noise learned" in r.stdout
    assert json.loads(r.stdout.strip().splitlines()[-1])["association_errors"] == 0
    r = _cli("mrclam", "--dir", MR, "--robot", "2", "--noise", "learned", "--noise-model", str(tmp_path / "none.json"))
    assert r.returncode == 3 and "none.json" in r.stderr


def _drive(delay_true, scale_true):
    """A read(model) for command_delay / fit: velocity commands every 0.1 s (random, held), the
    robot executing them `delay_true` s late and scaled by `scale_true`; the odometry integrated
    from the commands as the model says (its delay and scales)."""
    from cylslam.data import Dataset, Step, between
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 120.0, 0.1)
    v = np.repeat(rng.uniform(0.0, 0.3, len(t) // 10), 10)
    w = np.repeat(rng.uniform(-0.8, 0.8, len(t) // 10), 10)
    steps_t = np.arange(1.0, 118.0, 0.5)

    def poses(delay, sv, sw):
        odo = np.stack([t + delay, v * sv, w * sw], 1)
        return mrclam.dr_at(odo, mrclam.integrate(odo), steps_t)

    truth = poses(delay_true, *scale_true)

    def read(model):
        d, s = (model.cmd_delay_s, model.cmd_scale) if model is not None else (0.0, (1.0, 1.0))
        dr = poses(d, *s)
        steps = [Step(t=float(steps_t[0]), seq=0, truth=truth[0])]
        for k in range(1, len(steps_t)):
            steps.append(Step(t=float(steps_t[k]), seq=k, truth=truth[k], odom=between(dr[k - 1], dr[k]),
                              odom_cov=np.eye(3)))
        return [Dataset(name="drive", steps=steps)]

    return read


def test_command_delay_and_scales_are_recovered():
    read = _drive(0.2, (0.9, 0.8))
    d = nm.command_delay(read)
    assert d == pytest.approx(0.2, abs=0.01)
    sv, sw = nm.command_scales(read(nm._odometry_only(delay=d)))
    assert sv == pytest.approx(0.9, abs=0.01) and sw == pytest.approx(0.8, abs=0.01)


def test_shipped_model_round_trips(tmp_path):
    m = nm.NoiseModel.load(nm.DEFAULT_PATH)
    assert m.corr is not None and m.odom_corr is not None and m.cmd_delay_s > 0
    p = str(tmp_path / "again.json")
    m.save(p)
    m2 = nm.NoiseModel.load(p)
    assert m2.to_json() == m.to_json()


def test_inflation_is_the_sum_of_correlations():
    corr = {"a1": 0.6, "tau1_s": 2.0, "a2": 0.2, "tau2_s": 20.0}
    m = nm.NoiseModel(dict(TRUE), {c: {"k_t": 0.0, "k_d": 0.0, "k_a": 0.0} for c in ("x", "y", "theta")},
                      corr={"range": corr, "bearing": corr}, odom_corr={"x": corr, "y": corr, "theta": corr})
    t = [0.0, 1.0, 5.0]
    rho = lambda d: 0.6 * math.exp(-d / 2.0) + 0.2 * math.exp(-d / 20.0)  # noqa: E731
    want = [1 + rho(1) + rho(5), 1 + rho(1) + rho(4), 1 + rho(5) + rho(4)]
    f = m.inflation(t)
    assert np.allclose(f[:, 0], want) and np.allclose(f[:, 1], want)
    # any order in, the same order out
    assert np.allclose(m.inflation([5.0, 0.0, 1.0])[:, 0], [want[2], want[0], want[1]])
    assert np.allclose(m.odom_inflation(t)[:, 2], want)
    # a lone measurement, or no correlation model: factor 1
    assert np.allclose(m.inflation([3.0]), 1.0)
    m.corr = None
    assert np.allclose(m.inflation(t), 1.0)


def test_correlation_of_an_exponentially_correlated_stream_is_recovered():
    # AR(1) samples every 0.5 s with correlation exp(-dt / 4 s), 40 streams of 400
    rng = np.random.default_rng(9)
    tau, dt = 4.0, 0.5
    phi = math.exp(-dt / tau)
    streams = []
    for _ in range(40):
        z = np.empty(400)
        z[0] = rng.normal()
        for i in range(1, 400):
            z[i] = phi * z[i - 1] + math.sqrt(1 - phi * phi) * rng.normal()
        t = np.arange(400) * dt
        streams.append(np.stack([t, np.full(400, 2.0), z, z], 1))
    centres, counts, rr, rb = nm.empirical_correlation(streams, lambda r: (np.ones(len(r)), np.ones(len(r))), clip=10)
    c = nm.fit_correlation(centres, counts, rr, terms=1)
    assert c["a1"] == pytest.approx(1.0, abs=0.1)
    assert c["tau1_s"] == pytest.approx(tau, rel=0.2)
