"""Issue 33's proof from closed forms, on small plans (a few seconds each, no MuJoCo).

The cut face is computed here from the trajectory's TCP columns and the documented
formula (docs/kerf.md), not by the planner's functions: the wire is the TCP's z axis
through its origin (the wire's midpoint), its chord ends the points where it crosses the
block's faces ``y = -0.1`` (root) and ``y = 0.1`` (tip), their speeds across the wire
central differences in time, the kerf ``w = kerf_base + kerf_gain (p - p0) / v`` with
``p`` the trajectory's ``heat_power``; the face is the chord end moved ``w / 2`` towards
the part (down: the part is below the plane ``z = Z0``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import plan_outcome

from .panel import FEED, KERF, MATERIAL, Z0, write_corner, write_panel

KB, KG, P0 = MATERIAL["kerf_base"], MATERIAL["kerf_gain"], MATERIAL["power_threshold"]


def _plan(job_path):
    plan = make_plan(load_job(job_path))
    assert plan.trajectory is not None, plan.reasons
    return plan


def _ends(traj):
    """Per sample the chord ends (M, 2, 3) at y = -0.1, +0.1, their speeds across the wire
    (M, 2), and the samples of the cut phase with the wire across the whole block."""
    p, z = traj.tcp[:, :3], Rotation.from_rotvec(np.array(traj.tcp[:, 3:])).as_matrix()[:, :, 2]
    ends = np.stack([p + ((y - p[:, 1]) / z[:, 1])[:, None] * z for y in (-0.1, 0.1)], axis=1)
    v = np.gradient(ends, traj.t, axis=0)
    v -= np.einsum("mki,mi->mk", v, z)[..., None] * z[:, None, :]
    cut = np.zeros(traj.n, dtype=bool)
    for ph in traj.meta.phases:
        cut[ph.start:ph.stop] |= ph.name == "cut"
    across = cut & (np.abs(ends[..., 0] - 0.5) < 0.03 - 1e-3).all(axis=1)
    return ends, np.linalg.norm(v, axis=-1), across


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    return _plan(write_panel(tmp_path_factory.mktemp("panel")))


def test_tapered_panel_face_within_0_02_mm_at_both_ends(panel):
    traj = panel.trajectory
    ends, v, across = _ends(traj)
    assert across.sum() > 500
    p = traj.heat_power[across]
    assert np.allclose(p, P0 + (KERF - KB) * FEED / KG)  # on_off: the supply set for the kerf
    w = KB + KG * (p[:, None] - P0) / v[across]
    face = ends[across, :, 2] - 0.5 * w
    assert np.abs(face - Z0).max() < 2e-5  # both ends: within 0.02 mm of the plane
    # the ends got their own offsets: the tip moves 0.8 times as fast and melts wider
    lift = np.median(ends[across, :, 2] - Z0, axis=0)
    tip_kerf = KB + (KERF - KB) / 0.8
    np.testing.assert_allclose(lift, [KERF / 2, tip_kerf / 2], atol=5e-6)
    assert np.median(v[across, 1] / v[across, 0]) == pytest.approx(0.8, abs=2e-3)
    fe = traj.face_errors()["cut"]
    assert fe.ok and fe.worst < 2e-5


def test_constant_kerf_heat_power_follows_the_formula(tmp_path):
    lag = 0.1
    heat = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 200.0, '
            f"lag = {lag}, preheat = 0.5 }}")
    traj = _plan(write_panel(tmp_path, heat)).trajectory
    assert (traj.meta.heat.mode, traj.meta.heat.full_scale, traj.meta.heat.lag) == (
        "constant_kerf", 200.0, lag)
    _, v, across = _ends(traj)
    desired = P0 + (KERF - KB) * v.max(axis=1) / KG  # the reference: the faster end
    # the set-point leads by the lag: at t it is the power the motion asks at t + lag
    k = np.flatnonzero(across)
    k = k[(traj.t[k] + lag <= traj.t[k[-1]])]
    led = np.interp(traj.t[k] + lag, traj.t, desired)
    np.testing.assert_allclose(traj.heat_power[k], led, rtol=0.01)
    assert traj.heat_power.max() <= 200.0
    assert traj.face_errors()["cut"].ok


@pytest.mark.parametrize("mode, ok", [("constant", False), ("constant_kerf", True)])
def test_corner_stop_burns_with_constant_heat_only(tmp_path, mode, ok):
    power = ", power = 50.0" if mode == "constant" else ""
    job = write_corner(tmp_path, f'heat = {{ output = "analog:0", mode = "{mode}", '
                                 f"full_scale = 200.0{power} }}")  # fmt: skip
    plan = _plan(job)
    assert plan.motion.corner_stop.any()  # the wire stops in the block
    _, verdict = plan_outcome(plan, None)
    check = verdict["face_error"]
    assert check.gating and check.ok is ok
    assert not verdict["feed_min"].gating  # the feed window: information, the time law's target
    if not ok:
        assert check.detail.startswith("burn at t = ")
        assert check.value == float("inf")


def test_sidecar_keeps_the_face_and_the_material(panel, tmp_path):
    """The face target and the material survive the sidecar: a reader of the trajectory
    computes the same face_error as the plan (its heat power given, as a run records it)."""
    from ruledrobot.io.trajectory import meta_from_dict, meta_to_dict

    traj = panel.trajectory
    meta = meta_from_dict(meta_to_dict(traj.meta))
    assert meta.cut.material == traj.meta.cut.material
    back = type(traj)(traj.t, traj.q, traj.tcp, meta)
    a = traj.face_errors()["cut"]
    b = back.face_errors(heat_power=traj.heat_power)["cut"]
    assert b.worst == pytest.approx(a.worst, rel=1e-9) and b.at == a.at
