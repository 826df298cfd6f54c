"""A scheduled wire power on a forwarded run (issue 33), on the embedded emulator: the
controller's analog output follows the plan's heat_power ramp within one control period,
and the run's recording keeps it as its heat_power column."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from ruledrobot.export import run_trajectory
from ruledrobot.export.forward.program import REG_SAMPLE, REG_STATE, State
from ruledrobot.export.heat import HEAT_STEP, servo_levels, written_levels
from ruledrobot.export.settings import SERVO_GAIN, SERVO_LOOKAHEAD
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.robot.motion.trajectory import Heat, Phase, Trajectory
from tests.support.emulators import smooth_trajectory, start_emulator
from tests.support.rawclient import RawRTDEClient

pytest.importorskip("rtde_control")

FULL_SCALE = 100.0  # W/m at 1.0
FIELDS = ("timestamp", f"output_int_register_{REG_SAMPLE}", f"output_int_register_{REG_STATE}",
          "standard_analog_output0")  # fmt: skip


def _ramp_trajectory() -> Trajectory:
    """2.4 s of smooth motion; heat_power 0 for 0.3 s, a ramp to 90 W/m until 1.8 s, held,
    0 from 2.2 s (analog output 0, full scale 100 W/m)."""
    base = smooth_trajectory(duration=2.4, amplitude=(0.12, -0.08, 0.1, 0.0, 0.0, 0.0))
    t, n = base.t, base.n
    power = np.clip((t - 0.3) / 1.5, 0.0, 1.0) * 90.0
    power[t >= 2.2] = 0.0
    heat = Heat("analog", 0, windows=((0, n),), mode="constant", full_scale=FULL_SCALE)
    meta = base.meta.replace(heat=heat, phases=(Phase("cut", 0, n),))
    return Trajectory(t, base.q, base.tcp, meta, power)


def _record(host: str, done: threading.Event, rows: list) -> None:
    client = RawRTDEClient(host)
    try:
        assert client.negotiate()
        assert "NOT_FOUND" not in client.setup_outputs(FIELDS, 500.0)
        assert client.start()
        end = time.monotonic() + 30.0
        while not done.is_set() and time.monotonic() < end:
            d = client.read_data(timeout=2.0)
            rows.append(tuple(d[f] for f in FIELDS))
    finally:
        client.close()


def test_a_forwarded_run_sets_the_analog_output_with_each_sample(request, tmp_path):
    traj = _ramp_trajectory()
    # the set-points as sent: as the arm, trailing its servoj, reaches each sample, on the
    # controller's period (the run's grid: with the samples' own spacing, 2e-3 + 2e-18 s,
    # a level a rounding away from a band's edge fell in the next band)
    want = written_levels(servo_levels(traj.heat_power / FULL_SCALE,
                                       traj.meta.control_period, SERVO_LOOKAHEAD, SERVO_GAIN))
    emu = start_emulator(request.node.nodeid, model="ur5e", unlock_delay=0.0, q0=traj.q[0])
    rows: list = []
    done = threading.Event()
    rec = threading.Thread(target=_record, args=(emu.host, done, rows), daemon=True)
    try:
        rec.start()
        time.sleep(0.3)
        res = run_trajectory(traj, emu.host, actual_path=tmp_path / "actual.csv")
    finally:
        done.set()
        rec.join(5.0)
        emu.close()
    assert res.status == "completed", res.message
    _, k, state, analog = (np.asarray(c, dtype=float) for c in zip(*rows, strict=True))
    run = (state == State.RUNNING) & (k >= 0)
    assert run.sum() > 0.9 * traj.n
    kk = k[run].astype(int)
    # the output in each control period's package: the set-point of the sample the register
    # reports or of the next (within one control period: the program writes the register
    # of sample k at the start of the period in which it sets the output for k + 1 and
    # commands it)
    now, nxt = want[kk], want[np.minimum(kk + 1, traj.n - 1)]
    err = np.minimum(np.abs(analog[run] - now), np.abs(analog[run] - nxt))
    print(f"{run.sum()} periods; analog output against the set-point of its sample: largest "
          f"{err.max():.2e}; set-points {np.count_nonzero(np.diff(want))} changes")
    bad = np.flatnonzero(err > 1e-6)
    assert not bad.size, (f"{bad.size} periods off, first at sample {kk[bad[0]]}: output "
                          f"{analog[run][bad[:5]]}, set-points {now[bad[:5]]}")  # fmt: skip
    assert analog[run].max() == pytest.approx(0.9, abs=HEAT_STEP)
    assert analog[-1] == 0.0  # off at the end
    # the run's recording: the analog output times the full scale, a column of its CSV
    back = read_trajectory(res.actual_path)
    assert back.heat_power is not None and back.heat_power.shape == (back.n,)
    assert back.heat_power.max() == pytest.approx(90.0, abs=HEAT_STEP * FULL_SCALE)
    ramp = back.heat_power[(back.heat_power > 5.0) & (back.heat_power < 85.0)]
    assert ramp.size > 0.5 * 1.5 / 0.002  # the ramp seen sample by sample, not a step
