"""make's parts on their own: carve's setups in order, the steps by hand, a setup folder
listed again or stripped, the step counter, and the layer rules of the package."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np

import ruledrobot.make
from ruledrobot.carve import CarveResult, load_cell
from ruledrobot.carve.demo import write_demo_cell
from ruledrobot.io.atomic import atomic_write_text
from ruledrobot.io.outdir import StagedFolder, read_manifest
from ruledrobot.make.restage import restage, strip_runnable
from ruledrobot.make.setups import Setup, block_place, hand_steps, setups_of
from ruledrobot.make.steps import Step, StepCounter


def _carved(n: int) -> CarveResult:
    files = {f"job{k}": Path(f"/x/setup{k}/job.toml") for k in range(1, n + 1)}
    cuts = [{"name": f"c{k}", "kind": "rough", "closed": True, "setup": k}
            for k in range(1, n + 1)]  # fmt: skip
    return CarveResult({"cuts": cuts}, None, {"report": Path("/x/carve.json"), **files})  # type: ignore[arg-type]


def test_setups_come_in_their_numbers_order_past_nine():
    setups = setups_of(_carved(11))
    assert [s.number for s in setups] == list(range(1, 12))
    assert [s.job.parent.name for s in setups][-3:] == ["setup9", "setup10", "setup11"]
    assert setups[9].cuts == ("c10",)


def test_the_steps_by_hand_say_where_the_block_goes_and_what_to_put_back(tmp_path):
    cell = load_cell(write_demo_cell(tmp_path))
    setups = [Setup(1, Path("a"), ("top", "loop1"), ("exact", "rough"), (False, True)),
              Setup(2, Path("b"), ("loop2",), ("rough",), (True,))]
    first, second = hand_steps(setups, cell)
    assert first.startswith("Setup 1: clamp the 200 x 200 x 150 mm block with its centre at "
                            "(500, 0, 300) mm")  # fmt: skip
    assert "Run setup1/cut.script (cuts: top (exact), loop1 (rough, closed))" in first
    assert "not turned" in second and "setup 1's loop loop1 freed" in second


def test_a_turned_block_is_said_turned(tmp_path):
    path = write_demo_cell(tmp_path)
    path.write_text(path.read_text().replace("size = [0.2, 0.2, 0.15]",
                                             "size = [0.2, 0.2, 0.15]\nrotvec = [0.0, 0.0, 0.5]"))
    cell = load_cell(path)
    assert not np.allclose(cell.stock.rotation, np.eye(3))
    assert "rotation vector [0, 0, 0.5] rad" in block_place(cell)


def _plan_folder(tmp_path: Path) -> Path:
    with StagedFolder(tmp_path / "setup1") as stage:
        for name in ("report.json", "trajectory.csv", "trajectory.json", "simulation/simulated.csv",
                     "simulation/report.json"):  # fmt: skip
            atomic_write_text(stage.path / name, name)
        return stage.commit({"kind": "plan", "feasible": True})


def test_restage_lists_what_make_added_and_keeps_the_plans_fields(tmp_path):
    folder = _plan_folder(tmp_path)
    atomic_write_text(folder / "cut.script", "def x():\nend\n")
    lines = atomic_write_text(tmp_path / "face0.json", "{}")
    restage(folder, {"setup": 1}, add={"face0.json": lines})
    man = read_manifest(folder)
    assert {"cut.script", "face0.json", "trajectory.csv"} <= set(man["files"])
    assert man["kind"] == "plan" and man["feasible"] is True and man["setup"] == 1
    assert (folder / "face0.json").read_text() == "{}"


def test_strip_takes_what_could_run_and_says_why(tmp_path):
    folder = _plan_folder(tmp_path)
    atomic_write_text(folder / "cut.script", "def x():\nend\n")
    gone = strip_runnable(folder, "make: setup 2 fails")
    assert sorted(gone) == ["cut.script", "simulation/simulated.csv", "trajectory.csv",
                            "trajectory.json"]  # fmt: skip
    assert sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()) \
        == ["manifest.json", "report.json", "simulation/report.json"]
    man = read_manifest(folder)
    assert man["runnable_removed"] == "make: setup 2 fails" and man["kind"] == "plan"
    assert not list(tmp_path.glob(".setup1.staging-*"))


def test_the_step_counter_numbers_steps_and_grows_its_total():
    seen: list[Step] = []
    steps = StepCounter(seen.append, 1)
    say = steps.start("carve")
    say("fitting")
    steps.done("PASS")
    steps.total = 4
    steps.start("plan setup 1")
    assert [(s.index, s.total, s.name, s.message, s.done) for s in seen] == [
        (1, 1, "carve", "", False), (1, 1, "carve", "fitting", False),
        (1, 1, "carve", "PASS", True), (2, 4, "plan setup 1", "", False)]  # fmt: skip


def test_only_the_command_line_imports_make_and_make_uses_the_planners_face():
    root = Path(ruledrobot.make.__file__).parents[1]
    bad = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom) or not node.module:
                continue
            package = ["ruledrobot", *rel.split("/")[:-1]]
            if node.level:
                package = package[: len(package) + 1 - node.level]
            absolute = node.module if not node.level else ".".join([*package, node.module])
            if absolute.startswith("ruledrobot.make") and not rel.startswith(("cli/", "make/")):
                bad.append(f"{rel}: from {absolute}")
            if rel.startswith("make/") and absolute.startswith("ruledrobot.wirecut") \
                    and absolute != "ruledrobot.wirecut":
                bad.append(f"{rel}: from {absolute}")
    assert not bad, bad
