"""Finding a batch's jobs, hashing them, and the manifest's rules — no cluster needed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from ruledrobot.batch import BatchInputError, find_jobs
from ruledrobot.batch.content import code_identity, read_content
from ruledrobot.batch.jobs import JobEntry, merge_overrides
from ruledrobot.batch.manifest import (
    JobRecord,
    figures_of,
    load_records,
    resumable,
    write_manifest,
)
from ruledrobot.wirecut.job.load import file_fields, job_document

from .conftest import FAST_JOB, file_job, write_rulings


def _jobs(folder: Path, *names: str, text: str = FAST_JOB) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{n}.toml" for n in names]
    for p in paths:
        p.write_text(text)
    return paths


def test_files_and_globs_name_jobs_by_their_stems(tmp_path):
    a, b = _jobs(tmp_path / "pieces", "a", "b")
    (c,) = _jobs(tmp_path / "more" / "deep", "c")
    found = find_jobs([str(a), str(tmp_path / "pieces" / "b*.toml"),
                       str(tmp_path / "**" / "c.toml")])  # fmt: skip
    assert [(e.name, e.path) for e in found] == [("a", a), ("b", b), ("c", c)]
    assert all(e.label == str(e.path) and not e.overrides for e in found)
    # a glob does not pick up the job.toml copies in the batch's own output folder
    _jobs(tmp_path / "out" / "a", "job")
    found = find_jobs([str(tmp_path / "**" / "*.toml")], exclude=tmp_path / "out")
    assert [e.name for e in found] == ["c", "a", "b"]


def test_a_job_list_names_jobs_with_folder_names_and_overrides(tmp_path):
    _jobs(tmp_path / "pieces", "p1", "p2", "p3")
    listing = tmp_path / "batch.toml"
    listing.write_text("""
[defaults]
robot = { speed_scale = 0.8 }

[[jobs]]
job = "pieces/p1.toml"

[[jobs]]
job = "pieces/p2.toml"
name = "second"
overrides = { cut = { feed_speed = 0.03 }, stock = { size = [0.2, 0.2, 0.1] } }

[[jobs]]
job = "pieces/p[3]*.toml"
""")
    found = find_jobs([str(listing)])
    assert [e.name for e in found] == ["p1", "second", "p3"]
    second = found[1]
    assert second.path == tmp_path / "pieces" / "p2.toml"
    assert second.overrides == {"robot": {"speed_scale": 0.8}, "cut": {"feed_speed": 0.03},
                                "stock": {"size": [0.2, 0.2, 0.1]}}  # fmt: skip
    assert second.label == f"{listing}#second"
    # the same list as JSON
    as_json = tmp_path / "batch.json"
    as_json.write_text(json.dumps({"jobs": [{"job": "pieces/p2.toml", "name": "second",
                                             "overrides": {"cut": {"feed_speed": 0.03}}}]}))
    (e,) = find_jobs([str(as_json)])
    assert e.name == "second" and e.overrides == {"cut": {"feed_speed": 0.03}}


def test_overrides_merge_tables_and_replace_values():
    doc = {"cut": {"feed_speed": 0.01, "kerf": 0.001}, "stock": {"size": [1, 2, 3]}}
    out = merge_overrides(doc, {"cut": {"feed_speed": 0.02}, "stock": {"size": [4, 5, 6]}})
    assert out == {"cut": {"feed_speed": 0.02, "kerf": 0.001}, "stock": {"size": [4, 5, 6]}}
    assert doc["cut"]["feed_speed"] == 0.01  # the original is not changed
    # [[cut]] lists are replaced whole
    assert merge_overrides({"cut": [{"name": "a"}]}, {"cut": [{"name": "b"}]}) == {
        "cut": [{"name": "b"}]}


@pytest.mark.parametrize(
    ("setup", "args", "message"),
    [
        (None, ["nothing-*.toml"], r"pattern '.*nothing-\*\.toml' matches no file"),
        (None, ["missing.toml"], r"no such job file or job list: .*missing\.toml"),
        ("dupes", ["a/x.toml", "b/x.toml"], r"two jobs named 'x'.*a/x\.toml.*b/x\.toml"),
        ("list", ["list.toml"], r"list\.toml: not valid TOML"),
        ("badentry", ["list.toml"], r"list\.toml, \[\[jobs\]\] entry 1: unknown field\(s\) "
         r"nmae; expected some of job, name, overrides"),
        ("badname", ["list.toml"], r"entry 1: name: expected a folder name.*got '../up'"),
        ("nojob", ["list.toml"], r"entry 1: job: no such job file: .*gone\.toml"),
        ("folder", ["a"], r"is a folder; give its job files"),
        ("empty", ["list.json"], r"jobs: expected a non-empty list"),
    ],
)
def test_bad_input_to_the_batch_names_file_entry_and_field(tmp_path, monkeypatch, setup, args,
                                                         message):
    monkeypatch.chdir(tmp_path)
    _jobs(tmp_path / "a", "x")
    _jobs(tmp_path / "b", "x")
    lists = {
        "list": "[[jobs]]\njob = 'a/x.toml'\nname = \n",
        "badentry": "[[jobs]]\njob = 'a/x.toml'\nnmae = 'y'\n",
        "badname": "[[jobs]]\njob = 'a/x.toml'\nname = '../up'\n",
        "nojob": "[[jobs]]\njob = 'a/gone.toml'\n",
    }
    if setup in lists:
        (tmp_path / "list.toml").write_text(lists[setup])
    if setup == "empty":
        (tmp_path / "list.json").write_text('{"jobs": []}')
    with pytest.raises(BatchInputError, match=message):
        find_jobs(args)


def test_file_fields_name_every_input_file_of_a_job():
    doc = job_document("""
[robot]
calibration = "robot.calib.json"
[[cut]]
name = "a"
[cut.surface]
file = "../shapes/a.json"
[[cut]]
name = "b"
[cut.surface]
airfoil = { root = "clarky.dat", tip = "naca.dat", span = 0.3 }
[[cut]]
name = "c"
[cut.surface]
gcode = "wing.ngc"
""", "job")
    assert [v for _, v in file_fields(doc)] == ["../shapes/a.json", "clarky.dat", "naca.dat",
                                                "wing.ngc", "robot.calib.json"]  # fmt: skip
    assert file_fields(doc)[0][0] == ("cut", 0, "surface", "file")


def test_the_hash_covers_job_text_input_bytes_and_code_not_the_path(tmp_path):
    shapes = write_rulings(tmp_path / "shapes" / "hp.json")
    (job,) = _jobs(tmp_path / "jobs", "j", text=file_job("../shapes/hp.json"))
    entry = JobEntry("j", job)
    first = read_content(entry)
    assert first.error is None and [f.path for f in first.inputs] == [shapes]
    assert read_content(entry).digest == first.digest  # stable
    assert read_content(entry, code="other").digest != first.digest  # the code counts
    moved = tmp_path / "elsewhere" / "jobs"
    moved.mkdir(parents=True)
    (moved / "j.toml").write_text(job.read_text())
    write_rulings(tmp_path / "elsewhere" / "shapes" / "hp.json")
    assert read_content(JobEntry("j", moved / "j.toml")).digest == first.digest  # not the path
    shapes.write_text(shapes.read_text() + "\n")  # same rulings, other bytes
    assert read_content(entry).digest != first.digest
    over = read_content(JobEntry("j", job, {"cut": {"feed_speed": 0.03}}, "list", tmp_path))
    assert over.digest != first.digest and b"feed_speed = 0.03" in over.text
    assert "+" in code_identity().id and len(code_identity().sources) == 64


def test_a_job_that_cannot_be_read_is_bad_input_found_on_the_client(tmp_path):
    (bad,) = _jobs(tmp_path, "bad", text="[surface\n")
    c = read_content(JobEntry("bad", bad))
    assert c.text is None and c.error.startswith(f"{bad}: not valid TOML")
    c = read_content(JobEntry("gone", tmp_path / "gone.toml"))
    assert c.error == f"{tmp_path / 'gone.toml'}: no such job file"


def _report(ok: bool) -> dict:
    return {"duration_s": 10.0, "cut_duration_s": 6.0, "collisions": [],
            "verdict": {"checks": [
                {"name": "joint_speed", "value": 0.5, "limit": 1.0, "relation": "<=",
                 "gating": True},
                {"name": "feed_min", "value": 9.0 if ok else 9.4, "limit": 9.5,
                 "relation": ">=", "gating": True},
                {"name": "collisions", "value": 0, "limit": 0, "relation": "<=", "gating": True},
                {"name": "tracking_error", "value": 3.0, "limit": None, "relation": "",
                 "gating": False},
            ]}}  # fmt: skip


def test_margins_are_relative_to_the_limit_and_name_the_worst_check():
    figures, margins = figures_of(_report(True))
    assert figures == {"duration_s": 10.0, "cut_duration_s": 6.0, "collisions": 0}
    assert margins == pytest.approx({"joint_speed": 0.5, "feed_min": -0.5 / 9.5})
    r = JobRecord("a", "a.toml", "infeasible", "h", margins=margins, failed_checks=("feed_min",))
    assert r.worst_check == "feed_min" and r.worst_margin < 0
    # a failing check without a relative margin (collisions <= 0) is still the worst
    r = JobRecord("a", "a.toml", "infeasible", "h", margins=margins,
                  failed_checks=("collisions",))  # fmt: skip
    assert r.worst_check == "collisions" and r.worst_margin is None
    assert JobRecord("a", "a.toml", "feasible", "h", margins=margins).worst_check == "feed_min"


def test_the_manifest_round_trips_and_a_rerun_keeps_only_what_is_there(tmp_path):
    folder = tmp_path / "a"
    folder.mkdir()
    (folder / "report.json").write_text("{}")
    (folder / "manifest.json").write_text(json.dumps({"format": "ruledrobot.output/1",
                                                      "complete": True, "files": {}}))
    a = JobRecord("a", "a.toml", "feasible", "h1", files=("a/report.json", "a/manifest.json"))
    b = JobRecord("b", "b.toml", "bad_input", "h2", message="b.toml: [cut] ...")
    c = JobRecord("c", "c.toml", "crashed", "h3", message="Traceback ...\nRuntimeError: x")
    old = JobRecord("old", "old.toml", "infeasible", "h4", failed_checks=("reach",))
    write_manifest(tmp_path, [a, b, c], [old], {"started": "now"})
    records = load_records(tmp_path)
    assert records == {"a": a, "b": b, "c": c, "old": old}
    doc = json.loads((tmp_path / "batch.json").read_text())
    assert doc["counts"]["feasible"] == 1 and doc["complete"] is True
    csv = (tmp_path / "batch.csv").read_text().splitlines()
    assert csv[0].startswith("name,status,job,failed_checks,message")
    assert csv[3].startswith("c,crashed,c.toml,,RuntimeError: x")  # a crash's last line
    assert csv[4].startswith("old,infeasible,old.toml,reach,")
    assert resumable(a, "h1", tmp_path) and resumable(b, "h2", tmp_path)
    assert not resumable(a, "other", tmp_path)  # the job changed
    assert not resumable(c, "h3", tmp_path)  # a crash is planned again
    (folder / "report.json").unlink()
    assert not resumable(a, "h1", tmp_path)  # a listed file is gone


def test_a_batch_json_that_is_not_ours_is_not_overwritten(tmp_path):
    (tmp_path / "batch.json").write_text('{"my": "data"}')
    with pytest.raises(BatchInputError, match=r"batch\.json: not a batch manifest"):
        load_records(tmp_path)


def test_a_job_is_read_again_when_it_is_dispatched(tmp_path):
    """The inputs' bytes are read at dispatch (not held for every job from the start): a
    job changed meanwhile is planned as it is then, under its new hash; one deleted
    meanwhile is bad input."""
    from ruledrobot.batch.run import _Batch

    write_rulings(tmp_path / "shapes" / "hp.json")
    a, b = _jobs(tmp_path / "jobs", "a", "b", text=file_job("../shapes/hp.json"))
    contents = [read_content(JobEntry(p.stem, p)) for p in (a, b)]
    assert all(f.data is None for c in contents for f in c.inputs)  # hashed, not held
    before = contents[0].digest
    batch = _Batch(contents, tmp_path / "out", {}, False, None)
    assert [r.status for r in batch.records] == ["pending", "pending"]
    a.write_text(a.read_text().replace("feed_speed = 0.04 ", "feed_speed = 0.03 "))
    task = batch.task(0)
    assert b"feed_speed = 0.03" in task.text and len(task.inputs) == 1
    assert task.inputs[0][1] == (tmp_path / "shapes" / "hp.json").read_bytes()
    assert batch.records[0].hash == read_content(JobEntry("a", a)).digest != before
    b.unlink()
    (tmp_path / "out").mkdir()
    assert batch.task(1) is None
    assert batch.records[1].status == "bad_input" and "no such job file" in batch.records[1].message
