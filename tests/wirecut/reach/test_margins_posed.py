"""The margin ladder poses the bodies once (:class:`~ruledrobot.wirecut.cut.clearance.Posed`)
and judges each level on them: its results are exactly those of the rules recomputed from
scratch at every level, for every configuration (the ladder written plainly, below)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.robot import load
from ruledrobot.wirecut.cut.clearance import RULES, Cell, Posed, broken, clearance
from ruledrobot.wirecut.job.spec import ToolSpec
from ruledrobot.wirecut.reach.grid import RowBoxes
from ruledrobot.wirecut.reach.margins import (
    DEFAULT_RULES,
    GATES,
    REASON_TEXT,
    Reason,
    Rules,
    clearance_margins,
)

TOOL = ToolSpec(np.array([-0.2, 0.0, 0.25]), np.array([0.2, 0.0, 0.25]))
STOCK = Box([0.45, 0.0, 0.25], [0.3, 0.3, 0.2])


def _ladder(cell: Cell, q, P, rules: Rules, cap, depth: bool):
    """The clearance margins as the module doc defines them, every rule recomputed from the
    joints at every level for every configuration (no subsets, no pruning, no shared
    geometry): the value is the highest level tried at which the valued rules hold."""
    n = len(q)

    def bad_at(level: float, keys) -> np.ndarray:
        res = clearance(dataclasses.replace(cell, margin=level), q, P)
        return np.any([v for k, v in res.items() if k in keys], axis=0)

    valued = [k for k in RULES if k not in GATES]
    at_margin = clearance(dataclasses.replace(cell, margin=rules.margin), q, P)
    reason = np.zeros(n, np.int8)
    codes = {text: int(r) for r, text in REASON_TEXT.items()}
    for key in reversed(list(at_margin)):  # the first rule broken, in the rules' order
        reason = np.where(at_margin[key], np.int8(codes.get(key, Reason.CLEARANCE)), reason)
    env = bad_at(rules.margin, valued)
    gate = bad_at(rules.margin, GATES)
    levels = list(rules.levels)
    k0 = levels.index(rules.margin)
    value = np.where(env, levels[0] - rules.margin - 0.02, 0.0)
    cap = np.full(n, np.inf) if cap is None else cap
    upper = levels[k0:]
    for i in range(1, len(upper)):  # ascending: a higher level kept overrides
        v = np.inf if i == len(upper) - 1 else upper[i] - rules.margin
        tried = ~env & (cap > upper[i - 1] - rules.margin)
        value = np.where(tried & ~bad_at(upper[i], valued), v, value)
    if depth:
        for level in levels[:k0]:  # ascending: the highest level kept wins
            value = np.where(env & ~bad_at(level, valued), level - rules.margin, value)
    return np.where(gate, np.minimum(value, -rules.margin), value), reason


def _case(seed: int, self_collision: bool, rows: bool, hub: bool, n: int = 500):
    """A cell (random table height, optionally no hub, the arm against itself, one moved
    stock per configuration) and random configurations with their flange poses."""
    rng = np.random.default_rng(seed)
    model = load("ur5e")
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 1] = rng.uniform(-2.5, -0.5, n)
    table = float(rng.uniform(-0.1, 0.05))
    cell = Cell.of(model, TOOL, STOCK, table, 0.005, 0.02, None)
    cell = dataclasses.replace(cell, self_collision=self_collision,
                               hub=cell.hub if hub else None)  # fmt: skip
    if rows:
        T = np.repeat(np.eye(4)[None], n, axis=0)
        yaw = rng.uniform(-np.pi, np.pi, n)
        T[:, 0, 0], T[:, 0, 1], T[:, 1, 0], T[:, 1, 1] = (np.cos(yaw), -np.sin(yaw),
                                                          np.sin(yaw), np.cos(yaw))  # fmt: skip
        T[:, :3, 3] = rng.uniform([-0.3, -0.3, -0.1], [0.3, 0.3, 0.1], (n, 3))
        cell = dataclasses.replace(cell, stock=RowBoxes(STOCK, T))
    cap = rng.uniform(-0.01, 0.06, n) if seed % 2 else None
    return cell, q, model.fk(q), cap


CASES = [(s, sc, rows, hub) for s, (sc, rows, hub) in enumerate(
    [(False, False, True), (False, True, True), (True, False, True), (True, True, True),
     (False, True, False), (True, True, False)])]  # fmt: skip


@pytest.mark.parametrize(("seed", "self_collision", "rows", "hub"), CASES)
def test_the_ladder_on_posed_bodies_is_the_ladder_recomputed(seed, self_collision, rows, hub):
    cell, q, P, cap = _case(seed, self_collision, rows, hub)
    rules = [DEFAULT_RULES, Rules(margin=0.01, levels=(-0.02, 0.0, 0.01, 0.02, 0.04))]
    for r in rules:
        for depth in (True, False):
            got = clearance_margins(cell, q, P, r, cap=cap, depth=depth)
            want = _ladder(cell, q, P, r, cap, depth)
            np.testing.assert_array_equal(got[0], want[0])
            np.testing.assert_array_equal(got[1], want[1])
    value = got[0]
    # the batch spans the ladder: ample, the levels above the margin, failures, gates
    assert np.isinf(value).any() and ((value > 0) & np.isfinite(value)).any()
    assert (value < 0).any() and (value == 0).any()


@pytest.mark.parametrize(("seed", "self_collision", "rows", "hub"), CASES)
def test_rules_on_a_subset_of_posed_bodies_are_the_rules_of_those_configurations(
    seed, self_collision, rows, hub
):
    """``broken`` on ``Posed[idx]`` at another margin and the rows' stock, any subset of
    the rules, equals :func:`clearance` of those configurations alone."""
    cell, q, P, _ = _case(seed, self_collision, rows, hub, n=300)
    rng = np.random.default_rng(100 + seed)
    at = Posed.of(cell, q, P)
    for margin in (-0.03, 0.005, 0.03):
        idx = np.sort(rng.choice(len(q), 120, replace=False))
        stock = cell.stock.take(idx) if rows else cell.stock
        want = clearance(dataclasses.replace(cell, margin=margin, stock=stock), q[idx], P[idx])
        only = [k for k in RULES if rng.random() < 0.5]
        got = broken(cell, at[idx], margin=margin, stock=stock, only=only)
        assert list(got) == [k for k in want if k in only]
        for key in got:
            np.testing.assert_array_equal(got[key], want[key], err_msg=key)
        assert list(broken(cell, at[idx], margin, stock)) == list(want)
        assert sum(int(v.sum()) for v in want.values()) > 5  # rules break in the batch
