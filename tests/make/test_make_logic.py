"""make's own logic with carve and the planner stood in for (tests/make/fakes.py): setups in
order, a program per setup, what to do by hand, a failed setup named and nothing runnable
left, the summary, the exit codes."""

from __future__ import annotations

from typer.testing import CliRunner

from ruledrobot.carve.demo import write_demo_cell
from ruledrobot.cli import app
from ruledrobot.io.outdir import read_manifest

from .fakes import read, stub


def _run(tmp_path, *args):
    cell = write_demo_cell(tmp_path / "part")
    out = tmp_path / "made"
    return CliRunner().invoke(app, ["make", str(cell), "--out", str(out), *args]), out


def test_two_setups_that_pass_give_two_programs_and_the_steps_between(tmp_path, monkeypatch):
    stub(monkeypatch, setups=2)
    res, out = _run(tmp_path)
    assert res.exit_code == 0, res.output
    for k in (1, 2):
        assert (out / f"setup{k}" / "cut.script").is_file()
        assert (out / f"setup{k}" / "trajectory.csv").is_file()
        assert (out / f"setup{k}" / "trajectory.json").is_file()
        assert (out / f"setup{k}" / "report.json").is_file()
        assert (out / "view" / f"setup{k}.html").is_file()
    doc = read(out / "make.json")
    assert doc["ok"] and [s["setup"] for s in doc["setups"]] == [1, 2]
    assert doc["setups"][1]["program"]["file"] == "setup2/cut.script"
    assert doc["totals"]["duration_s"] == 21.0 + 22.0
    assert doc["totals"]["cut_duration_s"] == 20.0  # the cuts' own passes, not the transits
    steps = (out / "setups.txt").read_text()
    assert "Setup 1: clamp the 200 x 200 x 150 mm block" in steps
    assert "setup 1's loop loop1 freed and put it back in its place" in steps
    assert "Run setup2/cut.script (cut: loop2 (rough, closed))" in steps
    # the summary: setups, cuts, verdicts, excess, time, by hand, the verdict line
    text = " ".join(res.output.split())
    for words in ("2 cuts in 2 setups", "loop1", "loop2", "PASS", "excess material: 5.00 %",
                  "robot time: 43.0 s", "by hand", "make: PASS — 2 setups"):  # fmt: skip
        assert words in text, words
    # every file listed, the setup folders' own manifests too (the program added)
    man = read_manifest(out)
    assert "setup2/cut.script" in man["files"] and man["ok"] is True
    assert "cut.script" in read_manifest(out / "setup1")["files"]


def test_a_failed_setup_is_named_and_no_setup_keeps_a_program(tmp_path, monkeypatch):
    stub(monkeypatch, setups=2, failing={2})
    res, out = _run(tmp_path)
    assert res.exit_code == 1, res.output
    text = " ".join(res.output.split())
    assert "setup 2 fails (reach)" in text and "out of reach by 379 mm" in text
    doc = read(out / "make.json")
    assert not doc["ok"] and doc["failed_setups"] == [2]
    assert doc["setups"][1]["failed"] == [{"name": "reach", "detail": "out of reach by 379 mm"}]
    runnable = [p.relative_to(out).as_posix() for p in out.rglob("*")
                if p.name in ("cut.script", "trajectory.csv", "trajectory.json", "simulated.csv")]
    assert runnable == []
    assert not (out / "setups.txt").exists()
    assert doc["setups"][0]["program"]["file"] is None  # written, then taken
    assert doc["setups"][0]["program"]["what"].endswith("removed: make: setup 2 fails")
    assert "setup1/cut.script" not in text and "removed" in text
    assert doc["hand_steps"][0].endswith("Nothing to run: make: setup 2 fails (cut: loop1 (rough, "
                                         "closed)).")  # fmt: skip
    # setup 1 passed: its folder stays (report, job) and its manifest says what went and why
    man = read_manifest(out / "setup1")
    assert set(man["files"]) == {"job.toml", "report.json", "simulation/report.json"}
    assert man["runnable_removed"] == "make: setup 2 fails"
    assert set(read_manifest(out)["files"]) >= {"make.json", "setup1/report.json",
                                                "setup2/report.json", "carve/carve.json"}


def test_a_failed_carve_plans_nothing(tmp_path, monkeypatch):
    stub(monkeypatch, setups=1, carve_ok=False)
    res, out = _run(tmp_path)
    assert res.exit_code == 1, res.output
    assert "make: FAIL — carve fails: no_gouge" in " ".join(res.output.split())
    assert not (out / "setup1").exists() and read(out / "make.json")["setups"] == []


def test_a_failed_run_replaces_an_earlier_one_whole(tmp_path, monkeypatch):
    stub(monkeypatch, setups=1)
    res, out = _run(tmp_path)
    assert res.exit_code == 0 and (out / "setup1" / "cut.script").is_file()
    stub(monkeypatch, setups=1, failing={1})
    res, out = _run(tmp_path)
    assert res.exit_code == 1
    assert not (out / "setup1" / "cut.script").exists()
    assert not (out / "setup1" / "trajectory.csv").exists()


def test_a_setup_without_a_pendant_program_passes_and_is_streamed(tmp_path, monkeypatch):
    import ruledrobot.make.run
    from ruledrobot.make.program import no_program

    stub(monkeypatch, setups=1)
    monkeypatch.setattr(ruledrobot.make.run, "write_program",
                        lambda traj, folder: no_program("movep: refused; servoj: too long"))
    res, out = _run(tmp_path)
    assert res.exit_code == 0, res.output
    text = " ".join(res.output.split())
    assert "no pendant program (movep: refused; servoj: too long)" in text
    assert "Stream setup1/trajectory.csv (ruledrobot run setup1/trajectory.csv" in text
    assert (out / "setup1" / "trajectory.csv").is_file()
    assert not (out / "setup1" / "cut.script").exists()
    assert read(out / "make.json")["setups"][0]["program"] == {
        "file": None, "mode": None, "what": "movep: refused; servoj: too long"}
