"""The time law's feed bound is continuous along the path (issue 32, "Loops that hold their
feed"), and a path it cannot time within reason is a diagnosed failure, not bad input.

* Where the chord's end changes faces of the block — a synthetic wire turning about an
  axis through the block and rising, so that a chord end crosses a vertical edge and
  then the top face — the bound's jump between neighbouring solver nodes stays below
  :data:`BOUND_JUMP`, the law holds its feed within 1 % through it (98.2 % before), and
  the wire measured by the one model on the timed motion within 2 %.
* Where the joint path kinks (its direction turns 6° at one sample while the wire
  travels 23 % more per joint distance after it, as where a loop's exit slit met the
  loop: the bound jumped there and held the wire to 10.7 of 12 mm/s), the law holds
  its feed within 1 % (0.83 of it before).
* A path that needs hours at the joint limits raises :class:`TimingFailure` naming
  where the time goes and the limit that binds; a job with one fails its plan with the
  ``timing`` check (exit 1, report.json and the printed table), not exit 2.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry.box import Box
from ruledrobot.robot.wire.in_stock import across_speeds, feed_chord, wire_in_stock
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.motion.timing import MAX_SAMPLES, TimingFailure, time_path
from ruledrobot.wirecut.motion.timing.problem import _prepare

DT = 0.002
VL = np.array([2.0, 2.0, 3.0])  # rad/s
AL = np.array([4.0, 4.0, 6.0])  # rad/s²
FEED = 0.012  # m/s
#: largest relative change of the feed bound between neighbouring solver nodes
BOUND_JUMP = 0.01
STOCK = Box(np.zeros(3), np.array([0.2, 0.2, 0.15]))
WIRE = 0.4  # m


def _turning_wire(u: np.ndarray) -> np.ndarray:
    """Wire ends (N, 2, 3) of a wire at 60 mm from the block's vertical axis, tilted 10°
    up along itself, turning 120° about that axis and rising 70 mm (u in [0, 1])."""
    phi = np.radians(-60.0 + 120.0 * u)
    beta = np.radians(10.0)
    mid = np.stack([0.06 * np.cos(phi), 0.06 * np.sin(phi), -0.035 + 0.07 * u], axis=1)
    d = np.stack([-np.sin(phi) * np.cos(beta), np.cos(phi) * np.cos(beta),
                  np.full_like(phi, np.sin(beta))], axis=1)  # fmt: skip
    return np.stack([mid - 0.5 * WIRE * d, mid + 0.5 * WIRE * d], axis=1)


def _faces(ends: np.ndarray) -> np.ndarray:
    """(N, 2) the face (0..5: -x, +x, -y, +y, -z, +z) each chord end lies on."""
    w = wire_in_stock(np.arange(len(ends), dtype=float), ends, STOCK)
    p = w.chord_points() / (0.5 * STOCK.size)
    ax = np.argmax(np.abs(p), axis=-1)
    return 2 * ax + (np.take_along_axis(p, ax[..., None], -1)[..., 0] > 0)


def _bound_jump(prob) -> float:
    """Largest relative change of the path-speed bound of the feed between neighbouring
    solver nodes where it binds anywhere near (finite on both)."""
    b = np.sqrt(prob.x_feed)
    ok = np.isfinite(b[:-1]) & np.isfinite(b[1:])
    return float((np.abs(np.diff(b)) / np.maximum(b[:-1], b[1:]))[ok].max())


def test_the_bound_is_continuous_where_the_chord_end_changes_faces():
    n = 240
    u = np.linspace(0.0, 1.0, n)
    ends = _turning_wire(u)
    faces = _faces(ends)
    # the scenario: a chord end crosses a vertical edge (+x -> +y) and reaches the top face
    assert {tuple(f) for f in faces} >= {(3, 1), (3, 3)} or len({tuple(f) for f in faces}) >= 3
    changes = np.flatnonzero((np.diff(faces, axis=0) != 0).any(axis=1))
    assert changes.size >= 2
    # the one model's speed factor, as the planner computes it (speed_factor)
    s = u.copy()
    sf = np.nan_to_num(across_speeds(s, ends, feed_chord(ends, STOCK, 0.002)), nan=0.0).max(1)
    q = np.stack([np.radians(-60.0 + 120.0 * u), 0.7 * u, 0.2 * np.sin(2.0 * u)], axis=1)
    prob = _prepare(s, q, sf, FEED)
    assert _bound_jump(prob) < BOUND_JUMP
    tp = time_path(s, q, sf, FEED, VL, AL, DT)
    assert tp.within_limits and tp.max_feed_ratio <= 1.0 + 1e-6
    # the law's feed and the one model's on the timed motion hold it across every change
    w = wire_in_stock(tp.t, _turning_wire(np.interp(tp.s_of_t, s, u)), STOCK)
    for c in changes:
        near = np.abs(tp.s_of_t - s[c]) < 0.05
        assert np.abs(tp.feed[near] / FEED - 1.0).max() < 0.01
        assert np.abs(w.feed[near] / FEED - 1.0).max() < 0.02


def _kinked(n: int = 400, jump: float = 1.23, turn_deg: float = 6.0):
    """A 3-joint path (s (n,), q (n, 3)) whose direction turns by ``turn_deg`` at sample
    n/2 and whose joint step shrinks there by ``jump`` while ``s`` (the wire's travel)
    advances evenly: the wire travels ``jump`` times farther per joint distance after."""
    k = n // 2
    a = np.radians(turn_deg)
    d0 = np.array([0.6, 0.8, 0.0])
    d1 = np.array([0.6 * np.cos(a) - 0.8 * np.sin(a), 0.6 * np.sin(a) + 0.8 * np.cos(a), 0.0])
    step = np.r_[np.full(k, 0.002), np.full(n - 1 - k, 0.002 / jump)]
    dirs = np.where((np.arange(n - 1) < k)[:, None], d0, d1)
    q = np.r_[np.zeros((1, 3)), np.cumsum(step[:, None] * dirs, axis=0)] + [0.3, -1.0, 0.5]
    return np.linspace(0.0, 1.0, n), q


def test_a_kink_of_the_joint_path_keeps_the_feed():
    s, q = _kinked()
    sf = np.full(s.size, 0.1)  # m of wire per unit s: 0.1 m in all
    gap = np.diff(s) / np.linalg.norm(np.diff(q, axis=0), axis=1)
    assert gap[250] / gap[150] == pytest.approx(1.23)  # the bound per joint distance jumps
    prob = _prepare(s, q, sf, FEED)
    assert _bound_jump(prob) < BOUND_JUMP
    tp = time_path(s, q, sf, FEED, VL, AL, DT)
    mid = np.abs(tp.s_of_t - 0.5) < 0.45  # all but the start and stop ramps
    # the law's feed (with s(σ) piecewise linear, as before: 0.83 of it at the kink)
    assert np.abs(tp.feed[mid] / FEED - 1.0).max() < 0.01


def test_a_path_that_needs_hours_at_the_joint_limits_is_diagnosed():
    n = 300
    s = np.linspace(0.0, 1.0, n)
    q = np.stack([0.2 * s, -1.0 + 0.1 * s, 0.6 * np.sin(2.0 * np.pi * s)], axis=1)
    al = np.array([4.0, 4.0, 1e-6])  # joint 3 swings back and forth, 1e-6 rad/s²
    with pytest.raises(TimingFailure) as info:
        time_path(s, q, np.full(n, 0.5), FEED, VL, al, DT)
    f = info.value
    assert isinstance(f, ValueError)  # callers that only know bad input still stop
    assert f.reason == "too_long" and f.duration > MAX_SAMPLES * DT
    assert f.binding is not None and (f.binding.kind, f.binding.joint) == ("acceleration", 3)
    assert 0.0 <= f.s_range[0] < f.s_range[1] <= 1.0 and 0.0 < f.share <= 1.0
    msg = str(f)
    assert "MAX_SAMPLES" in msg and "joint 3's acceleration limit" in msg
    assert f"between s = {f.s_range[0]:.6g} and {f.s_range[1]:.6g}" in msg


def test_a_job_whose_cut_needs_hours_fails_its_plan_with_the_timing_check(tmp_path):
    """The demo with an acceleration limit of 1e-9 rad/s²: its cut would take 18 h.  The
    plan fails (exit 1), report.json and the printed table name the pass, the rulings
    where the time goes and the joint limit; no trajectory is written."""
    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB.replace("speed_scale = 1.0", "speed_scale = 1.0\n"
                                    "acceleration = 1e-9"))  # fmt: skip
    out = tmp_path / "out"
    res = CliRunner().invoke(app, ["plan", str(job), "--out", str(out)])
    assert res.exit_code == 1, res.output
    report = json.loads((out / "report.json").read_text())
    assert not report["feasible"] and report["verdict"]["failed"] == ["timing"]
    check = next(c for c in report["verdict"]["checks"] if c["name"] == "timing")
    assert check["value"] == 1 and check["limit"] == 0 and not check["ok"]
    detail = check["detail"]
    assert detail.startswith("pass 'cut': its timed path would last "), detail
    assert " h), " in detail and "% of it over rulings " in detail
    assert "'s acceleration limit (" in detail and "holds the wire to" in detail
    assert detail in report["reasons"]
    assert next(c for c in report["verdict"]["checks"] if c["name"] == "reach")["ok"]
    assert not (out / "trajectory.csv").exists()
    assert "timing" in res.output and "its timed path would last" in res.output
