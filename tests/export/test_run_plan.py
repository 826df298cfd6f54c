"""Where a run enters the trajectory (continue / replay the kerf / approach / refuse), the
recording's file names, the stop place: pure computation, no controller."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ruledrobot.export.run_plan import (
    entry_sample,
    moveJ_time,
    plan_entry,
    recording_path_for,
    stop_place,
)
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Phase, Trajectory
from ruledrobot.ursim import DEFAULT_Q

#: the phases of :func:`cut_trajectory` (sample ranges) and its one in-stock run
PHASES = (("approach", 0, 150), ("lead_in", 150, 250), ("cut", 250, 750),
          ("lead_out", 750, 850), ("retract", 850, 1001))  # fmt: skip
IN_STOCK = (250, 750)


def cut_trajectory(model: str = "ur5e") -> Trajectory:
    """2 s, 1001 samples, every joint moving monotonically (no pose visited twice), with
    the phases of a cut and the wire inside the stock on samples 250..749."""
    t = np.arange(1001) * 0.002
    s = 0.5 * (1 - np.cos(np.pi * t / t[-1]))
    q = np.asarray(DEFAULT_Q) + np.array([0.3, -0.2, 0.25, 0.2, 0.3, -0.3]) * s[:, None]
    phases = tuple(Phase(*p) for p in PHASES)
    return Trajectory.from_joints(t, q, load(model), phases=phases, in_stock=(IN_STOCK,),
                                  source="synthetic cut")  # fmt: skip


def test_movej_time_trapezoid_and_triangle() -> None:
    assert moveJ_time(1.0, 0.25, 0.5) == pytest.approx(1.0 / 0.25 + 0.25 / 0.5)
    assert moveJ_time(0.01, 0.25, 0.5) == pytest.approx(2 * np.sqrt(0.01 / 0.5))
    assert moveJ_time(0.0, 0.25, 0.5) == 0.0


def test_continue_when_the_arm_is_at_a_sample_near_the_requested_one() -> None:
    traj = cut_trajectory()
    e = plan_entry(traj, traj.q[600] + 0.001, 600)
    assert e.kind == "continue" and e.ok and abs(e.sample - 600) <= 4
    assert e.distance <= 0.005 and e.replay_time == 0.0
    # the arm stopped a little further than the requested sample: continue where it is
    e = plan_entry(traj, traj.q[640], 600)
    assert e.kind == "continue" and e.sample == 640 and "requested 600" in e.note
    # a fresh run with the arm at the first sample
    e = plan_entry(traj, traj.q[0], 0)
    assert e.kind == "continue" and e.sample == 0 and e.distance == 0.0


def test_a_path_that_comes_back_through_its_poses_continues_where_the_arm_stopped() -> None:
    """There and back (q0 + A sin^2(pi t / T)): sample 207's pose is sample 393's too.
    The arm came to rest a little past 207: continue there, never on the way back (that
    would skip 186 samples: a stretch of kerf never cut)."""
    t = np.arange(601) * 0.002
    q = np.asarray(DEFAULT_Q) + np.array([0.09, -0.07, 0.09, 0.07, 0.09, -0.09]) * (
        np.sin(np.pi * t / t[-1])[:, None] ** 2)  # fmt: skip
    for rest in (207, 209, 212):
        back = 600 - rest  # the same pose on the way back
        np.testing.assert_allclose(q[back], q[rest], atol=1e-12)
        # the arm 0.1 mrad off sample `rest`, and the way back passing exactly there
        arm = q[rest] + 1e-4
        qq = q.copy()
        qq[back] = arm
        traj = Trajectory.from_joints(t, qq, load("ur5e"), source="there and back")
        e = plan_entry(traj, arm, 207)
        assert e.kind == "continue" and e.sample == rest, (rest, e.sample)


def test_replay_from_the_lead_in_when_the_arm_is_elsewhere_and_the_sample_in_the_stock() -> None:
    traj = cut_trajectory()
    elsewhere = traj.q[0] - 0.2
    e = plan_entry(traj, elsewhere, 600)
    assert e.kind == "replay" and e.ok
    assert e.sample == 150  # the start of the lead-in before the in-stock run 250..749
    assert e.replay_time == pytest.approx(traj.t[600] - traj.t[150])
    assert "replay the kerf" in e.note and "150" in e.note
    d = np.abs(traj.q[150] - elsewhere)
    assert e.distance == pytest.approx(d.max()) and e.joint == int(np.argmax(d)) + 1
    assert e.approach_time == pytest.approx(moveJ_time(d.max(), 0.25, 0.5))
    # without a lead-in phase: the last sample before the wire entered the stock
    bare = Trajectory(traj.t, traj.q, traj.tcp, traj.meta.replace(phases=()))
    assert entry_sample(bare, IN_STOCK[0]) == IN_STOCK[0] - 1
    assert plan_entry(bare, elsewhere, 600).sample == IN_STOCK[0] - 1


def test_approach_when_the_sample_is_outside_the_stock() -> None:
    traj = cut_trajectory()
    e = plan_entry(traj, traj.q[0] - 0.2, 100)
    assert e.kind == "approach" and e.sample == 100 and e.ok
    e = plan_entry(traj, traj.q[0] - 0.2, 800)  # lead-out: outside the stock
    assert e.kind == "approach" and e.sample == 800


def test_refused_when_the_wire_is_in_the_stock_elsewhere() -> None:
    traj = cut_trajectory()
    e = plan_entry(traj, traj.q[300], 900)
    assert e.kind == "refused" and not e.ok and e.check.gating
    assert "--resume 300" in e.check.detail and "inside the stock" in e.check.detail


def test_recordings_never_overwrite_each_other(tmp_path: Path) -> None:
    src = tmp_path / "cut.csv"
    first = recording_path_for(src)
    assert first == tmp_path / "cut.run-001.csv" and first.exists()  # reserved at once
    assert recording_path_for(src) == tmp_path / "cut.run-002.csv"
    (tmp_path / "cut.run-003.json").write_text("{}")  # a sidecar alone also takes the number
    assert recording_path_for(src) == tmp_path / "cut.run-004.csv"
    assert recording_path_for(tmp_path / "cut.run-001.csv") == tmp_path / "cut.run-005.csv"


def test_stop_place_names_phase_and_stock() -> None:
    traj = cut_trajectory()
    p = stop_place(traj, 400)
    assert (p.sample, p.phase, p.in_stock) == (400, "cut", True)
    assert p.time == pytest.approx(0.8)
    assert "inside the stock" in p.describe()
    assert not stop_place(traj, 200).in_stock and stop_place(traj, 200).phase == "lead_in"
