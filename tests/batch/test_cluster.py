"""A batch on a real Dask LocalCluster: two worker processes on loopback, started and
stopped by the test, bounded in time.

The jobs mix every outcome: feasible (a built-in surface; the same through a lines
file one folder up on a robot with a calibration file, both of which the worker
receives as bytes; one changed by a job list's overrides), infeasible (out of
reach), bad input (a negative feed, found on the worker), and one whose worker is
killed mid-plan, twice (the test hook of
:mod:`ruledrobot.batch.task`).  The manifest must say the truth about each; the
files must equal those of ``plan`` on the same job; a rerun must keep every result
but the crash.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from ruledrobot.batch import local_cluster, run_batch
from ruledrobot.batch.task import KILL_HOOK, KILL_LOG
from ruledrobot.io.outdir import read_manifest
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan

from .conftest import (
    BROKEN_JOB,
    FAR_JOB,
    FAST_JOB,
    deadline,
    file_job,
    write_calibration,
    write_rulings,
)

pytest.importorskip("distributed")

#: fields of the plan's files that carry timings (they differ between two runs of plan)
TIMING = {
    "report.json": ("timings", "simulation_realtime_factor"),
    "simulation/report.json": ("realtime_factor", "physics_realtime_factor", "wall_time_s"),
}


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """Two single-threaded worker processes; jobs named ``killme*`` kill their worker."""
    log = tmp_path_factory.mktemp("kills") / "kills.log"
    saved = {k: os.environ.get(k) for k in (KILL_HOOK, KILL_LOG)}
    os.environ[KILL_HOOK], os.environ[KILL_LOG] = "killme*", str(log)
    try:
        with deadline(240):
            c = local_cluster(2)  # the workers inherit the hook's variables
        yield c, log
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    with deadline(60):
        c.close()


@pytest.fixture(scope="module")
def jobs(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("batch-jobs")
    write_rulings(root / "shapes" / "hp.json")
    write_calibration(root / "robot" / "robot.calib.json")
    folder = root / "jobs"
    folder.mkdir()
    from_file = file_job("../shapes/hp.json", calibration="../robot/robot.calib.json")
    for name, text in {"fast": FAST_JOB, "from_file": from_file,
                       "far": FAR_JOB, "broken": BROKEN_JOB}.items():  # fmt: skip
        (folder / f"{name}.toml").write_text(text)
    (root / "batch.toml").write_text("""
[[jobs]]
job = "jobs/fast.toml"
[[jobs]]
job = "jobs/from_file.toml"
[[jobs]]
job = "jobs/fast.toml"
name = "faster"
overrides = { cut = { feed_speed = 0.045 } }
[[jobs]]
job = "jobs/far.toml"
[[jobs]]
job = "jobs/broken.toml"
[[jobs]]
job = "jobs/fast.toml"
name = "killme"
""")
    return root


def _strip(rel: str, data: bytes) -> object:
    """A plan file for comparison: JSON without its timing fields, other files as bytes."""
    if rel not in TIMING and rel != "manifest.json":
        return data
    doc = json.loads(data)
    for key in TIMING.get(rel, ()):
        doc.pop(key, None)
    if rel == "manifest.json":  # the completion marker: when, and the timed files' checksums
        doc.pop("written")
        for name in TIMING:
            doc["files"][name].pop("sha256")
            doc["files"][name].pop("bytes")
    return doc


def _folder(folder: Path) -> dict[str, object]:
    return {p.relative_to(folder).as_posix(): _strip(p.relative_to(folder).as_posix(),
                                                      p.read_bytes())
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


@pytest.fixture(scope="module")
def first_run(cluster, jobs, tmp_path_factory):
    c, log = cluster
    out = tmp_path_factory.mktemp("batch-out")
    with deadline(240):
        result = run_batch([str(jobs / "batch.toml")], out, scheduler=c.scheduler_address)
    return result, out, log


def test_the_manifest_says_the_truth_about_every_job(first_run, jobs):
    result, out, log = first_run
    by = {r.name: r for r in result.records}
    assert {n: r.status for n, r in by.items()} == {  # (the messages say why, if not)
        "fast": "feasible", "from_file": "feasible", "faster": "feasible",
        "far": "infeasible", "broken": "bad_input", "killme": "crashed"}, \
        [(r.name, r.status, r.message) for r in result.records]  # fmt: skip
    assert result.exit_code == 1 and result.planned == 6 and not result.interrupted
    assert by["far"].failed_checks == ("reach",)
    assert "[cut] feed_speed: expected a number > 0, got -1" in by["broken"].message
    assert str(jobs / "jobs" / "broken.toml") in by["broken"].message  # names the user's file
    # the killed job was tried twice (retried once), then reported; nobody else suffered
    kills = log.read_text().split("\n")[:-1]
    assert [k.split()[0] for k in kills] == ["killme", "killme"]
    assert len({k.split()[1] for k in kills}) == 2  # two different worker processes
    assert "worker planning it died" in by["killme"].message
    # the manifest on disk is what run_batch returned, and lists files that are there
    doc = json.loads((out / "batch.json").read_text())
    assert [j["status"] for j in doc["jobs"]] == [r.status for r in result.records]
    assert doc["complete"] is True and doc["run"]["engine"]["allowed_failures"] == 0
    assert doc["run"]["engine"]["client_retries"] == 1 and by["killme"].attempts == 2
    fast = by["fast"]
    assert fast.figures["collisions"] == 0 and fast.figures["duration_s"] > 5
    assert fast.worst_margin > 0 and fast.plan_s > 0 and fast.hash and fast.worker
    assert all((out / f).is_file() for r in result.records for f in r.files)
    assert not (out / "far" / "trajectory.csv").exists()  # a failed plan writes none
    assert not (out / "broken").exists() and not (out / "killme").exists()
    csv = (out / "batch.csv").read_text().splitlines()
    assert len(csv) == 7 and csv[5].startswith("broken,bad_input,")
    # an overridden job names the job list and keeps its effective text
    faster = (out / "faster" / "job.toml").read_text()
    assert "feed_speed = 0.045" in faster
    report = json.loads((out / "faster" / "report.json").read_text())
    assert report["job"]["path"] == f"{jobs / 'batch.toml'}#faster"
    assert report["feed_speed_mm_s"] == pytest.approx(45.0)


def test_results_equal_those_of_plan_on_each_job_alone(first_run, jobs, tmp_path):
    """Every file of ``plan`` on the job, byte for byte; in report.json,
    simulation/report.json and manifest.json only the timing fields may differ."""
    _, out, _ = first_run
    job = jobs / "jobs" / "from_file.toml"  # its input files travelled as bytes
    with deadline(120):
        alone = plan(load_job(job), tmp_path / "alone")
    assert alone.feasible
    assert _folder(out / "from_file") == _folder(tmp_path / "alone")
    report = json.loads((out / "from_file" / "report.json").read_text())
    assert report["job"]["path"] == str(job)
    meta = json.loads((out / "from_file" / "trajectory.json").read_text())
    assert str(jobs / "robot" / "robot.calib.json") in json.dumps(meta)  # as plan names it


def test_a_rerun_keeps_the_results_and_plans_only_the_crash(first_run, cluster, jobs):
    result, out, log = first_run
    c, _ = cluster
    before = {n: (read_manifest(out / n)["written"], (out / n / "report.json").stat().st_mtime_ns)
              for n in ("fast", "from_file", "faster", "far")}  # fmt: skip
    with deadline(240):
        again = run_batch([str(jobs / "batch.toml")], out, scheduler=c.scheduler_address)
    assert again.kept == 5 and again.planned == 1  # the crash is planned again
    assert [r.status for r in again.records] == [r.status for r in result.records]
    kept = {r.name: r for r in again.records if r.name != "killme"}
    assert kept == {r.name: r for r in result.records if r.name != "killme"}
    after = {n: (read_manifest(out / n)["written"], (out / n / "report.json").stat().st_mtime_ns)
             for n in before}  # fmt: skip
    assert after == before  # not replanned, not rewritten
    assert len(log.read_text().splitlines()) == 4


def test_a_changed_input_file_replans_its_job_and_force_replans_all(first_run, cluster, jobs):
    _, out, _ = first_run
    c, _ = cluster
    shapes = jobs / "shapes" / "hp.json"
    shapes.write_text(shapes.read_text() + "\n")  # same rulings, other bytes
    with deadline(240):
        res = run_batch([str(jobs / "jobs" / "from_file.toml"), str(jobs / "jobs" / "far.toml")],
                        out, scheduler=c.scheduler_address)  # fmt: skip
        assert (res.planned, res.kept) == (1, 1) and res.exit_code == 1
        stamp = (out / "far" / "report.json").stat().st_mtime_ns
        forced = run_batch([str(jobs / "jobs" / "far.toml")], out, scheduler=c.scheduler_address,
                           force=True)  # fmt: skip
    assert (forced.planned, forced.kept) == (1, 0)
    assert (out / "far" / "report.json").stat().st_mtime_ns != stamp
    doc = json.loads((out / "batch.json").read_text())
    # jobs of earlier runs that this one does not name stay listed (their folders are there)
    assert [j["name"] for j in doc["jobs"]] == ["far"]
    assert {j["name"] for j in doc["earlier"]} == {"fast", "from_file", "faster", "broken",
                                                    "killme"}  # fmt: skip
