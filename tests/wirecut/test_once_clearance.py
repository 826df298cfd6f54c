"""The clearance rules in one batch (issue 25): the vectorised :func:`clearance` against
the rules checked capsule by capsule, and transits' moves checked in batches against one
at a time."""

from __future__ import annotations

import numpy as np

from ruledrobot.geometry.box import Box
from ruledrobot.geometry.segments import segment_distance
from ruledrobot.robot.arm.shape import arm_capsules
from ruledrobot.robot.tool import BowTool
from ruledrobot.wirecut.cut.clearance import _BODIES_NEAR_BOW, Cell, clearance
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion.transit import TransitPlanner


def _one_at_a_time(cell: Cell, q, P) -> dict[str, np.ndarray]:
    """The rules as they were written before (a segment test per capsule), the bow's
    table rule with the rods' radius (a capsule lowest at an end less its radius) and the
    hub's rim sampled at 4,096 points."""
    stock, margin = cell.stock, cell.margin
    qf = np.nan_to_num(q.reshape(-1, 6))
    Pf = P.reshape(-1, 4, 4)
    rods = np.concatenate([cell.rods, cell.wire[None]], axis=0)
    w = np.einsum("nij,kej->nkei", Pf[:, :3, :3], rods) + Pf[:, None, None, :3, 3]
    ends, radius, body = arm_capsules(cell.model, qf)
    n = len(qf)
    bow = stock.segment_hits(w[:, :3, 0], w[:, :3, 1], margin + BowTool.arm_radius).any(axis=1)
    h = np.einsum("nij,ej->nei", Pf[:, :3, :3], cell.hub) + Pf[:, None, :3, 3]
    bow |= stock.segment_hits(h[:, 0], h[:, 1], margin + cell.hub_radius)
    out = {"bow hits the stock": bow, "arm hits the stock": np.zeros(n, bool),
           "bow or wire hits the arm": np.zeros(n, bool)}  # fmt: skip
    for k in range(len(radius)):
        a, b = ends[:, k, 0], ends[:, k, 1]
        out["arm hits the stock"] |= stock.segment_hits(a, b, margin + radius[k])
        if body[k] in _BODIES_NEAR_BOW:
            dist = segment_distance(a[:, None], b[:, None], w[:, :, 0], w[:, :, 1])
            out["bow or wire hits the arm"] |= (dist < radius[k] + BowTool.arm_radius
                                                + margin).any(axis=1)  # fmt: skip
    # the rods' and the hub's solids, each capsule alone (the rods' radius, the hub's)
    below = np.zeros(n, bool)
    for k in range(3):
        below |= (w[:, k, :, 2] - BowTool.arm_radius < cell.table_z + margin).any(axis=1)
    # the hub a cylinder: its lowest point on a rim, over 64 points of each end's rim
    axis = (h[:, 1] - h[:, 0]) / np.linalg.norm(h[:, 1] - h[:, 0], axis=1)[:, None]
    e1 = np.cross(axis, [0.3, 0.5, 0.8])
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(axis, e1)
    ang = np.linspace(0.0, 2 * np.pi, 4096, endpoint=False)
    rim_z = cell.hub_radius * (np.cos(ang)[None] * e1[:, 2:] + np.sin(ang)[None] * e2[:, 2:])
    below |= (h[:, :, 2].min(axis=1) + rim_z.min(axis=1) < cell.table_z + margin - 1e-6)
    out["bow below the table"] = below
    up = body >= 1
    low = ends[:, up][..., 2].min(axis=2) - radius[up]
    out["arm below the table"] = (low < cell.table_z + margin).any(axis=1)
    return {key: v.reshape(q.shape[:-1]) for key, v in out.items()}


def test_the_batched_rules_are_the_rules_one_capsule_at_a_time():
    job = parse_job(job_document(DEMO_JOB, "demo"))
    model = job.robot_model()
    rng = np.random.default_rng(7)
    seen = 0
    for _ in range(12):
        stock = Box(np.r_[rng.uniform(-0.5, 0.5, 2), rng.uniform(0.0, 0.6)],
                    rng.uniform(0.1, 0.6, 3))  # fmt: skip
        cell = Cell.of(model, job.tool, stock, 0.0, 0.005, 0.02, None)
        q = rng.uniform(-3.2, 3.2, (4, 50, 6))
        q[0, 0, 0] = np.nan  # an IK failure: checked as zeros, as before
        P = model.fk(np.nan_to_num(q))
        got, want = clearance(cell, q, P), _one_at_a_time(cell, q, P)
        assert list(got) == list(want)
        for key in got:
            np.testing.assert_array_equal(got[key], want[key], err_msg=key)
            seen += int(got[key].sum())
    assert seen > 100  # the random cells break every kind of rule somewhere


def test_moves_checked_in_a_batch_are_each_move_checked_alone():
    job = parse_job(job_document(DEMO_JOB, "demo"))
    model = job.robot_model()
    transit = TransitPlanner.of(job, model)
    rng = np.random.default_rng(3)
    moves = [(rng.uniform(-3, 3, 6), rng.uniform(-3, 3, 6)) for _ in range(20)]
    moves += [(np.zeros(6), np.full(6, 0.01))]
    assert transit.clear_moves(moves).tolist() == [transit.clear(a, b) for a, b in moves]
