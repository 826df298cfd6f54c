"""Calibration as data: the type, its checks, the file format, random calibrations, FK."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.io.calibration import CALIBRATION_FORMAT, load_calibration, save_calibration
from ruledrobot.robot import (
    MODEL_NAMES,
    Calibration,
    CalibrationError,
    KinematicsRef,
    load,
    random_calibration,
)
from ruledrobot.robot.arm.calibration import calibration_deviations, zero_frames
from ruledrobot.robot.arm.calibration_random import dh_from_axes

from .helpers import dh_fk_reference

# Real factory calibrations: delta_theta, delta_a, delta_d, delta_alpha as a controller's
# calibration.conf lists them (effective = nominal + delta).  Sources: a UR3 in
# MyRobotLab/pyrobotlab#145 (2025), a UR5 in ros-industrial-attic/ur_modern_driver#179
# (2018), and the UR10 sets of UniversalRobots/Universal_Robots_ROS_Driver
# ur_calibration/test/calibration_test.cpp.
REAL = {
    "ur3": (
        [9.14361764983717684e-08, 0.178461025123001604, 6.68283349819805572,
         -0.578116982609792496, 6.11299818305960363e-06, -5.03926212855332345e-07],
        [-0.000243788991999517813, 0.00381165418642351317, 0.034503078453104935,
         0.000107694612896758047, -0.000198736633205663144, 0],
        [9.225352853908797e-05, 12.0620003757611567, 17.6719025641737275,
         -29.7339960369544869, -2.8164617795367608e-05, 0.000217420471082099831],
        [0.00115615746589403656, 0.0035851898103369975, 0.00392132336586574568,
         0.000406668888106365145, -0.00201170396009153762, 0],
    ),
    "ur5": (
        [2.07750978653505926e-05, 0.96821571555565844, -1.85685385014877657,
         0.888647901450376643, 5.66106814887767484e-05, -7.46310764096455082e-05],
        [0.000393621049984383038, 0.184093300397451837, 0.14493953300732923,
         -6.43297403642304399e-05, 7.76709040084077299e-06, 0],
        [4.00263097760228392e-05, 278.244144925623573, -183.695513914913732,
         -94.5471513669751289, 0.000304782681775556119, 0.000123737941387466743],
        [-0.000271624944216508624, 0.00125856505456124258, -0.00322052070697146503,
         0.00065153016530383745, -0.00058700465721117645, 0],
    ),
    "ur10": (
        [-2.41478068943590252e-07, 1.60233952386694556, -1.68607190752171299,
         0.0837331147700118711, -1.01260355871157781e-07, 3.91986209186123702e-08],
        [2.12234865571205891e-05, 0.632017132627700651, 0.00229833638891230319,
         -4.61409023720933908e-05, -6.39280053471801522e-05, 0],
        [-0.000160188285741325043, 439.140974079900957, -446.027059806332147,
         6.88618689642360149, -3.86588496858186748e-05, -0.00087908274257374186],
        [-0.000650246557584166496, 0.00139416666825590402, 0.00693818880325995126,
         -0.000811641562390219562, 0.000411120504570705592, 0],
    ),
}  # fmt: skip


def real_calibration(model: str) -> Calibration:
    nom = load(model)
    th, a, d, al = (np.array(v) for v in REAL[model])
    return Calibration(model, nom.theta_offset + th, nom.a + a, nom.d + d, nom.alpha + al,
                       source=f"real {model}", status=2)  # fmt: skip


# ---------------------------------------------------------------------- the type


@pytest.mark.parametrize("model", sorted(REAL))
def test_real_calibrations_are_accepted(model: str) -> None:
    cal = real_calibration(model)
    assert not cal.is_nominal
    assert cal.status_text == "linearised"
    dev = calibration_deviations(cal)
    assert abs(dev["d_sum"]) < 2e-3  # d2 + d3 + d4 stays put, d2..d4 move by metres
    assert np.abs(cal.deltas()[1:4, 2]).max() > 1.0
    assert dev["flange_position"] < 0.01


def test_nominal_calibration_and_views() -> None:
    cal = Calibration.nominal("UR5e")
    assert cal.model == "ur5e" and cal.is_nominal and cal.source == "nominal"
    m = load("ur5e")
    np.testing.assert_array_equal(cal.dh(), KinematicsRef.of(m).dh)
    assert np.all(cal.deltas() == 0.0)
    info = random_calibration("ur5e", 3).kinematics_info()
    back = Calibration.from_kinematics_info(info, "ur5e", source="controller 127.0.0.1")
    np.testing.assert_array_equal(back.dh(), random_calibration("ur5e", 3).dh())
    assert back.checksum == random_calibration("ur5e", 3).checksum and back.status == 2
    assert "calibrated" in repr(back) and "controller 127.0.0.1" in repr(back)


def test_structure_errors_name_the_field() -> None:
    m = load("ur5e")
    good = dict(theta_offset=m.theta_offset, a=m.a, d=m.d, alpha=m.alpha)
    with pytest.raises(CalibrationError, match="model: 'ur7'"):
        Calibration("ur7", **good)
    with pytest.raises(CalibrationError, match=r"d: expected 6 numbers.*shape \(5,\)"):
        Calibration("ur5e", **{**good, "d": m.d[:5]})
    bad = m.a.copy()
    bad[2] = np.nan
    with pytest.raises(CalibrationError, match=r"a\[2\] \(joint 3 \(elbow\)\): not a finite"):
        Calibration("ur5e", **{**good, "a": bad})
    with pytest.raises(CalibrationError, match=r"checksum\[1\].*uint32"):
        Calibration("ur5e", **good, checksum=(1, -2, 3, 4, 5, 6))
    with pytest.raises(CalibrationError, match="checksum: expected 6"):
        Calibration("ur5e", **good, checksum=(1, 2, 3))
    with pytest.raises(CalibrationError, match="status"):
        Calibration("ur5e", **good, status="linearised")  # type: ignore[arg-type]
    assert Calibration("ur5e", **good, checksum=("0xb3241580",) * 6).checksum[0] == 0xB3241580


# ---------------------------------------------------------------------- plausibility


def _with(model: str, joint: int, column: str, delta: float) -> dict:
    m = load(model)
    cols = dict(theta_offset=m.theta_offset.copy(), a=m.a.copy(), d=m.d.copy(),
                alpha=m.alpha.copy())  # fmt: skip
    cols[column][joint] += delta
    return cols


@pytest.mark.parametrize(
    ("joint", "column", "delta", "message"),
    [
        (0, "d", 0.006, r"joint 1 \(base\): d = .* by \+0\.006 m \(bound 0\.005 m\)"),
        (4, "d", -0.008, r"joint 5 \(wrist 2\): d = "),
        (5, "d", 0.01, r"joint 6 \(wrist 3\): d = "),
        (0, "a", 0.007, r"joint 1 \(base\): a = "),
        (3, "a", 0.007, r"joint 4 \(wrist 1\): a = "),
        (4, "a", -0.007, r"joint 5 \(wrist 2\): a = "),
        (5, "a", 0.007, r"joint 6 \(wrist 3\): a = "),
        (1, "alpha", 0.06, r"joint 2 \(shoulder\): alpha = .*bound 0\.05 rad"),
        (3, "alpha", -0.06, r"joint 4 \(wrist 1\): alpha = "),
        (0, "theta_offset", 0.06, r"joint 1 \(base\): theta_offset = "),
        (5, "theta_offset", -0.1, r"joint 6 \(wrist 3\): theta_offset = "),
        (2, "d", 0.006, r"joints 2-4: d2 \+ d3 \+ d4 .* by \+6 mm"),
        (3, "theta_offset", 0.06, r"joints 2-4: theta_offset2 \+ theta_offset3"),
        (1, "a", 0.03, r"joint 3 \(elbow\): axis 30 mm from its nominal position"),
        (2, "a", -0.03, r"joint 4 \(wrist 1\): axis 30 mm from its nominal position"),
        (1, "d", 20_000.0, r"joint 2 \(shoulder\): d = 20000.* beyond 10000 m"),
    ],
)
def test_implausible_calibrations_are_refused(
    joint: int, column: str, delta: float, message: str
) -> None:
    with pytest.raises(CalibrationError, match=message):
        Calibration("ur5e", **_with("ur5e", joint, column, delta))


def test_compensating_d_is_accepted_theta_pair_is_not() -> None:
    # d2 and d3 moved by 300 m in opposite directions: the same arm, accepted
    cols = _with("ur10e", 1, "d", 300.0)
    cols["d"][2] -= 300.0
    cal = Calibration("ur10e", **cols)
    assert calibration_deviations(cal)["axis_offset"].max() < 1e-12
    # theta2 + 0.1, theta3 - 0.1: the sum holds but the elbow axis swings 4 cm
    cols = _with("ur10e", 1, "theta_offset", 0.1)
    cols["theta_offset"][2] -= 0.1
    with pytest.raises(CalibrationError, match=r"joint 3 \(elbow\): axis .* mm from"):
        Calibration("ur10e", **cols)


def test_other_model_refused_when_attached() -> None:
    cal = random_calibration("ur10e", 1)
    with pytest.raises(ValueError, match=r"belongs to a ur10e.*this model is a ur5e"):
        load("ur5e").with_calibration(cal)
    with pytest.raises(ValueError, match="belongs to a ur10e"):
        load("ur5e", calibration=cal)


# ---------------------------------------------------------------------- random calibrations


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_random_calibrations_look_real(model: str) -> None:
    for seed in range(5):
        cal = random_calibration(model, seed)
        assert cal.model == model and cal.status == 2 and len(cal.checksum) == 6
        dev = calibration_deviations(cal)
        # small in the geometry ...
        assert dev["axis_tilt"].max() < 0.02 and dev["axis_offset"].max() < 0.005
        assert dev["flange_position"] < 0.02
        # ... and, as real ones, large compensating numbers on joints 2-4
        assert np.abs(cal.deltas()[1:4, 2]).max() > 0.05
        assert abs(dev["d_sum"]) < 0.005
    np.testing.assert_array_equal(
        random_calibration(model, 7).dh(), random_calibration(model, 7).dh()
    )
    assert not np.array_equal(random_calibration(model, 7).dh(), random_calibration(model, 8).dh())


def test_random_calibration_scale_is_refused_when_large() -> None:
    refused = 0
    for seed in range(10):
        try:
            random_calibration("ur5e", seed, scale=20.0)
        except CalibrationError:
            refused += 1
    assert refused >= 8  # even after 20 draws each


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_dh_from_axes_reproduces_the_nominal_table(model: str) -> None:
    m = load(model)
    F = zero_frames(m.theta_offset, m.a, m.d, m.alpha)
    table = dh_from_axes(F[:6, :3, 3], F[:6, :3, 2], F[6], F[1:, :3, 0])
    ref = np.stack([m.theta_offset, m.a, m.d, m.alpha], axis=1)
    np.testing.assert_allclose(table, ref, atol=1e-15)


def test_dh_from_axes_of_a_random_calibration_gives_its_axes() -> None:
    cal = random_calibration("ur16e", 4)
    F = zero_frames(*cal.dh().T)
    table = dh_from_axes(F[:6, :3, 3], F[:6, :3, 2], F[6], F[1:, :3, 0])
    G = zero_frames(*table.T)
    # same axes, same flange; the far-away common normals of the nearly parallel axes
    # 2-4 (d of hundreds of metres) cost some digits
    for i in range(7):
        np.testing.assert_allclose(G[i, :3, 2], F[i, :3, 2], atol=1e-12)
        assert np.linalg.norm(np.cross(G[i, :3, 3] - F[i, :3, 3], F[i, :3, 2])) < 5e-8
    np.testing.assert_allclose(G[6], F[6], atol=5e-8)  # 1.4e-8 with numpy 2.4


# ---------------------------------------------------------------------- files


def test_file_round_trip_is_exact(tmp_path) -> None:
    for model in MODEL_NAMES:
        cal = random_calibration(model, 11)
        path = save_calibration(tmp_path / f"{model}.json", cal)
        back = load_calibration(path)
        np.testing.assert_array_equal(back.dh(), cal.dh())
        assert (back.model, back.checksum, back.status, back.source) == (
            cal.model, cal.checksum, cal.status, cal.source)  # fmt: skip
    doc = json.loads((tmp_path / "ur5e.json").read_text())
    assert doc["format"] == CALIBRATION_FORMAT
    assert set(doc["dh"]) == {"theta_offset", "a", "d", "alpha"}
    assert not list(tmp_path.glob(".*.tmp"))


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(MODEL_NAMES), st.integers(0, 2**31), st.floats(0.1, 1.0))
def test_file_round_trip_property(model: str, seed: int, scale: float) -> None:
    import tempfile
    from pathlib import Path

    cal = random_calibration(model, seed, scale=scale)
    with tempfile.TemporaryDirectory() as tmp:
        back = load_calibration(save_calibration(Path(tmp) / "c.json", cal))
    np.testing.assert_array_equal(back.dh(), cal.dh())


def test_file_errors_name_file_and_field(tmp_path) -> None:
    good = json.loads(json.dumps({
        "format": CALIBRATION_FORMAT, "model": "ur5e", "source": "x", "status": 2,
        "checksum": None,
        "dh": {k: list(map(float, v)) for k, v in zip(
            ("theta_offset", "a", "d", "alpha"), random_calibration("ur5e", 2).dh().T,
            strict=True)},
    }))  # fmt: skip
    p = tmp_path / "cal.json"

    def fails(doc, message):
        p.write_text(doc if isinstance(doc, str) else json.dumps(doc))
        with pytest.raises(CalibrationError, match=message) as exc:
            load_calibration(p)
        assert str(p) in str(exc.value)

    fails("{not json", r"cal\.json: not JSON \(line 1")
    fails([1, 2], "expected a JSON object")
    fails({**good, "format": "ruledrobot.lines/1"}, "format: expected 'ruledrobot.calibration/1'")
    fails({k: v for k, v in good.items() if k != "dh"}, "dh: missing")
    fails({**good, "extra": 1}, "extra: unknown field")
    fails({**good, "dh": {**good["dh"], "a": [0, 1]}}, r"dh\.a: expected 6 numbers")
    fails({**good, "dh": {**good["dh"], "d": ["x"] * 6}}, r"dh\.d: expected a list of 6 numbers")
    fails(
        {**good, "dh": {k: v for k, v in good["dh"].items() if k != "alpha"}}, r"dh\.alpha: missing"
    )
    fails(
        {**good, "model": "ur10e"}, r"cal\.json: joint .*differs from the nominal|cal\.json: joint"
    )
    bad = json.loads(json.dumps(good))
    bad["dh"]["alpha"][3] += 0.2
    fails(bad, r"cal\.json: joint 4 \(wrist 1\): alpha = ")
    with pytest.raises(CalibrationError, match="no such calibration file"):
        load_calibration(tmp_path / "missing.json")
    # defaults: no source -> the path
    doc = {k: v for k, v in good.items() if k not in ("source", "status", "checksum")}
    p.write_text(json.dumps(doc))
    cal = load_calibration(p)
    assert cal.source == str(p) and cal.status is None and cal.checksum is None


# ---------------------------------------------------------------------- the model and FK


def test_attach_and_detach() -> None:
    nom = load("ur5e").with_tool([0, 0, 0.1, 0, 0, 0]).with_base([0.1, 0, 0, 0, 0, 0.3])
    cal = random_calibration("ur5e", 5)
    m = nom.with_calibration(cal)
    assert m.calibration is cal and nom.calibration is None
    np.testing.assert_array_equal(m.d, cal.d)
    np.testing.assert_array_equal(m.tool, nom.tool)
    np.testing.assert_array_equal(m.base, nom.base)
    assert m.has_analytic_ik and m.ur_geometry == nom.ur_geometry
    assert "calibrated (seeded random (seed 5))" in repr(m)
    back = m.nominal
    assert back.calibration is None
    np.testing.assert_array_equal(back.d, nom.d)
    assert m.with_calibration(None).calibration is None
    assert m.with_tool(np.eye(4)).calibration is cal  # kept through copies
    ref = KinematicsRef.of(m)
    np.testing.assert_array_equal(ref.dh, cal.dh())
    with pytest.raises(
        ValueError, match=r"d\[0\] = 0\.1625 is not the calibration's effective value"
    ):
        import dataclasses

        dataclasses.replace(m, d=nom.d)


def test_attach_from_a_file(tmp_path) -> None:
    cal = random_calibration("ur3e", 2)
    path = save_calibration(tmp_path / "robot.json", cal)
    m = load("ur3e", calibration=load_calibration(path))
    np.testing.assert_array_equal(m.alpha, cal.alpha)
    assert m.calibration.source == cal.source


@settings(max_examples=30, deadline=None)
@given(st.sampled_from(MODEL_NAMES), st.integers(0, 2**31), st.integers(0, 2**31))
def test_fk_equals_a_product_of_dh_matrices(model: str, seed: int, qseed: int) -> None:
    cal = random_calibration(model, seed)
    m = load(model, calibration=cal)
    q = np.random.default_rng(qseed).uniform(-2 * np.pi, 2 * np.pi, (20, 6))
    ref = dh_fk_reference(q, cal.d, cal.a, cal.alpha, cal.theta_offset)
    # two float64 products of six transforms whose offsets reach hundreds of metres (the
    # nearly cancelling d2..d4 of a calibration): rounding scales with their sum
    tol = 1e-12 + 64 * np.finfo(float).eps * float(np.abs(cal.d).sum() + np.abs(cal.a).sum())
    assert np.abs(m.fk(q) - ref).max() < tol


@pytest.mark.parametrize("model", sorted(REAL))
def test_fk_of_real_calibrations_against_pytransform3d(model: str) -> None:
    pt = pytest.importorskip("pytransform3d.transformations")
    pr = pytest.importorskip("pytransform3d.rotations")
    cal = real_calibration(model)
    m = load(model, calibration=cal)
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, (50, 6))
    T = m.fk(q)
    for k in range(q.shape[0]):
        A = np.eye(4)
        for i in range(6):
            Rz = pt.transform_from(pr.active_matrix_from_angle(2, q[k, i] + cal.theta_offset[i]),
                                   [0, 0, 0])  # fmt: skip
            Tz = pt.transform_from(np.eye(3), [0, 0, cal.d[i]])
            Tx = pt.transform_from(np.eye(3), [cal.a[i], 0, 0])
            Rx = pt.transform_from(pr.active_matrix_from_angle(0, cal.alpha[i]), [0, 0, 0])
            A = A @ Rz @ Tz @ Tx @ Rx
        assert np.abs(T[k] - A).max() < 1e-12
    # the calibration moves the flange by millimetres, not metres
    d = np.linalg.norm(T[:, :3, 3] - load(model).fk(q)[:, :3, 3], axis=-1)
    assert 1e-4 < d.max() < 0.01


def test_link_points_of_a_calibrated_arm_are_the_nominal_skeleton() -> None:
    m = load("ur10", calibration=real_calibration("ur10"))
    q = np.random.default_rng(3).uniform(-np.pi, np.pi, (10, 6))
    np.testing.assert_array_equal(m.link_points(q), load("ur10").link_points(q))
    assert np.abs(m.link_points(q)).max() < 2.0


def test_random_calibration_of_scale_zero_is_nominal() -> None:
    assert np.abs(random_calibration("ur20", 3, scale=0.0).deltas()).max() < 1e-15
