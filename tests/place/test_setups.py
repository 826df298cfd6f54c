"""Setups (place.setups) without the search: the groupings tried (set partitions, counted
against Stirling numbers), the marked corners of the block, which face is down after a
turn, and the operator's steps for setups made up here (placements and turns whose
corners are computed here by hand)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ruledrobot.place.regions import Placement, Turn
from ruledrobot.place.search import Candidate
from ruledrobot.place.setups import (
    Setup,
    SetupPlan,
    _down_face,
    _partitions,
    corners,
    operator_steps,
    plan_setups,
)
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job


def _job(text: str = PART_JOB):
    return parse_job(job_document(text, "j.toml"), "j.toml")


def _stirling2(n: int, k: int) -> int:
    if n == k:
        return 1
    if k == 0 or k > n:
        return 0
    return k * _stirling2(n - 1, k) + _stirling2(n - 1, k - 1)


@pytest.mark.parametrize("n", range(1, 7))
def test_partitions_are_every_grouping_once(n):
    for k in range(1, min(n, 4) + 1):
        parts = list(_partitions(n, k))
        assert len(parts) == _stirling2(n, k)
        seen = set()
        for part in parts:
            assert len(part) == k and all(part)
            flat = [i for g in part for i in g]
            assert sorted(flat) == list(range(n))  # every cut in exactly one group
            assert all(list(g) == sorted(g) for g in part)
            assert [g[0] for g in part] == sorted(g[0] for g in part)
            key = frozenset(frozenset(g) for g in part)
            assert key not in seen
            seen.add(key)


def test_the_marked_corners_follow_the_block():
    job = _job()
    st = job.stock  # centre (0.5, 0, 0.3), size (0.2, 0.2, 0.15), not turned
    A, B, D = corners(job, np.eye(4))
    np.testing.assert_allclose(A, [0.4, -0.1, 0.225])
    np.testing.assert_allclose(B, [0.6, -0.1, 0.225])
    np.testing.assert_allclose(D, [0.4, 0.1, 0.225])
    T = Placement(0.7, 0.2, 0.4).transform(job)
    moved = corners(job, T)
    np.testing.assert_allclose(moved, np.array([A, B, D]) @ T[:3, :3].T + T[:3, 3])
    np.testing.assert_allclose(np.linalg.norm(moved[1] - moved[0]), st.size[0])
    np.testing.assert_allclose(np.linalg.norm(moved[2] - moved[0]), st.size[1])


@pytest.mark.parametrize(
    "turn, face",
    [(Turn(), "bottom"), (Turn("z", 90), "bottom"), (Turn("x", 90), "-y"), (Turn("x", 270), "+y"),
     (Turn("y", 90), "+x"), (Turn("y", 270), "-x"), (Turn("x", 180), "top")],
)  # fmt: skip
def test_which_face_is_down_after_a_turn(turn, face):
    job = _job()
    T = turn.matrix(job.stock)
    assert _down_face(job, T) == face
    # independently: the block's corner points of that face are the lowest after T
    axis = {"+x": (0, 1), "-x": (0, -1), "+y": (1, 1), "-y": (1, -1), "top": (2, 1),
            "bottom": (2, -1)}[face]  # fmt: skip
    normal = np.zeros(3)
    normal[axis[0]] = axis[1]
    world = T[:3, :3] @ job.stock.rotation @ normal
    np.testing.assert_allclose(world, [0.0, 0.0, -1.0], atol=1e-12)


def _setup(job, number, cuts, placement, margin=0.012):
    return Setup(number, cuts, Candidate(placement, margin, margin, (margin,) * len(cuts)))


def _corner_text(job, placement) -> str:
    A, B, D = corners(job, placement.transform(job))
    f = lambda p: "(" + ", ".join(str(round(v * 1e3)) for v in p) + ") mm"  # noqa: E731
    return f"put corner A at {f(A)}, B at {f(B)}, D at {f(D)}"


def test_operator_steps_turn_tip_and_flip():
    job = _job()
    first = Placement(0.5, 0.0, 0.0)
    turned = Placement(0.55, 0.05, np.radians(30.0))
    tipped = Placement(0.5, 0.0, 0.0, turn=Turn("y", 90))
    flipped = Placement(0.5, 0.0, 0.0, turn=Turn("x", 180))
    order = (first, flipped, tipped, turned)
    plan = SetupPlan(tuple(_setup(job, k + 1, cuts, p) for k, (cuts, p) in
                           enumerate(zip(((0,), (1,), (2,), (0, 2)), order, strict=True))),
                     0.012, 10)  # fmt: skip
    steps = operator_steps(job, plan)
    assert len(steps) == 4
    assert steps[0].startswith("Setup 1 (cuts: top; worst margin 12 mm): Mark the block's "
                               "corners A")  # fmt: skip
    assert "Set the block on its bottom face;" in steps[0]
    assert "Unclamp the block. Turn it upside down, onto its top face (the bottom face was "\
           "down at first), then turn it about the vertical;" in steps[1]  # fmt: skip
    assert "Tip it 90 deg over its bottom edge between the top and +x faces, onto its +x "\
           "face" in steps[2]  # fmt: skip
    assert "between the +x and bottom faces, onto its bottom face" in steps[3]
    assert steps[3].startswith("Setup 4 (cuts: top, plug;")
    for s, p in zip(steps, order, strict=True):
        assert _corner_text(job, p) in s
        assert s.endswith(f"Clamp it and run setup{s.split()[1]}/job.toml.")
    yaw = re.search(r"yaw (-?[\d.]+) deg\)", steps[3])
    assert float(yaw[1]) == pytest.approx(30.0, abs=0.05)
    there = SetupPlan((_setup(job, 1, (0,), first), _setup(job, 2, (1,), turned)), 0.0, 1)
    assert "Unclamp the block. Turn it 30 deg counter-clockwise (seen from above) about the "\
           "vertical, still on its bottom face;" in operator_steps(job, there)[1]  # fmt: skip
    back = SetupPlan((_setup(job, 1, (0,), turned), _setup(job, 2, (1,), first)), 0.0, 1)
    assert "Turn it 30 deg clockwise" in operator_steps(job, back)[1]


def test_one_cut_needs_no_setups():
    job = _job(DEMO_JOB)
    assert plan_setups(job, None, None, ()) is None  # no search is made
