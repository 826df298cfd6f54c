"""movel/movep programs move as planned (issue 21): every phase and stock boundary a
waypoint, each move at the plan's speed, dwells as sleeps, the program's motion verified
before it is written — and each mode replayed on the emulator, what the controller
recorded measured with the one model of the wire against the block."""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.export import urscript_program
from ruledrobot.export.verify_program import (
    Move,
    ProgramRefused,
    check_path_program,
    measure_motion,
)
from ruledrobot.io.trajectory import write_trajectory
from ruledrobot.robot import load
from ruledrobot.robot.motion.trajectory import Heat, Phase, Trajectory
from ruledrobot.ursim.script.program import parse_call
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan
from tests.support.emulators import smooth_trajectory, start_emulator
from tests.support.rawclient import RawRTDEClient


def _planned(folder, text: str) -> Trajectory:
    """The planned trajectory of job ``text`` with what it cuts (``meta.cut``)."""
    path = folder / "job.toml"
    path.write_text(text)
    res = plan(load_job(path), None, simulate=False)
    traj = res.trajectory
    assert traj is not None and traj.meta.cut is not None
    return traj


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Trajectory:
    """The demo's planned trajectory with what it cuts (``meta.cut``)."""
    return _planned(tmp_path_factory.mktemp("demo"), DEMO_JOB)


def _calls(text: str) -> list:
    body = [ln.strip() for ln in text.splitlines()[1:-1]]
    return [parse_call(ln) for ln in body if ln and not ln.startswith("#")]


def _sample_of(traj: Trajectory, pose: np.ndarray) -> int:
    d = np.abs(traj.tcp - pose).max(axis=1)
    k = int(np.argmin(d))
    assert d[k] < 1e-8, "every linear move goes to a planned TCP pose"
    return k


def _joint_sample_of(traj: Trajectory, q: np.ndarray) -> int:
    d = np.abs(traj.q - q).max(axis=1)
    k = int(np.argmin(d))
    assert d[k] < 1e-8, "every joint move goes to planned joints"
    return k


@pytest.mark.parametrize("mode", ["movel", "movep"])
def test_the_demo_crosses_the_block_at_the_plans_speed(demo: Trajectory, mode: str) -> None:
    """The old export crossed the block in one movel at the average speed of lead-in, cut
    and lead-out (v = 0.01109 m/s where the plan's TCP moves at 9.70 mm/s): now the wire's
    entry and exit are waypoints and every move in the block keeps the plan's TCP speed
    over it within 2 %."""
    text = urscript_program(demo, mode=mode)
    (a, b), = demo.meta.in_stock
    calls = _calls(text)
    first = [c.name for c in calls].index("movej")  # the move to the start
    joint = {_joint_sample_of(demo, np.array(c.args[0])) for c in calls[first + 1 :]
             if c.name == "movej"}  # fmt: skip
    moves = [c for c in calls if c.name == mode]
    ks = [_sample_of(demo, np.array(c.args[0].values)) for c in moves]
    assert a in ks and b in ks
    for ph in demo.meta.phases:  # free air (the approach) is movej through the plan's joints
        assert ph.start in ks or ph.start in joint or ph.start == 0
    p = demo.tcp[:, :3]
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    speed = step / np.diff(demo.t)
    prev = ks[0]
    inside = 0
    for c, k in zip(moves[1:], ks[1:], strict=True):
        if a <= prev < k <= b:
            inside += 1
            planned = step[prev:k].sum() / (demo.t[k] - demo.t[prev])
            v = c.kwargs["v"]
            assert v == pytest.approx(planned, rel=0.003)  # chord vs arc of the plan
            assert speed[prev:k].max() <= 1.02 * speed[prev:k].min() + 2e-4
        prev = k
    assert inside >= 1
    assert "# verified" in text


def _preheat_trajectory() -> Trajectory:
    """One second still with the heat on (the pre-heat), then a move; heat on to the end."""
    base = smooth_trajectory(duration=1.2)
    hold = 500
    q = np.vstack([np.repeat(base.q[:1], hold, axis=0), base.q])
    t = 0.002 * np.arange(q.shape[0])
    n = t.size
    return Trajectory.from_joints(
        t, q, load("ur5e"), phases=(Phase("preheat", 0, hold), Phase("cut", hold, n)),
        heat=Heat("standard", 0, windows=((0, n),), preheat=1.0),
    )  # fmt: skip


@pytest.mark.parametrize("mode", ["movel", "movep"])
def test_a_preheat_is_a_sleep_after_the_heat_never_a_zero_length_move(mode: str) -> None:
    """The old movep export of the part switched the heat on and made a zero-length
    ``movep(..., v=0.0001)``: no sleep, no pre-heat."""
    traj = _preheat_trajectory()
    calls = _calls(urscript_program(traj, mode=mode))
    names = [c.name for c in calls]
    on = names.index("set_standard_digital_out", names.index("movej"))
    assert calls[on].args[1] is True
    assert names[on + 1] == "sleep"
    assert calls[on + 1].args[0] == pytest.approx(1.0, abs=0.003)
    where = traj.tcp[0]
    for c in calls[on + 2 :]:
        if c.name == mode:
            target = np.array(c.args[0].values)
            assert np.abs(target[:3] - where[:3]).max() > 1e-6 or \
                np.abs(target[3:] - where[3:]).max() > 1e-6  # fmt: skip
            where = target
    assert names[-2:] == ["set_standard_digital_out", "textmsg"]


def test_a_program_that_would_not_cut_as_planned_is_refused(demo: Trajectory, tmp_path) -> None:
    """The old program (one move from the lead-in to the end at the average speed) is
    measured too fast and off the wire; a coarse decimation against a tight wire tolerance
    is refused with the numbers, the CLI exits 1 (a check fails) and writes nothing."""
    names = {p.name: p for p in demo.meta.phases}
    i, k = names["lead_in"].start, demo.n - 1
    arc = np.linalg.norm(np.diff(demo.tcp[i : k + 1, :3], axis=0), axis=1).sum()
    old = [Move(demo.tcp[i], 1.0, 0.05, 0.0),
           Move(demo.tcp[k], 1.0, arc / (demo.t[k] - demo.t[i]), 0.0)]  # fmt: skip
    check = check_path_program(demo, old)
    (feed,) = check.feeds
    assert not feed.max_ok and feed.highest > 1.05 * feed.speed  # 10.8 mm/s against 10
    assert any("above 10.50 mm/s" in f for f in check.failures())
    with pytest.raises(ProgramRefused, match=r"movel program refused: .*beyond 0.10 mm"):
        urscript_program(demo, mode="movel", tolerance=0.01, wire_tolerance=0.0001)
    csv = write_trajectory(tmp_path / "cut.csv", demo)
    out = tmp_path / "cut.script"
    args = ["export", str(csv), "--out", str(out), "--mode", "movel", "--tolerance", "0.01",
            "--wire-tolerance", "0.0001"]  # fmt: skip
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 1, res.output
    assert "refused" in res.output and "beyond 0.10 mm" in res.output
    assert not out.exists()


def _record(host: str, emu, program: str, timeout: float) -> tuple[np.ndarray, np.ndarray]:
    """Send ``program`` to the script port and record (timestamp, actual_q) at 500 Hz
    until it ends; times from the controller's "ruledrobot: cut" message."""
    ts, qs = [], []
    with RawRTDEClient(host) as rtde:
        assert rtde.negotiate()
        rtde.setup_outputs(["timestamp", "actual_q", "runtime_state"], 500.0)
        assert rtde.start()
        with socket.create_connection((host, emu.ports["script"])) as s:
            s.sendall(program.encode())
        played = False
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            d = rtde.read_data()
            ts.append(d["timestamp"])
            qs.append(d["actual_q"])
            played = played or d["runtime_state"] == 2
            if played and d["runtime_state"] == 1:
                break
        else:
            pytest.fail("the program did not end in time")
    t0 = next(e[0] for e in emu.events if "ruledrobot: cut" in e[2])
    t, q = np.asarray(ts), np.asarray(qs, dtype=float)
    keep = t >= t0 - 1e-9
    return t[keep] - t0, q[keep]


@pytest.mark.parametrize("mode", ["servoj", "movel", "movep"])
def test_each_mode_cuts_at_the_plans_feed_on_the_emulator(short_demo: Trajectory, mode: str,
                                                          request) -> None:  # fmt: skip
    """The demo's cut (lead-in to lead-out; the narrowed demo at 25 mm/s, 4.7 s of motion:
    ``short_demo`` in tests/export/conftest.py) exported in each mode, run by the emulator
    from its script port; the joints it recorded, through the one model of the wire
    against the block: the feed within the plan's tolerance, the wire on the plan's."""
    names = {p.name: p for p in short_demo.meta.phases}
    cut = short_demo.sliced(names["lead_in"].start, names["lead_out"].stop)
    program = urscript_program(cut, mode=mode)
    emu = start_emulator(request.node.nodeid, model="ur5e", q0=cut.q[0])
    try:
        t, q = _record(emu.host, emu, program, timeout=cut.duration + 30.0)
    finally:
        emu.close()
    m = measure_motion(cut, t, q)
    print(f"{mode}: {m.summary()}")
    assert m.feeds and all(f.max_ok and f.min_ok for f in m.feeds), m.failures()
    assert m.deviation_ok, m.failures()
    assert m.duration == pytest.approx(cut.duration, abs=1.0)
