"""``--resume N`` against the emulator: continue where the arm rests, or — with the arm
elsewhere and N inside the stock — move to the lead-in and replay the kerf through N;
refuse when the wire is in the stock somewhere else."""

from __future__ import annotations

import numpy as np

from ruledrobot.export import run_trajectory
from ruledrobot.ursim import Emulator

from .test_run_plan import IN_STOCK, cut_trajectory

FAST = {"approach_speed": 1.0, "approach_acceleration": 4.0, "lookahead": 0.05}


def test_resume_continues_from_where_the_arm_stopped_in_the_stock(emulator: Emulator) -> None:
    traj = cut_trajectory()
    fired: list[int] = []

    def progress(done: int, total: int) -> None:
        if not fired and done >= 450:  # inside the stock (250..749), phase cut
            fired.append(done)
            emulator.protective_stop("injected in the cut")

    res = run_trajectory(traj, emulator.host, progress=progress, **FAST)
    assert res.status == "protective_stop", res
    assert res.stop is not None and res.stop.in_stock and res.stop.phase == "cut"
    assert IN_STOCK[0] < res.stop_index < IN_STOCK[1]
    emulator.clear_faults()
    res2 = run_trajectory(traj, emulator.host, start_index=res.resume_index, **FAST)
    assert res2.status == "completed", res2
    assert res2.entry is not None and res2.entry.kind == "continue"
    assert abs(res2.start_index - res.stop_index) <= 10 and res2.approach_distance < 0.005
    rec = res2.actual
    assert rec is not None
    np.testing.assert_allclose(rec.q[0], traj.q[res2.start_index], atol=2e-3)
    np.testing.assert_allclose(emulator.actual_q, traj.q[-1], atol=1e-4)


def test_resume_with_the_arm_elsewhere_replays_the_kerf(emulator: Emulator) -> None:
    traj = cut_trajectory()
    elsewhere = traj.q[0] - 0.15
    emulator.reset(elsewhere)
    N = 600  # inside the stock
    res = run_trajectory(traj, emulator.host, start_index=N, **FAST)
    assert res.status == "completed", res
    e = res.entry
    assert e is not None and e.kind == "replay" and e.sample == 150 == res.start_index
    assert "replay the kerf" in e.note
    rec = res.actual
    assert rec is not None
    # the moveJ ended at the start of the lead-in (outside the stock), the recording —
    # from the first streamed sample — follows the plan from there through N and on
    np.testing.assert_allclose(rec.q[0], traj.q[150], atol=2e-3)
    assert np.min(np.max(np.abs(rec.q - traj.q[IN_STOCK[0]]), axis=1)) < 2e-3  # stock entry
    assert np.min(np.max(np.abs(rec.q - traj.q[N]), axis=1)) < 2e-3
    assert res.max_deviation < 0.01
    np.testing.assert_allclose(emulator.actual_q, traj.q[-1], atol=1e-4)


def test_resume_refused_when_the_wire_is_in_the_stock_elsewhere(emulator: Emulator) -> None:
    traj = cut_trajectory()
    emulator.reset(traj.q[300])
    res = run_trajectory(traj, emulator.host, start_index=900)
    assert res.status == "refused" and not res.moved, res
    assert [c.name for c in res.verdict.failed] == ["entry"]
    assert "--resume 300" in res.message
    assert emulator.stats()["programs_received"] == 0
    np.testing.assert_allclose(emulator.actual_q, traj.q[300], atol=0)
