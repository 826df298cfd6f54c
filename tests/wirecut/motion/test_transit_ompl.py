"""Transits found by OMPL (wirecut.motion.transit_ompl) and transits that cannot be made.

* OMPL's planner calls the Python motion validator and keeps to its answers (a wall with
  a gap in a plane), and a seeded search gives the same route every time;
* a route from one side of the demo's block to the other, and a transit between two cuts
  on opposite sides of a block (over-the-top switched off, so OMPL routes it), checked
  independently in MuJoCo: every configuration of the planned legs, sampled finer than
  the planner samples them, has no contact at all in the job's cell (arm, base, bow, wire,
  table, stock) and the wire (MuJoCo's wire sites) stays out of the block;
* a transit the arm cannot make — home inside the table, home with the wire in the block —
  fails the plan: no motion is kept, and the ``transits`` check names the transit's passes
  and the bodies in the way, in ``report.json`` and in the printed verdict; a search that
  runs out of time says so and names what the direct move hits.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.io.demo_cell import DEMO_CELL
from ruledrobot.sim import Scene
from ruledrobot.sim._mujoco import mujoco
from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job
from ruledrobot.wirecut.motion import transit as transit_module
from ruledrobot.wirecut.motion.transit import TransitFailure, TransitNotFound, TransitPlanner
from ruledrobot.wirecut.motion.transit_ompl import rrt_connect
from ruledrobot.wirecut.plan import make_plan, transit_between
from ruledrobot.wirecut.report.outcome import plan_outcome

runner = CliRunner()

#: an upright, nearly flat face cut off the block at ``x`` (the 'side' cut of the part demo)
_CUT = """
[[cut]]
name = "{name}"
feed_speed = 0.012
approach_speed = 0.6
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = {{ c = 1.0 }}
u = [-0.1, 0.1]
rulings = 9
pose = [{x}, 0.0, 0.3, 0.0, 1.5707963267948966, 0.0]
steps = 3
"""
#: two faces on opposite sides of the demo's block, 4.5 cm either side of its centre
TWO_SIDES = DEMO_CELL + "mass = 1.0\n" + _CUT.format(name="near", x=0.455) + _CUT.format(
    name="far", x=0.545)  # fmt: skip


def _dense(q: np.ndarray, step: float = 5e-4) -> np.ndarray:
    """The straight joint moves between consecutive rows of ``q`` (K, J), every ``step``
    rad (max norm) at most: finer than the planner's own samples (1.4e-3 rad)."""
    out = [q[:1]]
    for a, b in itertools.pairwise(q):
        n = max(1, int(np.ceil(np.abs(b - a).max() / step)))
        out.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.concatenate(out)


def _mujoco_check(job, model, q: np.ndarray) -> tuple[set, int]:
    """MuJoCo's contacts (body pairs) at the configurations ``q`` (n, 6) in the job's cell,
    and how many of them hold the wire in the block: MuJoCo's wire sites, 201 points of
    the wire between them tested against the block in its own frame."""
    mj = mujoco()
    m = mj.MjModel.from_xml_string(Scene.from_job(job, robot=model).mjcf())
    d = mj.MjData(m)
    body = int(mj.mjtObj.mjOBJ_BODY)
    site = int(mj.mjtObj.mjOBJ_SITE)
    s0, s1 = mj.mj_name2id(m, site, "wire_start"), mj.mj_name2id(m, site, "wire_end")
    stock = job.stock
    R, c, half = stock.rotation, stock.centre, 0.5 * np.asarray(stock.size)
    u = np.linspace(0.0, 1.0, 201)[None, :, None]
    contacts = set()
    ends = np.empty((len(q), 2, 3))
    for k in range(len(q)):
        d.qpos[:6] = q[k]
        mj.mj_kinematics(m, d)
        mj.mj_collision(m, d)
        for con in d.contact[: d.ncon]:
            contacts.add(tuple(sorted(
                mj.mj_id2name(m, body, int(m.geom_bodyid[g])) for g in (con.geom1, con.geom2))))
        ends[k, 0], ends[k, 1] = d.site_xpos[s0], d.site_xpos[s1]
    wire_in = 0
    for e in np.array_split(ends, max(1, len(ends) // 2000)):  # 2,000 wires at a time
        a, b = e[:, :1], e[:, 1:]
        local = (a + u * (b - a) - c) @ R  # the wire's points (n, 201, 3) in the block's frame
        wire_in += int((np.abs(local) < half).all(axis=2).any(axis=1).sum())
    return contacts, wire_in


@pytest.fixture(scope="module")
def demo():
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    (cp,) = cut_paths(job, None, model)
    return job, model, cp, TransitPlanner.of(job, model)


def test_ompl_calls_the_python_motion_validator_and_keeps_to_it():
    """A plane with a wall at x = 0 open only for |y| > 0.8: the route from (-0.9, 0) to
    (0.9, 0) goes round it; every move OMPL kept was one the validator passed."""
    calls: list[tuple[np.ndarray, np.ndarray]] = []

    def free(q):
        return not (abs(q[0]) < 0.1 and abs(q[1]) < 0.8)

    def clear(a, b):
        calls.append((a, b))
        return all(free(p) for p in a + np.linspace(0, 1, 200)[:, None] * (b - a))

    args = (np.array([-0.9, 0.0]), np.array([0.9, 0.0]), np.full(2, -1.0), np.full(2, 1.0),
            free, clear)  # fmt: skip
    route = rrt_connect(*args, time_limit=2.0, step=0.3, seed=1)
    assert route is not None and len(calls) > 0
    np.testing.assert_array_equal(route[0], [-0.9, 0.0])
    np.testing.assert_array_equal(route[-1], [0.9, 0.0])
    assert max(abs(p[1]) for p in route) > 0.8  # round the wall
    for a, b in itertools.pairwise(route):
        assert clear(a, b)
    again = rrt_connect(*args, time_limit=2.0, step=0.3, seed=1)
    assert len(again) == len(route)
    assert all(np.array_equal(a, b) for a, b in zip(again, route, strict=True))


def test_ompl_is_not_loaded_by_planning_without_a_search():
    code = ("import sys\nimport ruledrobot.wirecut.plan\nimport ruledrobot.wirecut.motion.transit\n"
            "print('ompl' in sys.modules)")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_the_step_cannot_pass_through_the_thinnest_body(demo):
    """The step between checked samples is the bow's rod radius (8 mm, the thinnest body;
    below twice the 5 mm margin); the reach per radian bounds every point's speed."""
    _, model, cp, tp = demo
    assert tp.step == pytest.approx(0.008)
    assert tp.resolution == pytest.approx(0.008 / tp.reach.sum())
    assert 1e-3 < tp.resolution < 2e-3
    rng = np.random.default_rng(3)
    q = rng.uniform(tp.lower, tp.upper, (300, 6))
    from ruledrobot.geometry.se3 import transform_points
    from ruledrobot.robot.arm.shape import arm_capsules

    def points(q):
        ends, _, _ = arm_capsules(model, q)
        tool = np.concatenate([tp.cell.rods, tp.cell.wire[None], tp.cell.hub[None]])
        w = transform_points(model.fk(q)[:, None], tool)
        return np.concatenate([ends.reshape(len(q), -1, 3), w.reshape(len(q), -1, 3)], axis=1)

    for j in range(6):
        dq = np.zeros(6)
        dq[j] = 1e-6
        speed = np.linalg.norm(points(q + dq) - points(q), axis=-1).max() / 1e-6
        assert speed <= tp.reach[j]
    samples = tp.samples(cp.motion.q[0], cp.motion.q[-1])
    step = np.abs(np.diff(samples, axis=0)) @ tp.reach
    assert step.max() <= tp.step + 1e-12


def test_a_route_from_one_side_of_the_block_to_the_other_is_clear_in_mujoco(demo):
    job, model, cp, tp = demo
    qa, qb = cp.motion.q[0], cp.motion.q[-1]  # the lead-in and lead-out: either side
    assert not tp.clear(qa, qb)
    _, through = _mujoco_check(job, model, _dense(np.array([qa, qb]), 5e-3))
    assert through > 0  # the check sees the direct move's wire in the block
    route = tp.search(qa, qb)
    assert route is not None and len(route) >= 3
    again = tp.search(qa, qb)
    assert len(again) == len(route)
    assert all(np.array_equal(a, b) for a, b in zip(again, route, strict=True))
    q = _dense(np.array(route))
    assert model.within_limits(q).all()
    contacts, wire_in = _mujoco_check(job, model, q)
    assert contacts == set() and wire_in == 0


@pytest.fixture(scope="module")
def two_sides():
    """The two faces planned with the route over the top switched off: OMPL routes the
    transit between them."""
    job = parse_job(job_document(TWO_SIDES, "two.toml"), "two.toml")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(transit_module.TransitPlanner, "lifted", lambda self, q: None)
        plan = make_plan(job)
    return job, plan


def test_a_transit_between_cuts_on_opposite_sides_is_found_and_clear_in_mujoco(two_sides):
    job, plan = two_sides
    assert plan.motion is not None and plan.transit_failures == ()
    notes = [n for n in plan.notes if n.startswith("transit")]
    assert notes and all("around the stock through" in n for n in notes), plan.notes
    _, verdict = plan_outcome(plan, None)
    assert verdict["transits"].ok and verdict["transits"].value == 0
    mo = plan.motion
    rows = np.flatnonzero(mo.labels == "transit")
    assert rows.size
    near, far = (np.flatnonzero(mo.pass_of == k) for k in (0, 1))
    assert near[-1] < rows[0] and rows[-1] < far[0]  # between the two cuts
    # the timed samples lie on straight joint moves: densified between neighbours
    q = _dense(mo.timed.q[rows[0] - 1 : rows[-1] + 2])
    contacts, wire_in = _mujoco_check(job, plan.model, q)
    assert contacts == set() and wire_in == 0


def test_a_failed_transit_is_named_by_its_passes(two_sides):
    job, plan = two_sides
    passes = list(plan.passes)
    end, start = tuple(passes[0].motion.q[-1]), tuple(passes[1].motion.q[0])

    def failure(what, qa=(), qb=()):
        return TransitFailure(what, (), (), ("arm hits the stock",), True, 2.0, qa, qb)

    assert transit_between(job, passes, failure("to far", qb=start)) == "from 'near' to 'far'"
    assert transit_between(job, passes, failure("into far", qb=start)) == (
        "from 'near' to 'far' (the move from its entry pose into the pass)")
    assert transit_between(job, passes, failure("from near", qa=end)) == (
        "from 'near' to 'far' (the move out of the pass to its exit pose)")
    first = tuple(passes[0].motion.q[0])
    assert transit_between(job, passes, failure("into near", qb=first)) == (
        "into 'near' from its entry pose")
    assert transit_between(job, passes, failure("from far", qa=tuple(passes[1].motion.q[-1]))
                           ) == "from 'far' to the end (the move out of the pass to its exit pose)"
    assert failure("x").sentence() == ("transit x: no route found in 2 s (direct, over the "
                                       "stock, OMPL RRT-Connect); the direct move: arm hits "
                                       "the stock")  # fmt: skip


def _with_home(home) -> str:
    return DEMO_JOB.replace('speed_scale = 1.0', 'speed_scale = 1.0\nhome = [' +
                            ", ".join(f"{v:.12g}" for v in home) + "]")  # fmt: skip


def test_home_inside_the_table_fails_the_plan_with_the_transit_named(tmp_path):
    """Home with the forearm down through the table: the approach cannot be made; the
    plan writes no trajectory, exits 1 and its verdict (report.json, the printed table)
    says which transit and what is in the way."""
    job_file = tmp_path / "job.toml"
    job_file.write_text(_with_home([0.0, 0.0, np.pi / 2, 0.0, 0.0, 0.0]))
    out = tmp_path / "out"
    res = runner.invoke(app, ["plan", str(job_file), "--out", str(out)])
    assert res.exit_code == 1, res.output
    report = json.loads((out / "report.json").read_text())
    assert not report["feasible"] and report["verdict"]["failed"] == ["transits"]
    check = next(c for c in report["verdict"]["checks"] if c["name"] == "transits")
    assert check["value"] == 1 and check["limit"] == 0
    assert check["detail"].startswith("transit from home to 'cut': its start: ")
    assert "arm below the table" in check["detail"] and "bow below the table" in check["detail"]
    assert "the direct move: " in check["detail"]
    reach = next(c for c in report["verdict"]["checks"] if c["name"] == "reach")
    assert reach["ok"]
    assert not (out / "trajectory.csv").exists()
    assert "transits" in res.output and "arm below the table" in res.output


def test_a_start_blocked_by_the_stock_fails_the_plan_and_keeps_no_move(demo):
    """Home where the wire runs through the block (a configuration of the cut itself)."""
    _, model, cp, _ = demo
    home = cp.motion.q[len(cp.frames) // 2]
    job = parse_job(job_document(_with_home(home), "demo.toml"), "demo.toml")
    plan = make_plan(job, model)
    assert plan.motion is None and plan.trajectory is None and not plan.reachable
    (failure,) = plan.transit_failures
    assert failure.what == "from home to 'cut'"
    assert failure.start == ("wire in the stock",) and failure.goal == ()
    assert not failure.searched and "wire in the stock" in failure.move
    report, verdict = plan_outcome(plan, None)
    assert [c.name for c in verdict.checks] == ["reach", "transits"]
    assert [c.name for c in verdict.failed] == ["transits"]
    assert verdict["transits"].detail == failure.sentence()
    assert failure.sentence().startswith("transit from home to 'cut': its start: wire in the "
                                         "stock; the direct move: ")  # fmt: skip
    assert failure.sentence() in report["reasons"]


def test_a_search_that_finds_nothing_in_its_time_fails_with_the_direct_moves_bodies(
    demo, monkeypatch
):
    """Start and goal free, over-the-top switched off, a search with no time: the transit
    fails, says the search ran, and names what the direct move (through the block) hits."""
    _, _, cp, tp = demo
    monkeypatch.setattr(TransitPlanner, "lifted", lambda self, q: None)
    hurried = dataclasses.replace(tp, time_limit=1e-4)
    notes: list[str] = []
    with pytest.raises(TransitNotFound) as info:
        hurried.route(cp.motion.q[0], cp.motion.q[-1], notes, "to cut")
    failure = info.value.failure
    assert failure.searched and failure.start == () and failure.goal == ()
    assert "wire in the stock" in failure.move
    assert str(info.value) == failure.sentence()
    assert "no route found in 0.0001 s" in failure.sentence() and notes == []
