"""Analytic IK: round trips, singularities, unreachable poses, errors, an external oracle."""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.geometry import se3
from ruledrobot.robot import MODEL_NAMES, IKSolutions, RobotModel, load
from ruledrobot.robot.ik import analytic as analytic_ik

from .helpers import angle_diff, pose_error, random_poses, solutions_contain

POSE_TOL = 1e-9


@contextmanager
def strict() -> Iterator[None]:
    """Every floating-point warning is an error."""
    # underflow stays ignored (numpy's default: it never warns); the rest raises
    with warnings.catch_warnings(), np.errstate(divide="raise", over="raise", invalid="raise"):
        warnings.simplefilter("error")
        yield


def check_solutions(m: RobotModel, T: np.ndarray, sols: np.ndarray) -> None:
    """Every non-NaN row reproduces its pose; rows are all-NaN or all-finite; range (-pi, pi]."""
    nan = np.isnan(sols)
    assert np.all(nan.all(-1) | ~nan.any(-1))
    valid = ~nan[..., 0]
    qz = np.where(valid[..., None], sols, 0.0)
    err = np.where(valid, pose_error(m.fk(qz), T[..., None, :, :]), 0.0)
    assert err.max() < POSE_TOL, err.max()
    finite = sols[valid]
    assert np.all(finite > -np.pi) and np.all(finite <= np.pi)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_round_trip_random_configurations(name: str, rng: np.random.Generator) -> None:
    m = load(name)
    q = rng.uniform(-np.pi, np.pi, size=(3000, 6))
    T = m.fk(q)
    with strict():
        sols = m.ik(T)
    assert sols.shape == (3000, 8, 6)
    check_solutions(m, T, sols)
    # the generating configuration is among the solutions (away from singularities,
    # where the closed form is well conditioned)
    regular = m.singularity_factors(q).min(axis=1) > 1e-4
    assert regular.mean() > 0.95
    assert solutions_contain(sols[regular], q[regular], 1e-7).all()
    # at least 2 solutions always (the flipped wrist); 8 for most poses
    count = (~np.isnan(sols[..., 0])).sum(axis=1)
    assert count.min() >= 2 and np.median(count) == 8


def test_branch_numbering(rng: np.random.Generator) -> None:
    """index = 4 shoulder + 2 wrist + elbow; wrist 0: sin q5 >= 0, elbow 0: sin q3 >= 0."""
    m = load("ur5e")
    q = rng.uniform(-np.pi, np.pi, size=(500, 6))
    sols = m.ik(m.fk(q), return_info=True)
    Q = sols.q
    for b in range(8):
        shoulder, wrist, elbow = b // 4, (b // 2) % 2, b % 2
        v = sols.valid[:, b]
        s5 = np.sin(Q[v, b, 4])
        s3 = np.sin(Q[v, b, 2])
        assert np.all(s5 >= -1e-12) if wrist == 0 else np.all(s5 <= 1e-12)
        assert np.all(s3 >= -1e-12) if elbow == 0 else np.all(s3 <= 1e-12)
        g = m.ur_geometry
        t = Q[v, b]
        s = (
            g.a2 * np.cos(t[:, 1])
            + g.a3 * np.cos(t[:, 1] + t[:, 2])
            + g.d5 * np.sin(t[:, 1:4].sum(1))
        )
        assert np.all(s <= 1e-12) if shoulder == 0 else np.all(s >= -1e-12)


def test_batch_shapes_and_single_pose(rng: np.random.Generator) -> None:
    m = load("ur10e")
    q = rng.uniform(-np.pi, np.pi, size=(2, 3, 6))
    T = m.fk(q)
    assert m.ik(T).shape == (2, 3, 8, 6)
    one = m.ik(T[1, 2])
    assert one.shape == (8, 6)
    assert solutions_contain(one[None], q[1, 2][None], 1e-7).all()
    assert m.ik(T[0, :0]).shape == (0, 8, 6)


def test_info_matches_the_model_measures(rng: np.random.Generator) -> None:
    m = load("ur5e")
    q = rng.uniform(-np.pi, np.pi, size=(400, 6))
    info = m.ik(m.fk(q), return_info=True)
    assert isinstance(info, IKSolutions)
    v = info.valid
    qv = info.q[v]
    f = m.singularity_factors(qv)
    np.testing.assert_allclose(info.wrist[v], f[:, 0], atol=1e-10)
    np.testing.assert_allclose(info.elbow[v], f[:, 1], atol=1e-10)
    np.testing.assert_allclose(info.shoulder[v], f[:, 2], atol=1e-10)
    np.testing.assert_allclose(info.measure[v], m.singularity_measure(qv), atol=1e-10)
    assert np.isnan(info.measure[~v]).all()


def _near_singular_configurations() -> list[tuple[str, np.ndarray]]:
    base = np.array([0.4, -1.1, 1.3, -0.9, 0.8, 0.5])
    cases = []
    for q5 in (0.0, 1e-15, 1e-12, 1e-9, 1e-6, np.pi, np.pi - 1e-9, -1e-9):
        q = base.copy()
        q[4] = q5
        cases.append((f"wrist q5={q5:g}", q))
    for q3 in (0.0, 1e-12, 1e-9, -1e-7, np.pi, np.pi - 1e-9):
        q = base.copy()
        q[2] = q3
        cases.append((f"elbow q3={q3:g}", q))
    q = base.copy()
    q[2], q[4] = 0.0, 0.0
    cases.append(("wrist and elbow", q))
    # shoulder: wrist point on the cylinder r = d4 (s = a2 c2 + a3 c23 + d5 s234 = 0)
    g = load("ur5e").ur_geometry
    for q3 in (0.05, -0.2):
        q2 = -np.pi / 2
        s234 = -(g.a2 * np.cos(q2) + g.a3 * np.cos(q2 + q3)) / g.d5
        q4 = np.arcsin(s234) - q2 - q3
        cases.append((f"shoulder q3={q3}", np.array([0.3, q2, q3, q4, 1.0, -0.4])))
    q = cases[-1][1].copy()
    q[4] = 0.0
    cases.append(("shoulder and wrist", q))
    return cases


@pytest.mark.parametrize(("label", "q"), _near_singular_configurations())
def test_near_singular_configurations(label: str, q: np.ndarray) -> None:
    m = load("ur5e")
    T = m.fk(q)
    with strict():
        sols, info = m.ik(T), m.ik(T, return_info=True)
    check_solutions(m, T, sols)
    valid = ~np.isnan(sols[:, 0])
    assert valid.sum() >= 2, label
    # the generating configuration is found where it is isolated (not at an exact
    # wrist singularity, where q4 and q6 trade off)
    if abs(np.sin(q[4])) > 1e-6:
        assert solutions_contain(sols[None], q[None], 1e-5).all(), label
    assert np.nanmin(info.measure) < 1e-5


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_near_singular_wrist_with_stretched_elbow(name: str) -> None:
    """q6 noise ~1e-16 / |sin q5| moves the elbow target; a stretched elbow must survive it."""
    m = load(name)
    q = np.array([[1.0, 0.0, 0.0, -1.0, 1e-9, 0.0], [0.3, -2.0, 1e-12, 0.4, -1e-7, 2.0]])
    T = m.fk(q)
    with strict():
        sols = m.ik(T)
    check_solutions(m, T, sols)
    assert (~np.isnan(sols[..., 0])).any(axis=1).all()


def test_shoulder_singularity_is_detected() -> None:
    m = load("ur5e")
    q = _near_singular_configurations()[-2][1]
    info = m.ik(m.fk(q), return_info=True)
    # rho = sqrt(r^2 - d4^2): rounding of ~1e-17 m^2 shows up as ~1e-9 m
    assert np.nanmax(info.shoulder) < 1e-7
    assert m.singularity_factors(q)[2] < 1e-12


def test_wrist_singularity_uses_the_seed() -> None:
    m = load("ur5e")
    q = np.array([0.4, -1.1, 1.3, -0.9, 0.0, 0.5])
    T = m.fk(q)
    for seed in (0.0, 0.7, -2.0):
        info = m.ik(T, q6_seed=seed, return_info=True)
        check_solutions(m, T, info.q)
        # the singular rows (here shoulder 0: the other shoulder has its own z1, q5 != 0)
        singular = info.valid & (info.wrist < 1e-12)
        assert singular[:4].all() and not singular[4:].any()
        q6 = info.q[:4, 5]
        np.testing.assert_allclose(angle_diff(q6[:2], seed), 0.0, atol=1e-12)  # wrist 0
        np.testing.assert_allclose(angle_diff(q6[2:], seed + np.pi), 0.0, atol=1e-12)  # flipped
    # with the generating q6 as seed the generating configuration comes back exactly
    assert solutions_contain(m.ik(T, q6_seed=0.5)[None], q[None], 1e-9).all()
    # per-pose seeds
    sols = m.ik(np.stack([T, T]), q6_seed=np.array([0.1, 0.2]))
    np.testing.assert_allclose(sols[:, 0, 5], [0.1, 0.2], atol=1e-12)


def test_wrist_singularity_keeps_the_elbow_reachable(monkeypatch: pytest.MonkeyPatch) -> None:
    """q5 = 0 with a nearly stretched arm whose z4 points outwards: the elbow reaches only
    for q6 near the generating value, so the seed q6 = 0 must be replaced."""
    m = load("ur5e")
    q = np.array([0.3, -0.7, 1e-3, -np.pi / 2, 0.0, 2.5])
    T = m.fk(q)
    with strict():
        info = m.ik(T, q6_seed=0.0, return_info=True)
    check_solutions(m, T, info.q)
    assert info.valid[:4].all()  # shoulder 0 is the singular one
    assert np.all(np.abs(info.q[:2, 5] - 2.5) < 0.01)  # the reachable q6 nearest the seed
    # the seed is kept where it works
    sols_seeded = m.ik(T, q6_seed=2.5)
    assert solutions_contain(sols_seeded[None], q[None], 1e-9).all()
    # without the rescue the seed q6 = 0 leaves the elbow out of reach
    monkeypatch.setattr(
        analytic_ik,
        "_rescue_wrist",
        lambda g, idx, Px, Py, ux, uy: (ux[idx], uy[idx], np.zeros(idx.size, dtype=bool)),
    )
    assert not m.ik(T, q6_seed=0.0, return_info=True).valid[:4].any()


def test_unreachable_poses_give_nan_rows_without_warnings(rng: np.random.Generator) -> None:
    m = load("ur5e")
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.5]
    inside = np.eye(4)  # flange at the base origin: wrist point inside the shoulder cylinder
    inside[:3, 3] = [0.0, 0.0, 0.3]
    T = np.concatenate([np.stack([far, inside]), random_poses(rng, 5000, scale=1.0)])
    with strict():
        sols = m.ik(T)
        info = m.ik(T, return_info=True)
    assert np.isnan(sols[:2]).all()
    assert not info.valid[:2].any()
    check_solutions(m, T, sols)
    unreachable = np.isnan(sols[..., 0]).all(axis=1)
    assert 0.05 < unreachable.mean() < 0.95  # the random batch has both kinds


def test_theta_offsets_and_d2_d3_are_supported(rng: np.random.Generator) -> None:
    ref = load("ur5e")
    off = np.array([0.1, -0.2, 0.3, 0.0, 0.5, -1.0])
    d = ref.d.copy()
    d[1], d[2], d[3] = 0.05, -0.02, ref.d[3] - 0.03  # same d2 + d3 + d4
    m = RobotModel.from_dh(d, ref.a, ref.alpha, theta_offset=off)
    q = rng.uniform(-np.pi, np.pi, size=(500, 6))
    T = m.fk(q)
    sols = m.ik(T)
    check_solutions(m, T, sols)
    regular = m.singularity_factors(q).min(axis=1) > 1e-4
    assert solutions_contain(sols[regular], q[regular], 1e-7).all()


def test_base_and_tool_round_trip(rng: np.random.Generator) -> None:
    m = load("ur16e").with_base([0.3, -0.5, 0.9, np.pi, 0, 0]).with_tool([0, 0.02, 0.3, 0.4, 0, 0])
    q = rng.uniform(-np.pi, np.pi, size=(500, 6))
    T = m.fk(q)
    sols = m.ik(T)
    check_solutions(m, T, sols)
    regular = m.singularity_factors(q).min(axis=1) > 1e-4
    assert solutions_contain(sols[regular], q[regular], 1e-7).all()


@given(st.lists(st.floats(-np.pi, np.pi, allow_nan=False), min_size=6, max_size=6))
def test_round_trip_property(q: list[float]) -> None:
    m = load("ur5e")
    q_arr = np.array(q)
    T = m.fk(q_arr)
    with strict():
        sols = m.ik(T)
    check_solutions(m, T, sols)
    if m.singularity_factors(q_arr).min() > 1e-4:
        assert solutions_contain(sols[None], q_arr[None], 1e-7).all()


@pytest.mark.parametrize(
    ("T", "match"),
    [
        (np.eye(3), r"poses: expected an array of shape \(\.\.\., 4, 4\), got shape \(3, 3\)"),
        (np.zeros((2, 4, 3)), r"poses: expected an array of shape"),
        ("abc", "poses: expected numbers"),
    ],
)
def test_bad_pose_shapes(T: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        load("ur5e").ik(T)  # type: ignore[arg-type]


def test_bad_pose_values_name_the_index() -> None:
    m = load("ur5e")
    T = np.tile(np.eye(4), (2, 3, 1, 1))
    T[1, 2, 0, 3] = np.nan
    with pytest.raises(ValueError, match=r"poses\[1, 2\]: contains NaN"):
        m.ik(T)
    T[1, 2, 0, 3] = 0.0
    T[0, 1, :3, :3] *= 1.1
    with pytest.raises(ValueError, match=r"poses\[0, 1\]: rotation part is not orthonormal"):
        m.ik(T)
    T[0, 1, :3, :3] = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(ValueError, match=r"poses\[0, 1\]: rotation part is a reflection"):
        m.ik(T)
    T[0, 1, :3, :3] = np.eye(3)
    T[0, 0, 3, 0] = 1.0
    with pytest.raises(ValueError, match=r"poses\[0, 0\]: last row"):
        m.ik(T)
    with pytest.raises(ValueError, match="q6_seed"):
        m.ik(np.tile(np.eye(4), (3, 1, 1)), q6_seed=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"q6_seed"):
        m.ik(np.eye(4), q6_seed=np.nan)


# ---------------------------------------------------------------------------
# external oracle: ur_analytic_ik (C++/Eigen, same DH tables), test-time only
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["ur5e", "ur3", "ur10e", "ur20"])
def test_agrees_with_ur_analytic_ik(name: str, rng: np.random.Generator) -> None:
    oracle_pkg = pytest.importorskip("ur_analytic_ik")
    oracle = getattr(oracle_pkg, name)
    m = load(name)
    q = rng.uniform(-np.pi, np.pi, size=(200, 6))
    T = m.fk(q)
    np.testing.assert_allclose(
        np.array([oracle.forward_kinematics(*row) for row in q]), T, atol=1e-12
    )
    ours = m.ik(T)
    for k in range(len(q)):
        theirs = np.array(oracle.inverse_kinematics(T[k])).reshape(-1, 6)
        mine = ours[k][~np.isnan(ours[k, :, 0])]
        if m.singularity_factors(mine).min() < 1e-6:
            continue  # duplicate/degenerate rows are filtered differently
        # same solution set modulo 2 pi (theirs has duplicates removed)
        d = angle_diff(mine[:, None, :], theirs[None, :, :]).max(axis=-1)
        assert d.min(axis=1).max() < 1e-7
        assert d.min(axis=0).max() < 1e-7


def test_pose_vector_round_trip_with_geometry_layer(rng: np.random.Generator) -> None:
    """UR pose vectors from the controller convert through se3 and solve."""
    m = load("ur5e")
    q = rng.uniform(-np.pi, np.pi, size=(20, 6))
    vec = se3.ur_vector_from_pose(m.fk(q))
    sols = m.ik(se3.pose_from_ur_vector(vec))
    assert solutions_contain(sols, q, 1e-6).all()
