"""The margins of issue 13: the planner's thresholds, the branch-and-bound search, the
stock of many placements in one clearance call, the quantised clearance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.robot import load
from ruledrobot.wirecut.cut.clearance import Cell, clearance
from ruledrobot.wirecut.cut.wire_pose import SearchOptions
from ruledrobot.wirecut.job.spec import ToolSpec
from ruledrobot.wirecut.reach.branch_bound import best_of
from ruledrobot.wirecut.reach.grid import RowBoxes, directions_needed
from ruledrobot.wirecut.reach.margins import (
    DEFAULT_RULES,
    GATES,
    clearance_margins,
    joint_limit_margin,
    limit_levers,
)

TOOL = ToolSpec(np.array([-0.2, 0.0, 0.25]), np.array([0.2, 0.0, 0.25]))


def test_the_rules_are_the_planners():
    """Acceptable (margin >= 0) must mean what the redundancy search accepts."""
    defaults = SearchOptions()  # the search's defaults (solve_redundancy's too)
    assert DEFAULT_RULES.singular_min == defaults.singular_min
    assert DEFAULT_RULES.margin == defaults.margin
    assert defaults.table_z == 0.0  # the cell of the map and the search (reach.job_cell)


def test_joint_limit_margin_takes_the_best_whole_turn():
    model = load("ur5e")
    q = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 3.0, 0.0, 0.0, 0.0]])
    np.testing.assert_allclose(joint_limit_margin(model, q), [np.pi, np.pi - 3.0])
    narrow = model.with_limits(lower=[-1.0] * 6, upper=[3.0] * 6)
    # q1 = -3 has the representative 2 pi - 3 = 3.28 (outside) and -3 (outside): none fits
    assert joint_limit_margin(narrow, np.array([-3.0, 1, 1, 1, 1, 1])) < 0.0
    assert joint_limit_margin(narrow, np.array([1.0, 1, 1, 1, 1, 1])) == pytest.approx(2.0)
    levers = limit_levers(model)
    assert levers[2] == pytest.approx(0.3922) and levers[0] == pytest.approx(0.8172)


def test_best_of_is_exact_and_prunes():
    rng = np.random.default_rng(0)
    bound = rng.uniform(-1, 1, (300, 40))
    value = bound - rng.exponential(0.5, bound.shape)
    calls = []

    def evaluate(g, o, floor):
        calls.append(len(g))
        return value[g, o]

    best, arg, exact = best_of(bound, evaluate, per_round=3)
    np.testing.assert_allclose(best, value.max(axis=1))
    np.testing.assert_allclose(value[np.arange(300), arg], best)
    assert exact.all() and sum(calls) < 0.5 * bound.size
    best, _, exact = best_of(bound, evaluate, per_round=1, max_rounds=1)
    assert (best <= value.max(axis=1)).all() and not exact.all()


def _configs(model, n: int, seed: int):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 1] = rng.uniform(-2.5, -0.5, n)
    return q, model.fk(q)


def test_row_boxes_give_each_configuration_its_own_stock():
    """The clearance rules with one moved stock per configuration (the placement search)
    equal the rules with that stock alone."""
    model = load("ur5e")
    stock = Box([0.5, 0.0, 0.3], [0.3, 0.2, 0.15])
    q, P = _configs(model, 400, 1)
    rng = np.random.default_rng(2)
    T = np.repeat(np.eye(4)[None], 400, axis=0)
    yaw = rng.uniform(-np.pi, np.pi, 400)
    c, s = np.cos(yaw), np.sin(yaw)
    T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = c, -s, s, c
    T[:, :2, 3] = rng.uniform(-0.5, 0.5, (400, 2))
    cell = Cell.of(model, TOOL, stock, 0.0, 0.005, 0.02, None)
    batched = clearance(dataclasses.replace(cell, stock=RowBoxes(stock, T)), q, P)
    for i in range(0, 400, 7):
        moved = Box(T[i, :3, :3] @ stock.centre + T[i, :3, 3], stock.size, T[i, :3, :3])
        one = clearance(dataclasses.replace(cell, stock=moved), q[i:i + 1], P[i:i + 1])
        assert {k: bool(v[0]) for k, v in one.items()} == {
            k: bool(v[i]) for k, v in batched.items()}
    hits = sum(int(v.sum()) for v in batched.values())
    assert hits > 50  # the test sees collisions, not only clear configurations


def test_clearance_margin_is_nonnegative_exactly_where_the_planner_accepts():
    model = load("ur5e")
    stock = Box([0.45, 0.0, 0.25], [0.3, 0.3, 0.2])
    q, P = _configs(model, 3000, 4)
    cell = Cell.of(model, TOOL, stock, 0.0, 0.005, 0.02, None)
    value, reason = clearance_margins(cell, q, P, DEFAULT_RULES)
    planner = clearance(cell, q, P)
    bad = np.zeros(len(q), bool)
    for v in planner.values():
        bad |= v
    assert ((value >= 0) == ~bad).all() and ((reason > 0) == bad).all()
    # the levels: a value v >= 0 means the rules (not the gates) hold at margin + v
    ok = np.isfinite(value) & (value > 0)
    lifted = clearance(dataclasses.replace(cell, margin=0.005 + 0.0099), q[ok], P[ok])
    assert not any(v.any() for k, v in lifted.items() if k not in GATES)
    assert np.isinf(value).any() and (value[np.isfinite(value) & ~bad] < 0.045).all()


def test_a_symmetric_bow_needs_one_wire_direction():
    from ruledrobot.robot.tool import BowTool

    assert directions_needed(BowTool.from_spec(TOOL).wire_frame()) == (False,)
    off = ToolSpec(np.array([-0.2, 0.05, 0.25]), np.array([0.2, 0.05, 0.25]))
    assert directions_needed(BowTool.from_spec(off).wire_frame()) == (False, True)
