"""The arm against itself (clearance.ARM_ARM) and the bow against every link, in a cell with
``self_collision`` (the transits'): no false positive at the arm's home configuration, a
wrist folded into the upper arm caught (and MuJoCo agrees), the pairs left out are MuJoCo's
own exclusions and the pairs that overlap at every configuration — measured here over
random configurations — and no contact MuJoCo finds at random configurations is missed."""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ruledrobot.geometry.segments import segment_distance
from ruledrobot.robot.arm.catalogue import MODEL_NAMES, load
from ruledrobot.robot.arm.shape import arm_capsules
from ruledrobot.sim import Scene
from ruledrobot.sim._mujoco import mujoco
from ruledrobot.sim.mjcf import robot_mjcf
from ruledrobot.wirecut.cut.clearance import (
    ARM_ARM,
    BOW_ARM,
    RULES,
    Cell,
    base_capsule,
    clearance,
    self_pairs,
)
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job

HOME = np.array([0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, 0.0])
#: the elbow bent 160 degrees, wrist straight: wrists 2 and 3 fold into the upper arm
FOLDED = np.array([0.0, -np.pi / 2, 2.8, 0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def demo():
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    cell = Cell.of(model, job.tool, job.stock, 0.0, 0.005, 0.0, None)
    return job, model, dataclasses.replace(cell, self_collision=True)


def _rules(cell: Cell, q: np.ndarray) -> dict[str, bool]:
    q = np.atleast_2d(q)
    return {k: bool(v[0]) for k, v in clearance(cell, q, cell.model.fk(q)).items()}


def _contacts(mj, m, q: np.ndarray) -> set[tuple[str, str]]:
    """MuJoCo's contacts (body pairs, sorted names) at the configuration ``q``."""
    d = mj.MjData(m)
    d.qpos[: len(q)] = q
    mj.mj_kinematics(m, d)
    mj.mj_collision(m, d)
    body = int(mj.mjtObj.mjOBJ_BODY)
    names = lambda g: mj.mj_id2name(m, body, int(m.geom_bodyid[g]))  # noqa: E731
    return {tuple(sorted((names(c.geom1), names(c.geom2)))) for c in d.contact[: d.ncon]}


def test_the_rule_is_listed_and_only_in_a_self_collision_cell(demo):
    cell = demo[2]
    assert RULES[-1] == ARM_ARM
    assert ARM_ARM in _rules(cell, HOME)
    plain = dataclasses.replace(cell, self_collision=False)  # the wire-pose search's cell
    assert ARM_ARM not in _rules(plain, HOME)


@pytest.mark.parametrize("name", MODEL_NAMES)
def test_no_false_positive_at_home(name):
    """Every catalogue arm with the demo bow: the home configuration breaks no rule of the
    arm against itself or the bow against it (margin 5 mm); MuJoCo agrees (UR5e)."""
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = load(name)
    cell = dataclasses.replace(Cell.of(model, job.tool, job.stock, 0.0, 0.005, 0.0, None),
                               self_collision=True)  # fmt: skip
    rules = _rules(cell, HOME)
    assert not rules[ARM_ARM] and not rules[BOW_ARM], rules


def test_home_is_clear_in_mujoco_and_a_folded_wrist_is_caught(demo):
    job, model, cell = demo
    mj = mujoco()
    arm = mj.MjModel.from_xml_string(robot_mjcf(model))
    scene = mj.MjModel.from_xml_string(Scene.from_job(job, robot=model).mjcf())
    assert _contacts(mj, arm, HOME) == set() and _contacts(mj, scene, HOME) == set()
    assert not any(_rules(cell, HOME).values())
    # the folded wrist: the planner's rule and MuJoCo's arm alone (no bow, no table)
    assert _rules(cell, FOLDED)[ARM_ARM]
    touching = _contacts(mj, arm, FOLDED)
    assert touching and all("link2" in pair for pair in touching), touching
    assert touching <= {("link2", "link5"), ("link2", "link6")}


def _mjcf_excludes(model) -> set[tuple[int, int]]:
    """The body pairs the MuJoCo model excludes, as body indices (-1 the base, k link k+1)."""
    root = ET.fromstring(robot_mjcf(model))
    index = {"base": -1, **{f"link{k + 1}": k for k in range(model.n_joints)}}
    return {tuple(sorted((index[e.get("body1")], index[e.get("body2")])))
            for e in root.iter("exclude")}  # fmt: skip


@pytest.mark.parametrize("name", ["ur5e", "ur10e", "ur3"])
def test_the_pairs_left_out_are_neighbours_and_mujocos_exclusions(name):
    model = load(name)
    _, _, body = arm_capsules(model, np.zeros(6))
    b = np.r_[-1, body]
    I, J = self_pairs(model, b)
    tested = {(int(b[i]), int(b[j])) for i, j in zip(I, J, strict=True)}
    excluded = _mjcf_excludes(model)
    assert excluded == {(-1, 0), (-1, 1), (2, 4), (3, 5)}
    for i in range(-1, 6):
        for j in range(i + 1, 6):
            left_out = j == i + 1 or (i, j) in excluded
            assert ((i, j) in tested) != left_out, (i, j)


def test_no_tested_pair_overlaps_at_every_configuration(demo):
    """Measured: over 2,000 random configurations every capsule pair the rule tests is
    clear of each other at some configuration (none would fail everywhere), while some
    capsules of every pair of joint neighbours, and the base with the shoulder, overlap at
    every one (they must be left out)."""
    _, model, cell = demo
    rng = np.random.default_rng(7)
    q = rng.uniform(np.maximum(model.lower, -2 * np.pi), np.minimum(model.upper, 2 * np.pi),
                    (2000, 6))  # fmt: skip
    ends, radius, body = arm_capsules(model, q)
    axis, r0 = base_capsule(model)
    e = np.concatenate([np.broadcast_to(axis, (len(q), 1, 2, 3)), ends], axis=1)
    r, b = np.r_[r0, radius], np.r_[-1, body]
    I, J = np.triu_indices(len(b), 1)
    gap = segment_distance(e[:, I, 0], e[:, I, 1], e[:, J, 0], e[:, J, 1]) - r[I] - r[J]
    always = (gap < cell.margin).all(axis=0)
    TI, TJ = self_pairs(model, b)
    tested = set(zip(TI.tolist(), TJ.tolist(), strict=True))
    for k, (i, j) in enumerate(zip(I.tolist(), J.tolist(), strict=True)):
        if always[k]:
            assert (i, j) not in tested, (b[i], b[j])
    # the body pairs that overlap everywhere: joint neighbours, and the base with the
    # shoulder housing (MuJoCo's base-link2 exclusion)
    overlapping = {(int(b[i]), int(b[j])) for k, (i, j) in enumerate(zip(I, J, strict=True))
                   if always[k] and b[i] != b[j]}  # fmt: skip
    assert overlapping == {(-1, 0), (-1, 1), (0, 1), (1, 2), (2, 3), (3, 4), (4, 5)}


def test_every_mujoco_contact_at_random_configurations_is_caught(demo):
    """1,000 random configurations in the demo's cell: wherever MuJoCo finds a link
    touching another link, the base or the bow, the planner's rules say so too (the
    rules are the stricter: a 5 mm margin and capsules for cylinders)."""
    job, model, cell = demo
    mj = mujoco()
    m = mj.MjModel.from_xml_string(Scene.from_job(job, robot=model).mjcf())
    rng = np.random.default_rng(11)
    q = rng.uniform(np.maximum(model.lower, -2 * np.pi), np.minimum(model.upper, 2 * np.pi),
                    (1000, 6))  # fmt: skip
    rules = clearance(cell, q, model.fk(q))
    arm_mj = np.zeros(len(q), bool)
    bow_mj = np.zeros(len(q), bool)
    for k in range(len(q)):
        for pair in _contacts(mj, m, q[k]):
            if "world" in pair:
                continue
            if "bow" in pair:
                bow_mj[k] = True
            else:
                arm_mj[k] = True
    assert arm_mj.sum() > 100 and bow_mj.sum() > 100  # the sample does fold the arm
    assert not (arm_mj & ~rules[ARM_ARM]).any()
    assert not (bow_mj & ~rules[BOW_ARM]).any()
