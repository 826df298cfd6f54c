"""The heat_power column in trajectory files: CSV, JSON and NPZ round trips; old files."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.export import export_trajectory
from ruledrobot.io.trajectory import HEADER, read_trajectory, sidecar_path, write_trajectory
from ruledrobot.robot.motion.trajectory import Heat, Phase, Trajectory

HEAT = Heat("analog", 1, windows=((4, 45),), preheat=0.5, mode="constant_kerf",
            full_scale=75.0, lag=0.04)  # fmt: skip


def _traj(power: bool = True, n: int = 50) -> Trajectory:
    model = rr.robot.load("ur5e").with_tool((0.0, 0.0, 0.25, 0.0, 0.3, 0.0))
    t = np.arange(n) * 0.002
    q = np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.2]) + 0.3 * np.sin(np.outer(t, np.arange(1, 7)))
    tr = Trajectory.from_joints(t, q, model, phases=(Phase("cut", 0, n),), heat=HEAT)
    # an irregular schedule: zeros, a ramp, digits a %.10g text keeps
    p = np.where(np.arange(n) < 4, 0.0, 20.0 + 1.2345678 * np.arange(n))
    return Trajectory(tr.t, tr.q, tr.tcp, tr.meta, p) if power else tr


def test_csv_round_trip_keeps_the_column_and_the_heat_model(tmp_path):
    traj = _traj()
    p = write_trajectory(tmp_path / "traj.csv", traj)
    rows = list(csv.reader(p.open()))
    assert rows[0] == [*HEADER, "heat_power"] and all(len(r) == 14 for r in rows)
    np.testing.assert_allclose([float(r[13]) for r in rows[1:]], traj.heat_power, rtol=1e-10)
    back = read_trajectory(p)
    np.testing.assert_allclose(back.heat_power, traj.heat_power, rtol=1e-10)
    h = back.meta.heat
    assert (h.mode, h.full_scale, h.lag, h.kind, h.index) == ("constant_kerf", 75.0, 0.04,
                                                                "analog", 1)  # fmt: skip
    np.testing.assert_allclose(back.q, traj.q, atol=1e-9)


def test_a_trajectory_without_heat_power_writes_and_reads_as_before(tmp_path):
    p = write_trajectory(tmp_path / "traj.csv", _traj(power=False))
    assert p.read_text().splitlines()[0] == ",".join(HEADER)
    assert read_trajectory(p).heat_power is None


def test_an_old_sidecar_without_the_heat_model_reads(tmp_path):
    """A file of before issue 33: heat without mode, full scale, lag; 13 columns."""
    p = write_trajectory(tmp_path / "old.csv", _traj(power=False))
    side = sidecar_path(p)
    doc = json.loads(side.read_text())
    for key in ("mode", "full_scale_w_m", "lag_s"):
        doc["heat"].pop(key)
    side.write_text(json.dumps(doc))
    h = read_trajectory(p).meta.heat
    assert (h.mode, h.full_scale, h.lag) == ("on_off", None, 0.0)


@pytest.mark.parametrize("suffix", [".json", ".npz"])
def test_json_and_npz_keep_heat_power(tmp_path, suffix):
    traj = _traj()
    back = read_trajectory(export_trajectory(traj, tmp_path / f"cut{suffix}"))
    np.testing.assert_array_equal(back.heat_power, traj.heat_power)
    assert back.meta.heat.full_scale == 75.0
    plain = read_trajectory(export_trajectory(_traj(False), tmp_path / f"plain{suffix}"))
    assert plain.heat_power is None


@pytest.mark.parametrize("edit, message", [
    (lambda rows: rows[3].__setitem__(13, "-2"), r"heat_power\[2\]: expected a finite power"),
    (lambda rows: rows[5].pop(), r"line 6: expected 14 values"),
])  # fmt: skip
def test_bad_heat_power_cells_are_named(tmp_path, edit, message):
    p = write_trajectory(tmp_path / "bad.csv", _traj())
    side = sidecar_path(p)
    doc = json.loads(side.read_text())
    doc.pop("csv_sha256")
    side.write_text(json.dumps(doc))
    rows = list(csv.reader(p.open()))
    edit(rows)
    p.write_text("\n".join(",".join(r) for r in rows) + "\n")
    with pytest.raises(ValueError, match=message) as info:
        read_trajectory(p)
    assert "bad.csv" in str(info.value)


def test_an_analog_heat_power_without_full_scale_is_refused_by_the_reader(tmp_path):
    p = write_trajectory(tmp_path / "t.csv", _traj())
    side = sidecar_path(p)
    doc = json.loads(side.read_text())
    doc["heat"]["full_scale_w_m"] = None
    side.write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"t\.csv with t\.json: heat\.full_scale"):
        read_trajectory(p)


def test_an_export_with_heat_power_is_known_as_a_csv_export(tmp_path):
    """An export replaces an earlier export of its own kind: the 14-column CSV is one."""
    from ruledrobot.io.export_targets import file_kind

    assert file_kind(write_trajectory(tmp_path / "a.csv", _traj())) == "csv"
    assert file_kind(write_trajectory(tmp_path / "b.csv", _traj(False))) == "csv"
