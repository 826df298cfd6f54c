"""Placement search and setups (issue 13), each verified by the planner and MuJoCo."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.geometry import se3
from ruledrobot.io.trajectory import read_trajectory
from ruledrobot.place.job_file import write_job_file
from ruledrobot.place.regions import Placement, moved_job
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan
from tests.wirecut.reach_jobs import LONG_JOB, demo_at

runner = CliRunner()


def _in_block(job, k: int = 0) -> np.ndarray:
    """The cut surface's pose in the block's own frame (what a placement keeps)."""
    return se3.inverse(job.stock.pose) @ job.cuts[k].surface.pose


def test_place_moves_a_block_out_of_reach_to_where_the_plan_passes(tmp_path):
    src = tmp_path / "far.toml"
    src.write_text(demo_at(1.25))
    job = load_job(src)
    assert not plan(job, None, simulate=False).feasible  # where the user put it
    out = tmp_path / "placed"
    res = runner.invoke(app, ["place", str(src), "--x", "0.3:1.3", "--y", "-0.4:0.4",
                              "--yaw", "-90:90", "--grid", "5x5x5", "--refine", "1",
                              "--turns", "", "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "as the job places it: worst margin -" in text and "out of reach" in text
    doc = json.loads((out / "place.json").read_text())
    assert doc["ok"] and doc["as_placed"]["margin_mm"] < 0
    best = doc["ranked"][0]
    assert best["margin_mm"] > 0 and doc["verified"]["chosen"] == best
    assert doc["search"]["evaluated"] >= 125 and doc["search"]["rulings_per_candidate"] == 48
    # the job file: the block where the search put it, the surface moved with it
    placed = load_job(out / "job.toml")
    np.testing.assert_allclose(placed.stock.centre[:2], [best["x_m"], best["y_m"]], atol=1e-6)
    np.testing.assert_allclose(_in_block(placed), _in_block(job), atol=1e-6)
    assert "# ruledrobot demo job" in (out / "job.toml").read_text()  # comments kept
    # verified: the plan of that file passed the planner and MuJoCo, and left a program
    report = json.loads((out / "plan" / "report.json").read_text())
    assert report["verdict"]["ok"] and report["max_wire_deviation_mm"] <= 0.5
    assert read_trajectory(out / "plan" / "trajectory.csv").meta.job["path"].endswith("job.toml")
    assert (out / "cut.script").exists() and (out / "margin.png").stat().st_size > 10_000


def test_no_placement_in_the_region_is_reported_with_the_best_margin(tmp_path):
    src = tmp_path / "job.toml"
    src.write_text(demo_at(0.5))
    out = tmp_path / "nowhere"
    res = runner.invoke(app, ["place", str(src), "--x", "1.4:1.7", "--y", "-0.2:0.2",
                              "--yaw", "-30:30", "--grid", "3x3x3", "--refine", "1",
                              "--out", str(out)])  # fmt: skip
    assert res.exit_code == 1, res.output
    text = " ".join(res.output.split())
    assert "no placement in the region serves the job: the best worst margin found is -" in text
    doc = json.loads((out / "place.json").read_text())
    assert not doc["ok"] and doc["ranked"][0]["margin_mm"] < -100  # far beyond the reach
    assert doc["verified"] is None and not (out / "job.toml").exists()
    assert "out of reach" in doc["lines"][2]


def test_a_job_that_needs_two_setups(tmp_path):
    """The long block's two ends: no placement serves both, a half turn between two setups
    does, each setup verified by the planner and MuJoCo.  The cuts are refined two steps
    (half the rulings of LONG_JOB's three) and candidates scored on 24 rulings: what is
    proved is the grouping and the turn, which do not need the finer cut."""
    src = tmp_path / "long.toml"
    src.write_text(LONG_JOB.replace("steps = 3", "steps = 2"))
    job = load_job(src)
    out = tmp_path / "setups"
    res = runner.invoke(app, ["place", str(src), "--x", "0.7:0.8", "--y", "-0.1:0.1",
                              "--yaw", "-10:10", "--grid", "3x3x3", "--refine", "1",
                              "--rulings", "24", "--turns", "z180", "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "place.json").read_text())
    assert doc["ranked"][0]["margin_mm"] < 0  # no single placement serves both ends
    setups = doc["setups"]
    assert [s["cuts"] for s in setups] == [["near end"], ["far end"]]
    assert all(s["passes"] for s in setups)
    steps = (out / "setups.txt").read_text()
    assert "Turn it 180 deg" in steps and "corner A at" in steps
    for k, name in ((1, "near end"), (2, "far end")):
        placed = load_job(out / f"setup{k}" / "job.toml")
        assert [c.name for c in placed.cuts] == [name]
        i = [c.name for c in job.cuts].index(name)
        np.testing.assert_allclose(_in_block(placed), _in_block(job, i), atol=1e-6)
        report = json.loads((out / f"setup{k}" / "plan" / "report.json").read_text())
        assert report["verdict"]["ok"]
    # between the setups the block turned half a turn about the vertical
    R1 = load_job(out / "setup1" / "job.toml").stock.rotation
    R2 = load_job(out / "setup2" / "job.toml").stock.rotation
    assert (R1.T @ R2)[0, 0] == pytest.approx(-1.0, abs=1e-6)


@pytest.mark.parametrize(("args", "message"), [
    (["--x", "a:b"], "--x: expected LOW:HIGH"),
    (["--yaw", "10:-10"], "--yaw: expected LOW:HIGH with LOW <= HIGH"),
    (["--turns", "z45"], "--turns: expected items like z90"),
    (["--grid", "9x9"], "--grid: expected NXxNYxNYAW"),
    (["--move", "table"], "--move: expected stock or robot"),
])  # fmt: skip
def test_bad_options_exit_2_and_say_what_was_expected(tmp_path, args, message):
    src = tmp_path / "job.toml"
    src.write_text(demo_at(0.5))
    res = runner.invoke(app, ["place", str(src), "--out", str(tmp_path / "o"), *args])
    assert res.exit_code == 2 and message in " ".join(res.output.split())


def test_the_robot_can_move_instead(tmp_path):
    src = tmp_path / "job.toml"
    src.write_text(demo_at(1.25))
    out = tmp_path / "robot"
    res = runner.invoke(app, ["place", str(src), "--move", "robot", "--x", "0:0.8",
                              "--y", "-0.2:0.2", "--yaw", "0", "--grid", "5x3x1",
                              "--refine", "0", "--no-verify", "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads((out / "place.json").read_text())
    best = doc["ranked"][0]
    assert doc["move"] == "robot" and best["margin_mm"] > 0 and best["x_m"] > 0.2
    # in the new base frame the block is nearer by the robot's move
    placed = load_job(out / "job.toml")
    assert placed.stock.centre[0] == pytest.approx(1.25 - best["x_m"], abs=1e-6)
    # ... and the base moved by it, so in the world (base @ stock) the block stays put
    np.testing.assert_allclose(placed.robot.base[:3, 3], [best["x_m"], best["y_m"], 0.0],
                               atol=1e-6)  # fmt: skip
    world = placed.robot.base[:3, :3] @ placed.stock.centre + placed.robot.base[:3, 3]
    np.testing.assert_allclose(world, load_job(src).stock.centre, atol=1e-6)


def test_job_files_keep_comments_rebase_paths_and_drop_cuts(tmp_path):
    from ruledrobot.geometry.surfaces import sample_surface
    from ruledrobot.io.lines import save_lines

    (tmp_path / "data").mkdir()
    save_lines(tmp_path / "data" / "rulings.json",
               sample_surface("hyperbolic_paraboloid", n=9, start=-0.12, stop=0.12, c=0.4).lines)
    text = LONG_JOB.replace('builtin = "hyperbolic_paraboloid"\nparams = { c = 0.4 }\n'
                            'u = [-0.14, 0.14]\npose = [1.1',
                            'file = "data/rulings.json"\npose = [1.1')  # fmt: skip
    src = tmp_path / "long.toml"
    src.write_text(text)
    job = load_job(src)
    T = Placement(0.6, 0.1, 0.5).transform(job)
    moved = moved_job(job, T)
    (tmp_path / "out" / "deeper").mkdir(parents=True)
    path = write_job_file(moved, tmp_path / "out" / "deeper" / "all.toml", note="moved")
    written = path.read_text()
    assert written.startswith("# moved\n") and "# the end towards the robot" in written
    assert 'file = "../../data/rulings.json"' in written
    back = load_job(path)
    for k in range(2):
        np.testing.assert_allclose(back.cuts[k].surface.pose, T @ job.cuts[k].surface.pose,
                                   atol=1e-8)  # fmt: skip
        np.testing.assert_allclose(back.cuts[k].keep, T[:3, :3] @ job.cuts[k].keep + T[:3, 3])
    import dataclasses

    one = dataclasses.replace(moved, cuts=(moved.cuts[1],))
    path = write_job_file(one, tmp_path / "out" / "far.toml", keep_cuts=[1])
    back = load_job(path)
    assert [c.name for c in back.cuts] == ["far end"] and "near end" not in path.read_text()


def test_region_edges_name_the_option_to_widen():
    from ruledrobot.place.regions import Region

    r = Region((0.5, 1.0), (-0.2, 0.2), (-1.0, 1.0))
    assert r.edges(np.array([0.7, 0.0, 0.0])) == ""
    assert r.edges(np.array([0.5, 0.2, 0.0])) == "the low end of --x, the high end of --y"
    assert r.edges(np.array([0.7, 0.0, -1.0])) == "the low end of --yaw"
    fixed = Region((0.5, 0.5), (-0.2, 0.2), (-np.pi, np.pi))  # one x; yaw a whole turn
    assert fixed.edges(np.array([0.5, 0.0, np.pi])) == ""
