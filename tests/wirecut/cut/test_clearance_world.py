"""The planner's clearance rules against MuJoCo's contacts with the table and the stock.

A configuration where MuJoCo finds the bow (its rods, crossbar or hub) or a link touching
the table or the stock must break the matching rule (:data:`BOW_TABLE`, :data:`ARM_TABLE`,
:data:`BOW_STOCK`, :data:`ARM_STOCK`); the wire in the stock is the cut, not a contact.
The rules were found too lenient this way: the table rule read the bow rods' axes and not
their 8 mm radius, and a transit it passed drove ``bow_arm1`` 0.53 mm into the table.
"""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.sim import Scene
from ruledrobot.sim._mujoco import mujoco
from ruledrobot.sim.scene import STOCK_GEOM, TABLE_GEOM, WIRE_GEOM
from ruledrobot.wirecut.cut.clearance import (
    ARM_STOCK,
    ARM_TABLE,
    BOW_STOCK,
    BOW_TABLE,
    Cell,
    clearance,
)
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job


@pytest.fixture(scope="module")
def world():
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    # margin 0: the rules' own solids against MuJoCo's (the planner's margin only adds)
    cell = Cell.of(model, job.tool, job.stock, 0.0, 0.0, 0.0, None)
    mj = mujoco()
    m = mj.MjModel.from_xml_string(Scene.from_job(job, robot=model).mjcf())
    return model, cell, mj, m


_RULE = {("bow", "table"): BOW_TABLE, ("arm", "table"): ARM_TABLE,
         ("bow", "stock"): BOW_STOCK, ("arm", "stock"): ARM_STOCK}  # fmt: skip


def _world_contacts(mj, m, q: np.ndarray) -> dict[str, bool]:
    """Which of bow/arm touch table/stock at ``q``, by MuJoCo's narrow phase (depth > 0.1 mm)."""
    d = mj.MjData(m)
    d.qpos[: len(q)] = q
    mj.mj_kinematics(m, d)
    mj.mj_collision(m, d)
    geom = int(mj.mjtObj.mjOBJ_GEOM)
    body = int(mj.mjtObj.mjOBJ_BODY)
    out = {BOW_TABLE: False, ARM_TABLE: False, BOW_STOCK: False, ARM_STOCK: False}
    for c in d.contact[: d.ncon]:
        if c.dist > -1e-4:  # a touch within 0.1 mm: MuJoCo's margin, not a collision
            continue
        g = (mj.mj_id2name(m, geom, int(c.geom1)), mj.mj_id2name(m, geom, int(c.geom2)))
        b = (mj.mj_id2name(m, body, int(m.geom_bodyid[c.geom1])),
             mj.mj_id2name(m, body, int(m.geom_bodyid[c.geom2])))  # fmt: skip
        world = {TABLE_GEOM: "table", STOCK_GEOM: "stock"}
        hit = [world[n] for n in g if n in world]
        if not hit:
            continue
        other = 1 if g[0] in world else 0
        if g[other] == WIRE_GEOM or g[other] in world:
            continue
        kind = "bow" if b[other] == "bow" else "arm"
        out[_RULE[kind, hit[0]]] = True
    return out


def test_every_mujoco_contact_with_the_table_or_the_stock_is_caught(world):
    """2,000 random configurations, the shoulder lowered towards the table: each contact
    MuJoCo finds of the bow or a link with the table or the stock breaks the rule of that
    pair (the rules may be stricter: a half-space for the table top, capsules for
    cylinders), and the sample does touch both, with each of bow and arm."""
    model, cell, mj, m = world
    rng = np.random.default_rng(5)
    q = rng.uniform(-np.pi, np.pi, (2000, 6))
    q[:, 1] = rng.uniform(-np.pi, 0.2, len(q))  # shoulder from upright to past horizontal
    rules = clearance(cell, q, model.fk(q))
    found = {k: np.zeros(len(q), bool) for k in (BOW_TABLE, ARM_TABLE, BOW_STOCK, ARM_STOCK)}
    for k in range(len(q)):
        for rule, touched in _world_contacts(mj, m, q[k]).items():
            found[rule][k] = touched
    for rule, hit in found.items():
        assert hit.sum() >= 10, f"the sample never makes MuJoCo report {rule!r}"
        missed = np.flatnonzero(hit & ~rules[rule])
        assert missed.size == 0, f"{rule}: MuJoCo contact the rule misses at q = {q[missed[0]]}"
