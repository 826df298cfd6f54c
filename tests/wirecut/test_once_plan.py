"""The plan path does each thing once (issues 23, 25, 34): the job file read once (by
load_job), the bow and
the clearance cell built once, each cut's input rulings read once, the playback measured
once; passes know their cut as an object."""

from __future__ import annotations

import hashlib
import json
import pathlib
from collections import Counter

import pytest

from ruledrobot.robot.tool import BowTool
from ruledrobot.sim.result import PlaybackResult
from ruledrobot.wirecut.cut.clearance import Cell
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.job.spec import SurfaceSpec
from ruledrobot.wirecut.plan import job_reference, make_plan
from ruledrobot.wirecut.planner import plan
from ruledrobot.wirecut.verify import verify_plan


def _count(monkeypatch, counts: Counter, owner, name: str, label: str) -> None:
    raw = owner.__dict__[name]
    f = raw.__func__ if isinstance(raw, classmethod) else raw

    def counted(*a, **k):
        counts[label] += 1
        return f(*a, **k)

    monkeypatch.setattr(owner, name, classmethod(counted) if isinstance(raw, classmethod)
                        else counted)  # fmt: skip


@pytest.fixture
def counts(monkeypatch):
    """Counters of the repeated work of the review (issue 23)."""
    c: Counter = Counter()
    post_init = BowTool.__post_init__

    def built(self):
        c["bow built"] += 1
        post_init(self)

    monkeypatch.setattr(BowTool, "__post_init__", built)
    _count(monkeypatch, c, Cell, "of", "Cell.of")
    _count(monkeypatch, c, SurfaceSpec, "document", "document")
    _count(monkeypatch, c, PlaybackResult, "_measure", "playback measured")
    return c


def _job_reads(monkeypatch, counts: Counter, path: pathlib.Path) -> None:
    target = path.resolve()
    for meth in ("read_bytes", "read_text"):
        orig = getattr(pathlib.Path, meth)

        def read(self, *a, _orig=orig, **k):
            if self.resolve() == target:
                counts["job file read"] += 1
            return _orig(self, *a, **k)

        monkeypatch.setattr(pathlib.Path, meth, read)


def test_the_demo_plan_does_each_thing_once(tmp_path, monkeypatch, counts):
    path = tmp_path / "job.toml"
    path.write_text(DEMO_JOB)
    job = load_job(path)
    counts.clear()
    _job_reads(monkeypatch, counts, path)
    res = plan(job, tmp_path / "out")
    assert res.feasible
    # the job's bytes were read by load_job (issue 34): hashed for the reports and copied
    # as job.toml from those, the file itself not opened again
    assert counts["job file read"] == 0
    assert counts["bow built"] == 1
    assert counts["Cell.of"] == 1  # the search's cell; the transits' is the same one
    assert counts["document"] == len(job.cuts)  # the surface sampled once per cut
    assert counts["playback measured"] == 1  # the verification's, report and files
    data = path.read_bytes()
    assert (tmp_path / "out" / "job.toml").read_bytes() == data
    ref = {"path": str(job.source), "sha256": hashlib.sha256(data).hexdigest()}
    assert res.plan.job_ref == ref == job_reference(job) == job_reference(res.plan)
    assert json.loads((tmp_path / "out" / "report.json").read_text())["job"] == ref
    assert res.plan.trajectory.meta.job == ref


def test_a_part_reads_each_cut_once_and_its_passes_know_their_cut(tmp_path, counts):
    path = tmp_path / "part.toml"
    path.write_text(PART_JOB)
    job = load_job(path)
    counts.clear()
    planned = make_plan(job)
    assert planned.motion is not None
    assert counts["document"] == len(job.cuts) == 3
    assert counts["bow built"] == 1 and counts["Cell.of"] == 1
    # every pass carries its cut, the job's own object (no look-up by name)
    assert all(any(cp.cut is cut for cut in job.cuts) for cp in planned.passes)
    assert [cp.cut.name for cp in planned.passes] == [cp.name for cp in planned.passes]
    assert {id(cp.cut) for cp in planned.passes} == {id(c) for c in job.cuts}
    assert planned.bow is not None and planned.bow.wire_length == job.tool.wire_length


def test_the_playback_report_is_a_fresh_copy_each_time(tmp_path):
    path = tmp_path / "job.toml"
    path.write_text(DEMO_JOB)
    ver = verify_plan(make_plan(load_job(path)))
    first = ver.playback.report()
    first["ok"] = "changed by a caller"
    first["joint_speed"]["ratio"].append(99.0)
    again = ver.playback.report()
    assert again["ok"] in (True, False) and 99.0 not in again["joint_speed"]["ratio"]
    assert again == ver.report
