# SPDX-License-Identifier: BSD-3-Clause
"""Unknown association's options: one landmark gives one observation a frame (--exclusion), joint
compatibility (--assoc-method jcbb) and the merging of duplicates (--merge-every)."""
import itertools

import gtsam
import numpy as np
import pytest

from cylslam import backend, metrics
from cylslam.backend import L, X
from cylslam.data import Dataset, Obs, Step, wrap


def _obs(pose, lm, cov):
    h, _ = backend.predict_rb(pose, lm)
    return Obs(cls="post", range_m=float(h[0]), bearing_rad=float(h[1]), cov=cov, confidence=1.0)


def _cluster_drive():
    """Two posts 0.2 m apart at 3 m, observed with a range sigma of 0.15 m and a bearing sigma of
    0.04 rad (0.12 m across at 3 m): each post lies well inside the other's gate. Frame 0 sees post
    A alone; frames 1-3 see both."""
    A, B = np.array([3.0, 0.1]), np.array([3.0, -0.1])
    cov = np.diag([0.15 ** 2, 0.04 ** 2])
    steps = [Step(t=0, seq=0, truth=np.zeros(3), obs=[_obs(np.zeros(3), A, cov)])]
    pose = np.zeros(3)
    for k in range(1, 4):
        pose = pose + [0.05, 0.0, 0.0]
        steps.append(Step(t=k, seq=k, odom=np.array([0.05, 0.0, 0.0]), odom_cov=np.diag([1e-6] * 3),
                          truth=pose.copy(), obs=[_obs(pose, A, cov), _obs(pose, B, cov)]))
    return Dataset(name="cluster", steps=steps, truth_landmarks={0: (*A, "post"), 1: (*B, "post")})


@pytest.mark.parametrize("joint", [False, True])
def test_exclusion_maps_both_posts_of_a_cluster(joint):
    """Without exclusion the second post's observation, inside A's gate but not taken by it, is
    dropped as ambiguous frame after frame and B is never mapped; with it, an observation whose every
    compatible landmark is taken in its frame starts B, and both posts are mapped without error."""
    ds = _cluster_drive()
    old = backend.Slam(backend.Params(assoc="unknown", joint=joint)).run(ds)
    assert len(old.lms) == 1 and old.stats["dropped_ambiguous"] == 3
    new = backend.Slam(backend.Params(assoc="unknown", exclusion=True, joint=joint)).run(ds)
    assert len(new.lms) == 2 and new.stats["dropped_ambiguous"] == 0
    assert new.stats["new_by_exclusion"] == 1
    assert metrics.evaluate(ds, new)["association_errors"] == 0
    assert np.allclose(sorted(new.lms[:, 1]), [-0.1, 0.1], atol=0.02)


def _problem(cur, lms, zs, R, sig_pose, sig_lm, ids=None, cands=None, corr=None):
    """One frame's association problem as Slam._associate sees it: landmarks `lms` with
    ids `ids` (default 0..m-1), candidates per observation `cands` (default all), the joint covariance
    of pose and landmarks block-diagonal with the given sigmas plus `corr` (a symmetric matrix added,
    the pose-landmark and landmark-landmark correlations)."""
    ids = list(range(len(lms))) if ids is None else list(ids)
    col = {j: k for k, j in enumerate(ids)}
    dim = 3 + 2 * len(lms)
    cov = np.zeros((dim, dim))
    cov[:3, :3] = np.diag(np.square(sig_pose))
    cov[3:, 3:] = np.eye(2 * len(lms)) * sig_lm ** 2
    if corr is not None:
        cov = cov + corr
    gate = backend.chi2_2dof(0.99)
    cands = [ids for _ in zs] if cands is None else cands
    lm_est = {j: np.asarray(lms[col[j]], float) for j in ids}
    d2s = []
    for z, cs in zip(zs, cands):
        d = {}
        for j in cs:
            h, H = backend.predict_rb(cur, lm_est[j])
            o = 3 + 2 * col[j]
            idx = np.r_[0:3, o:o + 2]
            nu = np.asarray(z, float) - h
            nu[1] = wrap(nu[1])
            d[j] = float(nu @ np.linalg.solve(H @ cov[np.ix_(idx, idx)] @ H.T + R, nu))
        d2s.append(d)
    return dict(zs=[np.asarray(z, float) for z in zs], covs=[R] * len(zs), cands=cands, d2s=d2s, allc=ids,
                lm_est=lm_est, cur=cur, gate=gate), cov


def _jcbb(slam, pb, cov):
    """Slam._jcbb on the problem, its gated pairs built as Slam._associate builds them."""
    col = {j: k for k, j in enumerate(pb["allc"])}
    gated = {}
    for a, z in enumerate(pb["zs"]):
        for j in pb["cands"][a]:
            if pb["d2s"][a][j] <= pb["gate"]:
                h, H = backend.predict_rb(pb["cur"], pb["lm_est"][j])
                nu = z - h
                nu[1] = wrap(nu[1])
                gated[a, j] = (nu, H, np.r_[0:3, 3 + 2 * col[j]:5 + 2 * col[j]])
    return slam._jcbb(gated, pb["covs"], pb["cands"], cov, len(pb["zs"]))


def _joint_nis(pb, cov, hyp):
    col = {j: k for k, j in enumerate(pb["allc"])}
    pairs = [(a, j) for a, j in enumerate(hyp) if j is not None]
    if not pairs:
        return 0.0
    nus, Hs = [], []
    for a, j in pairs:
        h, H = backend.predict_rb(pb["cur"], pb["lm_est"][j])
        Hr = np.zeros((2, cov.shape[0]))
        Hr[:, :3] = H[:, :3]
        o = 3 + 2 * col[j]
        Hr[:, o:o + 2] = H[:, 3:]
        nu = pb["zs"][a] - h
        nu[1] = wrap(nu[1])
        nus.append(nu)
        Hs.append(Hr)
    nu, Hm = np.concatenate(nus), np.vstack(Hs)
    S = Hm @ cov @ Hm.T + np.kron(np.eye(len(pairs)), pb["covs"][0])
    return float(nu @ np.linalg.solve(S, nu))


def _brute_force(pb, cov, p=0.99):
    """Every hypothesis (each observation to a distinct individually gated candidate of its own, or
    none) whose pairings, added in observation order, pass the joint gate at each step (the rule of
    branch and bound, which extends a hypothesis one observation at a time); the most pairings, then
    the least joint NIS."""
    n = len(pb["zs"])
    opts = [[None] + [j for j in pb["cands"][a] if pb["d2s"][a][j] <= pb["gate"]] for a in range(n)]
    best = None
    for hyp in itertools.product(*opts):
        js = [j for j in hyp if j is not None]
        if len(js) != len(set(js)):
            continue
        ok, k = True, 0
        for a in range(n):
            if hyp[a] is not None:
                k += 1
                pre = list(hyp[:a + 1]) + [None] * (n - a - 1)
                ok = ok and _joint_nis(pb, cov, pre) <= backend.chi2_2k(p, k)
        if not ok:
            continue
        key = (-len(js), _joint_nis(pb, cov, hyp))
        if best is None or key < best[0]:
            best = (key, hyp)
    return best[1]


def test_jcbb_matches_brute_force():
    """Random frames: landmark ids that are not column numbers, each observation with its own
    candidates, and a joint covariance with pose-landmark and landmark-landmark correlations."""
    rng = np.random.default_rng(11)
    slam = backend.Slam(backend.Params(assoc="unknown", joint=True))
    checked = 0
    for _ in range(60):
        m, n = int(rng.integers(2, 5)), int(rng.integers(1, 4))
        ids = sorted(rng.choice(40, m, replace=False).tolist())
        lms = [np.array([3.0, 0.0]) + rng.normal(0, 0.3, 2) for _ in range(m)]
        cur = np.array([0.0, 0.0, rng.normal(0, 0.02)])
        R = np.diag([0.1 ** 2, 0.03 ** 2])
        zs = []
        for _ in range(n):
            h, _ = backend.predict_rb(np.zeros(3), lms[int(rng.integers(m))])
            zs.append(h + rng.normal(0, [0.1, 0.03]))
        cands = [sorted(rng.choice(ids, int(rng.integers(1, m + 1)), replace=False).tolist()) for _ in range(n)]
        G = rng.normal(0, 0.05, (3 + 2 * m, 3 + 2 * m))   # correlations strong enough to change choices
        pb, cov = _problem(cur, lms, zs, R, [0.05, 0.05, 0.05], 0.1, ids=ids, cands=cands, corr=G @ G.T)
        got_j = _jcbb(slam, pb, cov)
        want = _brute_force(pb, cov)
        assert all(j is None or j in pb["cands"][a] for a, j in enumerate(got_j))
        assert sum(j is not None for j in got_j) == sum(j is not None for j in want)
        assert _joint_nis(pb, cov, got_j) == pytest.approx(_joint_nis(pb, cov, want), rel=1e-9, abs=1e-12)
        checked += sum(j is not None for j in want) >= 2
    assert checked >= 10      # enough cases with two or more pairings


def test_jcbb_rejects_pairings_one_heading_cannot_explain():
    """The heading is uncertain (0.1 rad), the landmarks well known. Two observations, one turned
    +0.08 rad from landmark A, the other -0.08 rad from B: each alone is inside its gate (the heading
    could be off by 0.08), both together are not (one heading error turns both the same way). The
    Hungarian assignment takes both; joint compatibility keeps one."""
    A, B = np.array([3.0, 0.6]), np.array([3.0, -0.6])
    R = np.diag([0.02 ** 2, 0.005 ** 2])
    za = backend.predict_rb(np.zeros(3), A)[0] + [0.0, 0.08]
    zb = backend.predict_rb(np.zeros(3), B)[0] + [0.0, -0.08]
    pb, cov = _problem(np.zeros(3), [A, B], [za, zb], R, [0.01, 0.01, 0.1], 0.01)
    assert pb["d2s"][0][0] < pb["gate"] and pb["d2s"][1][1] < pb["gate"]
    assert _joint_nis(pb, cov, [0, 1]) > backend.chi2_2k(0.99, 2)
    slam = backend.Slam(backend.Params(assoc="unknown", joint=True))
    assert sum(j is not None for j in _jcbb(slam, pb, cov)) == 1
    cost = np.full((2, 4), 1e9)
    for a in range(2):
        for j in range(2):
            if pb["d2s"][a][j] <= pb["gate"]:
                cost[a, j] = pb["d2s"][a][j]
        cost[a, 2 + a] = pb["gate"]
    assert backend.hungarian(cost) == [0, 1]


def _two_landmarks(offset, sigma):
    """An iSAM2 with one pose and two landmarks of a class, each seen once from it, `offset` m
    apart, range and bearing sigmas `sigma` (m, rad/3)."""
    isam = gtsam.ISAM2()
    g, v = gtsam.NonlinearFactorGraph(), gtsam.Values()
    g.add(gtsam.PriorFactorPose2(X(0), gtsam.Pose2(), gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-3, 1e-3, 1e-4]))))
    v.insert(X(0), gtsam.Pose2())
    noise = gtsam.noiseModel.Diagonal.Sigmas(np.array([sigma / 3, sigma]))
    for j, y in enumerate((0.0, offset)):
        p = np.array([3.0, y])
        h, _ = backend.predict_rb(np.zeros(3), p)
        g.add(gtsam.BearingRangeFactor2D(X(0), L(j), gtsam.Rot2(h[1]), h[0], noise))
        v.insert(L(j), gtsam.Point2(*p))
    isam.update(g, v)
    return isam


@pytest.mark.parametrize("offset,sigma,co_seen,merged", [
    (0.05, 0.1, set(), True),           # inside the gate, never seen together: one landmark
    (0.05, 0.1, {(0, 1)}, False),        # seen in one frame: two landmarks, however close
    (0.6, 0.1, set(), False),            # 0.6 m apart with 0.1 m sigmas: two landmarks
])
def test_merge_of_duplicates(offset, sigma, co_seen, merged):
    isam = _two_landmarks(offset, sigma)
    slam = backend.Slam(backend.Params(assoc="unknown", merge_every=1))
    by_class, merged_into, st = {"post": [0, 1]}, {}, {"marginal_calls": 0}
    fs = slam._merge(isam, by_class, merged_into, set(co_seen), backend.chi2_2dof(0.99), st)
    assert (merged_into == {1: 0}) == merged
    assert len(fs) == int(merged) and by_class["post"] == ([0] if merged else [0, 1])
    if merged:          # the factor ties the two: after it, one point
        g = gtsam.NonlinearFactorGraph()
        g.add(fs[0])
        isam.update(g, gtsam.Values())
        a, b = isam.calculateEstimatePoint2(L(0)), isam.calculateEstimatePoint2(L(1))
        assert np.linalg.norm(np.asarray(a) - np.asarray(b)) < 0.005


def test_exclusion_leaves_an_observation_ambiguous_while_its_landmark_is_free():
    """Beyond A's association gate but inside its new-landmark gate, with A taken by no other
    observation of the frame: nothing says this is another landmark, and it stays dropped."""
    A = np.array([3.0, 0.1])
    cov = np.diag([0.15 ** 2, 0.04 ** 2])
    p1 = np.array([0.05, 0.0, 0.0])
    z = _obs(p1, A, cov)
    z.range_m += 0.76                                 # d2 about 13: between chi2_2(0.99) and chi2_2(0.9999)
    ds = Dataset(name="free", steps=[
        Step(t=0, seq=0, truth=np.zeros(3), obs=[_obs(np.zeros(3), A, cov)]),
        Step(t=1, seq=1, odom=p1.copy(), odom_cov=np.diag([1e-6] * 3), truth=p1, obs=[z])])
    res = backend.Slam(backend.Params(assoc="unknown", exclusion=True)).run(ds)
    assert len(res.lms) == 1 and res.stats["dropped_ambiguous"] == 1 and res.stats["new_by_exclusion"] == 0


def test_a_duplicate_is_merged_and_reported_once():
    """The odometry claims 0.3 m (sigma 0.3 m) that the robot did not drive; with a candidate radius
    of 5 cm the next view of A is no candidate and starts a second landmark. Its difference from the
    first is inside the gate and the two were never seen in one frame: merged, the run reports one
    landmark, every observation on it, and the equality pulls the pose back to where it was."""
    A = np.array([3.0, 0.0])
    cov = np.diag([0.01 ** 2, 0.003 ** 2])
    z = _obs(np.zeros(3), A, cov)
    steps = [Step(t=0, seq=0, truth=np.zeros(3), obs=[z]),
             Step(t=1, seq=1, odom=np.array([0.3, 0.0, 0.0]), odom_cov=np.diag([0.3 ** 2, 1e-6, 1e-6]),
                  truth=np.zeros(3), obs=[_obs(np.zeros(3), A, cov)]),
             Step(t=2, seq=2, odom=np.zeros(3), odom_cov=np.diag([1e-6] * 3), truth=np.zeros(3),
                  obs=[_obs(np.zeros(3), A, cov)])]
    ds = Dataset(name="duplicate", steps=steps, truth_landmarks={0: (*A, "post")})
    kept = backend.Slam(backend.Params(assoc="unknown", cand_radius=0.05)).run(ds)
    assert len(kept.lms) == 2
    res = backend.Slam(backend.Params(assoc="unknown", cand_radius=0.05, merge_every=1)).run(ds)
    assert res.stats["merged_landmarks"] == 1 and res.stats["new_landmarks"] == 2
    assert len(res.lms) == 1 and res.lm_keys == [L(0)] and [j for (_, _, j) in res.assoc] == [0, 0, 0]
    assert np.allclose(res.lms[0], A, atol=1e-3) and np.allclose(res.poses[:, 0], 0.0, atol=2e-3)
    m = metrics.evaluate(ds, res)
    assert m["association_errors"] == 0 and m["anees_landmarks_joint"] is not None


def _drive(views, odom=(0.05, 0.0, 0.0)):
    """Steps with the given observations (list per step) from poses odom apart, truth = odometry."""
    steps, pose = [], np.zeros(3)
    for k, obs in enumerate(views):
        if k:
            pose = pose + np.array(odom)
        steps.append(Step(t=k, seq=k, odom=None if k == 0 else np.array(odom, float),
                          odom_cov=None if k == 0 else np.diag([1e-6] * 3), truth=pose.copy(),
                          obs=[_obs(pose, lm, np.diag([0.02 ** 2, 0.005 ** 2])) for lm in obs]))
    return Dataset(name="buffer", steps=steps)


def test_candidate_buffer_starts_a_landmark_from_agreeing_views_only():
    """init_views 2: a blob seen once (clutter) never becomes a landmark and is counted; a post seen
    twice does, at the mean of its views, and both views are its observations (the first at its own
    step); two views in one step do not confirm each other."""
    A, C, D = np.array([3.0, 0.5]), np.array([2.0, -1.0]), np.array([4.0, 2.0])
    ds = _drive([[A, C], [A], [D, D + [0.01, 0.0]], []])
    res = backend.Slam(backend.Params(assoc="unknown", init_views=2)).run(ds)
    assert len(res.lms) == 1 and np.allclose(res.lms[0], A, atol=1e-3)
    assert [(k, j) for (k, _, j) in res.assoc] == [(0, 0), (1, 0)]
    assert res.stats["dropped_unconfirmed"] == 3       # C once, D twice in one step
    at_once = backend.Slam(backend.Params(assoc="unknown")).run(ds)
    assert len(at_once.lms) == 4 and at_once.stats["dropped_unconfirmed"] == 0   # D twice, as two


def test_candidate_buffer_forgets_a_view_after_its_window():
    A = np.array([3.0, 0.5])
    gap = [[A]] + [[]] * 6 + [[A], [A]]
    ds = _drive(gap, odom=(0.0, 0.0, 0.0))
    res = backend.Slam(backend.Params(assoc="unknown", init_views=2, init_window=5)).run(ds)
    assert [k for (k, _, _) in res.assoc] == [7, 8] and res.stats["dropped_unconfirmed"] == 1
    res = backend.Slam(backend.Params(assoc="unknown", init_views=2, init_window=10)).run(ds)
    assert [k for (k, _, _) in res.assoc] == [0, 7, 8] and res.stats["dropped_unconfirmed"] == 0


def test_views_that_wait_in_the_buffer_still_count_as_seen_together():
    """A and B are seen together at step 0; A is confirmed at step 1, B only at step 3 from its step-0
    view and a new one. Their step-0 views make them landmarks seen in one frame, which merging must
    never join, although no later step sees both."""
    A, B = np.array([3.0, 0.5]), np.array([3.0, -0.5])
    ds = _drive([[A, B], [A], [], [B], [A]], odom=(0.0, 0.0, 0.0))
    got = []

    class Spy(backend.Slam):
        def _merge(self, isam, by_class, merged_into, co_seen, gate, st):
            got.append(set(co_seen))
            return super()._merge(isam, by_class, merged_into, co_seen, gate, st)

    res = Spy(backend.Params(assoc="unknown", init_views=2, merge_every=1)).run(ds)
    assert len(res.lms) == 2 and [(k, j) for (k, _, j) in res.assoc] == [(0, 0), (1, 0), (0, 1), (3, 1), (4, 0)]
    assert (0, 1) in got[-1]


def test_batch_reassociation_mends_a_swapped_frame_and_merges_a_duplicate():
    """Two posts 0.8 m apart at 3 m, both seen from six poses along x with precise odometry. The
    pairings handed to the re-association are wrong in two ways: frame 3's two observations are
    swapped, and frame 5's view of A went to a third landmark (a duplicate of A). The batch solve of
    those pairings is left with the swapped views' residuals (landmark 0 holds A's views and frame 3's
    view of B);
    re-paired at that estimate, the passes end with every observation of a post on one landmark (A's
    on the undistorted duplicate: landmark 0 is left with none and removed), and the map within 1 cm."""
    A, B = np.array([3.0, 0.4]), np.array([3.0, -0.4])
    cov = np.diag([0.05 ** 2, 0.01 ** 2])
    slam = backend.Slam(backend.Params(assoc="unknown", robust="cauchy", huber_k=2.3, reassoc=10))
    base = [gtsam.PriorFactorPose2(X(0), gtsam.Pose2(), gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-3, 1e-3, 1e-4])))]
    graph = gtsam.NonlinearFactorGraph()
    graph.add(base[0])
    v = gtsam.Values()
    frames, assoc = [], []
    odo = gtsam.noiseModel.Diagonal.Sigmas(np.array([1e-3, 1e-3, 1e-3]))
    for i in range(6):
        pose = np.array([0.1 * i, 0.0, 0.0])
        v.insert(X(i), gtsam.Pose2(*pose))
        if i:
            f = gtsam.BetweenFactorPose2(X(i - 1), X(i), gtsam.Pose2(0.1, 0.0, 0.0), odo)
            base.append(f)
            graph.add(f)
        za, zb = _obs(pose, A, cov), _obs(pose, B, cov)
        frames.append((i, [za, zb], [cov, cov]))
        ja, jb = {3: (1, 0), 5: (2, 1)}.get(i, (0, 1))
        for o, j in ((za, ja), (zb, jb)):
            assoc.append((i, o, j))
            graph.add(gtsam.BearingRangeFactor2D(X(i), L(j), gtsam.Rot2(o.bearing_rad), o.range_m, slam._obs_noise(cov)))
    for j, p in enumerate((A, B, A + [0.05, 0.0])):
        v.insert(L(j), gtsam.Point2(*p))
    est = gtsam.LevenbergMarquardtOptimizer(graph, v).optimize()
    st = {}
    graph2, est2, assoc2, removed = slam._reassociate(frames, base, est, graph, assoc, ["post"] * 3, {},
                                                      backend.chi2_2dof(0.99), st)
    post = {id(o): k % 2 for k, (_, o, _) in enumerate(assoc)}      # 0: A, 1: B
    lm_of = {p_: {j for (_, o, j) in assoc2 if post[id(o)] == p_} for p_ in (0, 1)}
    assert len(assoc2) == 12 and all(len(js) == 1 for js in lm_of.values())   # each post on one landmark
    ja, jb = lm_of[0].pop(), lm_of[1].pop()
    assert ja != jb and removed == {0, 1, 2} - {ja, jb} and len(removed) == 1
    assert st["reassoc_changed"][-1] == 0 and len(st["reassoc_changed"]) >= 2
    assert np.allclose(est2.atPoint2(L(ja)), A, atol=0.01) and np.allclose(est2.atPoint2(L(jb)), B, atol=0.01)
    assert graph2.size() == len(base) + 12
    # the wrong pairings leave a cost the Cauchy kernel caps (about 27); the mended ones none
    assert graph.error(est) > 10.0 and graph2.error(est2) < 1e-6


def test_reassociation_merges_a_duplicate_in_a_run():
    """The drive of the duplicate test above, with --reassoc instead of --merge-every: one landmark,
    every observation on it, the pose pulled back."""
    A = np.array([3.0, 0.0])
    cov = np.diag([0.01 ** 2, 0.003 ** 2])
    steps = [Step(t=0, seq=0, truth=np.zeros(3), obs=[_obs(np.zeros(3), A, cov)]),
             Step(t=1, seq=1, odom=np.array([0.3, 0.0, 0.0]), odom_cov=np.diag([0.3 ** 2, 1e-6, 1e-6]),
                  truth=np.zeros(3), obs=[_obs(np.zeros(3), A, cov)]),
             Step(t=2, seq=2, odom=np.zeros(3), odom_cov=np.diag([1e-6] * 3), truth=np.zeros(3),
                  obs=[_obs(np.zeros(3), A, cov)])]
    ds = Dataset(name="duplicate", steps=steps, truth_landmarks={0: (*A, "post")})
    res = backend.Slam(backend.Params(assoc="unknown", cand_radius=0.05, reassoc=5)).run(ds)
    assert res.stats["new_landmarks"] == 2 and res.stats["reassoc_merges"] == 1
    assert len(res.lms) == 1 and [j for (_, _, j) in res.assoc] == [0, 0, 0]
    assert np.allclose(res.lms[0], A, atol=1e-3) and np.allclose(res.poses[:, 0], 0.0, atol=2e-3)
    assert metrics.evaluate(ds, res)["association_errors"] == 0
    with pytest.raises(ValueError, match="re-association"):
        backend.Slam(backend.Params(assoc="unknown", reassoc=5, batch=False)).run(ds)
