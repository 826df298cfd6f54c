"""Path IK: branch continuity, singular stretches, unreachable segments, limits, flags."""

from __future__ import annotations

import dataclasses
import time
import warnings

import numpy as np
import pytest

from ruledrobot.geometry import se3
from ruledrobot.robot import PathIKResult, PathStatus, load, path_ik

from .helpers import pose_error

Q0 = np.array([0.0, -1.0, 1.2, -1.5, -1.57, 0.0])


def smooth_joint_path(n: int, q5_min: float) -> np.ndarray:
    """A smooth joint path whose q5 crosses zero with closest value ``q5_min``."""
    t = np.linspace(0.0, 1.0, n)
    return np.stack(
        [0.3 + 0.5 * t, -1.2 + 0.3 * t, 1.4 - 0.2 * t, -1.0 + 0.5 * t,
         0.3 - 0.6 * t + q5_min, 0.5 + t],
        axis=-1,
    )  # fmt: skip


def quiet_path_ik(*args: object, **kwargs: object) -> PathIKResult:
    with warnings.catch_warnings(), np.errstate(divide="raise", over="raise", invalid="raise"):
        warnings.simplefilter("error")
        return path_ik(*args, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("q5_min", [1e-4, 1e-7, 1e-10])
def test_keeps_the_branch_near_a_wrist_singularity(q5_min: float) -> None:
    m = load("ur5e")
    q = smooth_joint_path(2000, q5_min)
    T = m.fk(q)
    res = quiet_path_ik(m, T, q_start=q[0])
    assert res.all_ok, res.summary()
    # the generating path is the continuous one; q5 changes sign, so the analytic
    # wrist branch changes, continuously
    np.testing.assert_allclose(res.q, q, atol=1e-6)
    assert res.max_step < 1e-3
    assert set(res.branch.tolist()) == {0, 2}
    assert pose_error(m.fk(res.q), T).max() < 1e-9
    # without a start configuration the result is still continuous
    free = quiet_path_ik(m, T)
    assert free.all_ok and free.max_step < 1e-2


def test_through_an_exact_wrist_singularity_stays_continuous() -> None:
    m = load("ur5e")
    q = smooth_joint_path(1001, 0.0)
    q[:, 4] -= q[500, 4]  # exactly 0 at sample 500
    T = m.fk(q)
    res = quiet_path_ik(m, T, q_start=q[0])
    assert res.all_ok and res.max_step < 2e-3, res.summary()
    assert pose_error(m.fk(res.q), T).max() < 1e-9
    assert abs(res.q[500, 5] - res.q[499, 5]) < 1e-3


def test_held_wrist_singularity_segment() -> None:
    """q5 = 0 on a whole segment: q6 is free there; it is interpolated between the
    regular samples around the segment, so nothing jumps at either end."""
    m = load("ur5e")
    q = smooth_joint_path(600, 0.0)
    q[200:400, 4] = 0.0
    q[:200, 4] = np.linspace(0.3, 0.0, 200)
    q[400:, 4] = np.linspace(0.0, -0.3, 200)
    T = m.fk(q)
    res = quiet_path_ik(m, T, q_start=q[0])
    assert res.all_ok and res.max_step < 0.02, res.summary()
    assert pose_error(m.fk(res.q), T).max() < 1e-9
    # the generating q6 is linear in time there, as is the interpolation
    np.testing.assert_allclose(res.q, q, atol=1e-6)


def test_reports_an_unreachable_segment() -> None:
    m = load("ur5e")
    T0 = m.fk(Q0)
    n = 300
    T = np.repeat(T0[None], n, axis=0)
    T[:, 0, 3] -= 0.6 * np.sin(np.pi * np.linspace(0.0, 1.0, n))  # out of reach and back
    res = quiet_path_ik(m, T, q_start=Q0)
    bad = res.unreachable
    assert bad.size > 100
    assert np.array_equal(bad, np.arange(bad[0], bad[-1] + 1))  # one contiguous run
    assert np.all(res.status[bad] == PathStatus.UNREACHABLE)
    assert np.isnan(res.q[bad]).all() and np.isnan(res.step[bad]).all()
    assert not res.ok[bad].any() and res.ok[: bad[0]].all() and res.ok[bad[-1] + 1 :].all()
    assert any(f"samples {bad[0]}-{bad[-1]}: unreachable" in msg for msg in res.messages)
    assert "beyond the reach" in res.summary()
    good = np.flatnonzero(res.ok)
    assert pose_error(m.fk(res.q[good]), T[good]).max() < 1e-9
    # the path resumes on the same branch after the gap
    assert res.branch[bad[0] - 1] == res.branch[bad[-1] + 1]


def test_flags_a_jump_at_a_near_singular_crossing() -> None:
    """A screw motion that grazes the wrist singularity: q4 and q6 swing within a sample."""
    m = load("ur5e")
    qa = np.array([0.3, -1.2, 1.4, -1.0, 1e-3, 0.5])
    qb = qa.copy()
    qb[4], qb[0] = -1e-3, qa[0] + 0.02
    T = se3.geodesic(m.fk(qa), m.fk(qb), np.linspace(0.0, 1.0, 101))
    res = quiet_path_ik(m, T, q_start=qa)
    assert res.jumps.size >= 1
    assert np.all(res.status[res.jumps] == PathStatus.SINGULAR)
    assert any("wrist |sin q5|" in msg for msg in res.messages)
    assert pose_error(m.fk(res.q), T).max() < 1e-9


def test_flags_a_forced_branch_switch() -> None:
    """The start branch loses the elbow's reach further on: the switch is forced (and put
    where it is cheapest, before the branch actually ends)."""
    m = load("ur5e")
    q0 = np.array([-1.285, 1.837, 0.69, -2.807, 0.418, -0.388])
    d = np.array([-0.794, 0.481, 0.37])
    T = np.repeat(m.fk(q0)[None], 200, axis=0)
    T[:, :3, 3] += np.outer(np.linspace(0.0, 0.5, 200), d / np.linalg.norm(d))
    start = m.ik(T[0])[4]
    valid = m.ik(T, return_info=True).valid
    assert valid[0, 4] and not valid[:, 4].all()  # branch 4 ends inside the path
    res = quiet_path_ik(m, T, q_start=start)
    assert res.branch[0] == 4 and res.jumps.size == 1
    assert res.status[res.jumps[0]] == PathStatus.BRANCH_LOST
    assert "forced branch switch" in res.summary()
    assert pose_error(m.fk(res.q), T).max() < 1e-9


def test_flags_a_jump_in_the_poses() -> None:
    m = load("ur5e")
    q = np.concatenate([np.tile(Q0, (10, 1)), np.tile(Q0 + 0.5, (10, 1))])
    res = quiet_path_ik(m, m.fk(q), q_start=Q0)
    assert res.jumps.tolist() == [10]
    assert res.status[10] == PathStatus.JUMP
    np.testing.assert_allclose(res.step[10], 0.5, atol=1e-9)
    assert not res.all_ok and res.ok.sum() == 19


def test_joint_limits_force_a_wrap() -> None:
    """q6 turns three times; +-2 pi allows two turns, so one turn-back is unavoidable."""
    m = load("ur5e")
    q = np.tile(Q0, (600, 1))
    q[:, 5] = np.linspace(0.0, 6 * np.pi, 600)
    res = quiet_path_ik(m, m.fk(q), q_start=Q0)
    assert res.jumps.size == 1
    assert res.status[res.jumps[0]] == PathStatus.LIMIT_WRAP
    assert "turned back by 2 pi" in res.summary()
    assert m.within_limits(res.q).all()
    # away from the wrap the motion is continuous and reproduces the poses
    steps = np.delete(res.step, res.jumps)
    assert steps.max() < 0.04
    assert pose_error(m.fk(res.q), m.fk(q)).max() < 1e-9


def test_unlimited_wrist_needs_no_wrap() -> None:
    m = load("ur3e")  # wrist 3 unlimited
    q = np.tile(Q0, (600, 1))
    q[:, 5] = np.linspace(0.0, 6 * np.pi, 600)
    res = quiet_path_ik(m, m.fk(q), q_start=Q0)
    assert res.all_ok
    np.testing.assert_allclose(res.q, q, atol=1e-9)


def test_motion_is_shifted_into_the_limits() -> None:
    m = load("ur5e")
    q = np.tile(Q0, (300, 1))
    q[:, 5] = np.linspace(0.5, 3 * np.pi + 0.5, 300)  # 3 pi span: fits after a -2 pi shift
    res = quiet_path_ik(m, m.fk(q))
    assert res.all_ok
    assert m.within_limits(res.q).all()
    assert np.all(np.abs(np.diff(res.q[:, 5])) < 0.04)
    # q_start picks the 2 pi representative of the first sample
    q2 = np.tile(Q0, (50, 1))
    q2[:, 5] = np.linspace(0.5, 0.6, 50)
    start = Q0.copy()
    start[5] = 0.5 - 2 * np.pi
    res2 = quiet_path_ik(m, m.fk(q2), q_start=start)
    np.testing.assert_allclose(res2.q[:, 5], q2[:, 5] - 2 * np.pi, atol=1e-9)


def test_out_of_limits_samples() -> None:
    m = load("ur5e").with_limits(
        lower=[-0.2, -2 * np.pi, -np.pi, -2 * np.pi, -2 * np.pi, -6.3],
        upper=[0.2, 2 * np.pi, np.pi, 2 * np.pi, 2 * np.pi, 6.3],
    )
    q = np.tile(Q0, (100, 1))
    q[:, 0] = np.linspace(0.0, 1.0, 100)  # leaves the narrow q1 range
    res = quiet_path_ik(m, m.fk(q), q_start=Q0)
    unsolved = res.unreachable
    assert unsolved.size > 0
    assert np.all(res.status[unsolved] == PathStatus.OUT_OF_LIMITS)
    assert m.within_limits(res.q[res.ok]).all()
    assert any("inside the joint limits" in msg for msg in res.messages)


def test_base_and_tool_are_honoured() -> None:
    m = load("ur10e").with_base([0.1, 0.2, 0.3, 0.0, 0.0, 0.5]).with_tool([0, 0, 0.2, 0, 0, 0])
    q = smooth_joint_path(500, 0.05)
    T = m.fk(q)
    res = quiet_path_ik(m, T, q_start=q[0])
    assert res.all_ok
    np.testing.assert_allclose(res.q, q, atol=1e-9)
    assert isinstance(m.path_ik(T), PathIKResult)


def test_result_is_frozen_and_typed() -> None:
    m = load("ur5e")
    res = path_ik(m, m.fk(np.tile(Q0, (3, 1))))
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.max_step = 1.0  # type: ignore[misc]
    assert res.q.shape == (3, 6) and res.status.dtype == np.int8
    assert res.branch.dtype == np.int8 and res.messages == ()
    assert res.step[0] == 0.0
    single = path_ik(m, m.fk(Q0)[None])
    assert single.all_ok and single.max_step == 0.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"poses": np.eye(4)}, r"poses: expected a path of shape \(N, 4, 4\)"),
        ({"poses": np.zeros((0, 4, 4))}, "N >= 1"),
        ({"q_start": np.zeros(5)}, "q_start"),
        ({"q_start": np.zeros((2, 6))}, "q_start"),
        ({"weights": [1, 1, 1, 1, 1, -1]}, r"weights\[5\]"),
        ({"jump_threshold": np.nan}, "jump_threshold"),
    ],
)
def test_bad_input(kwargs: dict, match: str) -> None:
    m = load("ur5e")
    args = {"poses": m.fk(np.tile(Q0, (3, 1)))}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        path_ik(m, **args)


def test_nan_pose_is_named() -> None:
    m = load("ur5e")
    T = m.fk(np.tile(Q0, (5, 1)))
    T[3, 1, 1] = np.nan
    with pytest.raises(ValueError, match=r"poses\[3\]"):
        path_ik(m, T)


def test_speed_2000_poses() -> None:
    """Generous bound (the benchmark reports the real figure, ~10-20 ms)."""
    m = load("ur5e")
    T = m.fk(smooth_joint_path(2000, 1e-3))
    path_ik(m, T)
    t0 = time.perf_counter()
    path_ik(m, T)
    assert time.perf_counter() - t0 < 1.0
