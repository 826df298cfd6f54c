"""IK of calibrated arms: round trips near singularities, branch identity, non-convergence."""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.robot import (
    MODEL_NAMES,
    CalibratedIKSolutions,
    Calibration,
    IKSolutions,
    RobotModel,
    load,
    random_calibration,
)
from ruledrobot.robot.ik import calibrated as cik

from .helpers import angle_diff, solutions_contain
from .test_calibration import REAL, real_calibration

TOL = 1e-10  # the residual every returned solution must have (m and rad)


@contextmanager
def strict() -> Iterator[None]:
    with warnings.catch_warnings(), np.errstate(divide="raise", over="raise", invalid="raise"):
        warnings.simplefilter("error")
        yield


def residuals(m: RobotModel, T: np.ndarray, Q: np.ndarray, valid: np.ndarray):
    """Position [m] and rotation [rad] errors (n, 8) of solutions Q (n, 8, 6), FK of the model."""
    F = m.fk(np.where(valid[..., None], Q, 0.0))
    Tb = np.broadcast_to(T[:, None], F.shape)
    dp = np.linalg.norm(F[..., :3, 3] - Tb[..., :3, 3], axis=-1)
    R = np.einsum("...ji,...jk->...ik", F[..., :3, :3], Tb[..., :3, :3])
    w = 0.5 * np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0],
                        R[..., 1, 0] - R[..., 0, 1]], axis=-1)  # fmt: skip
    rot = np.arcsin(np.minimum(np.linalg.norm(w, axis=-1), 1.0))
    return np.where(valid, dp, 0.0), np.where(valid, rot, 0.0)


def shoulder_singular_q2(g, q3: np.ndarray, q4: np.ndarray) -> np.ndarray:
    """q2 with a2 c2 + a3 c23 + d5 s234 = 0 (the nominal shoulder singularity)."""
    A = g.a2 + g.a3 * np.cos(q3) + g.d5 * np.sin(q3 + q4)
    B = -g.a3 * np.sin(q3) + g.d5 * np.cos(q3 + q4)
    return np.arctan2(A, -B)


def singular_mix(m: RobotModel, rng: np.random.Generator, n: int) -> tuple:
    """n joint vectors: 70 % uniform, 10 % each at the wrist, elbow and shoulder singularity."""
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    k = n // 10
    w, e, s = slice(n - 3 * k, n - 2 * k), slice(n - 2 * k, n - k), slice(n - k, n)
    q[w, 4] = rng.choice([0.0, 1e-12, -1e-9, 1e-6, -1e-4, np.pi, np.pi - 1e-7], k)
    q[e, 2] = rng.choice([0.0, 1e-12, -1e-8, 1e-5, -1e-3, np.pi, -np.pi + 1e-6], k)
    q[s, 1] = shoulder_singular_q2(m.ur_geometry, q[s, 2], q[s, 3])
    q[s, 1] += rng.choice([0.0, 1e-9, -1e-6, 1e-4], k)
    regular = np.ones(n, dtype=bool)
    regular[n - 3 * k :] = False
    return q, regular


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_round_trip_10000_poses_near_singularities(model: str) -> None:
    rng = np.random.default_rng(1000 + MODEL_NAMES.index(model))
    m = load(model, calibration=random_calibration(model, 100 + MODEL_NAMES.index(model)))
    q, regular = singular_mix(m, rng, 10_000)
    T = m.fk(q)
    with strict():
        info = m.ik(T, return_info=True)
    assert isinstance(info, CalibratedIKSolutions)
    v = info.valid
    np.testing.assert_array_equal(v, info.converged)
    assert np.all(np.isnan(info.q[~v])) and np.all(np.isfinite(info.q[v]))
    assert np.all(info.q[v] > -np.pi) and np.all(info.q[v] <= np.pi)
    dp, rot = residuals(m, T, info.q, v)
    assert dp.max() < TOL and rot.max() < TOL, (dp.max(), rot.max())
    assert np.all(info.residual[v] <= cik.DEFAULT_TOL)
    # every pose is solved but a few next to the wrist singularity, whose nominal seeds
    # the calibration can push out of the elbow's reach (docs/robot.md, "what is left");
    # away from singularities the generating q is found
    solved = v.any(axis=1)
    clear_wrist = np.abs(np.sin(q[:, 4])) > 0.05
    assert solved[clear_wrist].mean() > 0.999, np.flatnonzero(~solved & clear_wrist)
    assert solved.mean() > 0.995, solved.mean()
    found = solutions_contain(info.q, q, 1e-7)
    assert found[regular].mean() > 0.985, found[regular].mean()
    # most of the nominal closed form's branches converge (measured 0.948-0.991 on this
    # mix, 30 % of it at singularities, where a branch of the nominal arm may not exist
    # on the calibrated one)
    _, exact = cik.nominal_seeds(m.ur_geometry, m.flange_poses(T), np.zeros(len(q)))
    assert (v & exact).sum() / exact.sum() > 0.94


@pytest.mark.parametrize("model", sorted(REAL))
def test_real_calibrations_round_trip(model: str) -> None:
    m = load(model, calibration=real_calibration(model))
    q = np.random.default_rng(5).uniform(-np.pi, np.pi, (3000, 6))
    T = m.fk(q)
    info = m.ik(T, return_info=True)
    dp, rot = residuals(m, T, info.q, info.valid)
    assert dp.max() < TOL and rot.max() < TOL
    assert solutions_contain(info.q, q, 1e-7).mean() > 0.98
    assert info.valid.any(axis=1).mean() > 0.998


@settings(max_examples=20, deadline=None)
@given(st.sampled_from(MODEL_NAMES), st.integers(0, 2**31), st.integers(0, 2**31))
def test_round_trip_property(model: str, cal_seed: int, q_seed: int) -> None:
    m = load(model, calibration=random_calibration(model, cal_seed))
    q = np.random.default_rng(q_seed).uniform(-np.pi, np.pi, (40, 6))
    T = m.fk(q)
    info = m.ik(T, return_info=True)
    dp, rot = residuals(m, T, info.q, info.valid)
    assert dp.max() < TOL and rot.max() < TOL
    # every pose solved, but next to the wrist singularity: there the calibration can
    # swing q6 and push the seed's elbow target out of reach (docs/robot.md, known gaps;
    # found here: ur3, calibration seed 11, a pose with sin q5 = -0.0039)
    regular = np.abs(np.sin(q[:, 4])) > 0.05
    assert info.valid.any(axis=1)[regular].all()


def flags(g, Q: np.ndarray) -> np.ndarray:
    """Branch index of joint vectors by the nominal formulas (docs/robot.md)."""
    t2, t3, t4 = Q[..., 1], Q[..., 2], Q[..., 3]
    s = g.a2 * np.cos(t2) + g.a3 * np.cos(t2 + t3) + g.d5 * np.sin(t2 + t3 + t4)
    return 4 * (s > 0) + 2 * (np.sin(Q[..., 4]) < 0) + (np.sin(t3) < 0)


@pytest.mark.parametrize("model", ["ur3", "ur5e", "ur10e", "ur20"])
def test_branch_identity_is_kept(model: str) -> None:
    m = load(model, calibration=random_calibration(model, 9))
    nom = m.nominal
    rng = np.random.default_rng(9)
    q = rng.uniform(-np.pi, np.pi, (5000, 6))
    T = m.fk(q)
    info = m.ik(T, return_info=True)
    seeds = nom.ik(T, return_info=True)
    # branches well clear of every singularity (nominal factors at the seed)
    scale = abs(nom.ur_geometry.a2) + abs(nom.ur_geometry.a3) + abs(nom.ur_geometry.d5)
    clear = (seeds.wrist > 0.2) & (seeds.elbow > 0.2) & (seeds.shoulder / scale > 0.05)
    sel = clear & info.valid
    assert sel.sum() > 10_000
    # the calibrated solution of branch b is the one nearest the nominal solution of b ...
    d = angle_diff(info.q[:, None, :, :], seeds.q[:, :, None, :]).max(-1)  # (n, seed b, sol c)
    d = np.where(np.isnan(d), np.inf, d)
    nearest = d.argmin(axis=2)
    rows, cols = np.nonzero(sel)
    np.testing.assert_array_equal(nearest[rows, cols], cols)
    # ... it moved by about the calibration's size, and its flags are those of b
    moved = d[rows, cols, cols]
    assert np.median(moved) < 0.02 and np.quantile(moved, 0.999) < 0.3, np.quantile(moved, 0.999)
    np.testing.assert_array_equal(flags(nom.ur_geometry, info.q[sel]), cols)


def test_non_convergence_is_reported() -> None:
    m = load("ur5e", calibration=random_calibration("ur5e", 1))
    q = np.random.default_rng(0).uniform(-np.pi, np.pi, (4000, 6))
    T = m.fk(q)
    info = m.ik(T, return_info=True)
    failed = info.seeded & ~info.converged
    assert failed.any()  # fallback seeds of branches only the 1 cm longer arm reaches
    assert np.all(np.isnan(info.q[failed])) and not info.valid[failed].any()
    assert np.all(info.residual[failed] > cik.DEFAULT_TOL)
    assert np.all(np.isnan(info.residual[~info.seeded]))
    assert np.all(info.iterations[~info.seeded] == 0)
    # a too small iteration budget: flagged, NaN, not hidden
    flange = m.flange_poses(T[:200])
    seeds, _ = cik.nominal_seeds(m.ur_geometry, flange, np.zeros(200))
    Q, conv, res, its = cik.refine_solutions(
        m.d, m.a, m.alpha, m.theta_offset, flange, seeds, np.zeros(6), max_iter=1
    )
    seeded = ~np.isnan(seeds[..., 0])
    assert (seeded & ~conv).sum() > 0.9 * seeded.sum()
    assert np.all(np.isnan(Q[~conv])) and np.all(res[seeded & ~conv] > cik.DEFAULT_TOL)
    assert its[seeded].max() <= 1


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_nominal_calibration_is_bit_for_bit(model: str) -> None:
    nom = load(model).with_tool([0.01, 0.02, 0.15, 0.1, 0.2, 0.3])
    m = nom.with_calibration(Calibration.nominal(model))
    assert m.calibration is not None
    q = np.random.default_rng(2).uniform(-np.pi, np.pi, (500, 6))
    q[:50, 4] = 0.0
    T = nom.fk(q)
    np.testing.assert_array_equal(m.fk(q), T)
    np.testing.assert_array_equal(m.ik(T), nom.ik(T))
    a, b = m.ik(T, return_info=True, q6_seed=0.3), nom.ik(T, return_info=True, q6_seed=0.3)
    assert type(a) is IKSolutions
    for f in ("q", "valid", "wrist", "elbow", "shoulder", "measure"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    # and without a calibration nothing changed
    assert type(load(model).ik(T[:5], return_info=True)) is IKSolutions


def test_base_tool_and_batch_shapes() -> None:
    m = (load("ur16e", calibration=random_calibration("ur16e", 3))
         .with_tool([0, 0.05, 0.2, 0, 0.3, 0]).with_base([0.5, -0.2, 0.1, 0, 0, 1.0]))  # fmt: skip
    q = np.random.default_rng(4).uniform(-np.pi, np.pi, (3, 7, 6))
    T = m.fk(q)
    info = m.ik(T, return_info=True)
    assert info.q.shape == (3, 7, 8, 6) and info.residual.shape == (3, 7, 8)
    assert m.ik(T[0, 0]).shape == (8, 6)
    dp, rot = residuals(m, T.reshape(-1, 4, 4), info.q.reshape(-1, 8, 6),
                        info.valid.reshape(-1, 8))  # fmt: skip
    assert dp.max() < TOL and rot.max() < TOL
    with pytest.raises(ValueError, match=r"poses\[0, 1\]"):
        bad = T.copy()
        bad[0, 1, 0, 0] = 2.0
        m.ik(bad)


def test_path_ik_on_a_calibrated_arm() -> None:
    m = load("ur5e", calibration=random_calibration("ur5e", 6)).with_tool([0, 0, 0.1, 0, 0, 0])
    t = np.linspace(0.0, 1.0, 400)[:, None]
    q = np.hstack([0.3 + 0.5 * t, -1.2 + 0.3 * t, 1.4 - 0.2 * t, -1.0 + 0.5 * t,
                   0.3 + 0.6 * t, 0.5 + 2.0 * t])  # fmt: skip
    P = m.fk(q)
    res = m.path_ik(P, q_start=q[0])
    assert res.all_ok, res.summary()
    err = np.abs(m.fk(res.q) - P).max()
    assert err < 1e-9
    np.testing.assert_allclose(res.q, q, atol=1e-6)
