"""The placement search scored on a real Dask LocalCluster (two worker processes on
loopback, started and stopped by the test, bounded in time): the same scores as in one
process, a failing chunk scored again here, and ``ruledrobot place --workers 2``
writing the same ranking as without."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.batch.engine import WORKER_MALLOC, Engine
from ruledrobot.batch.place import DistributedEvaluator
from ruledrobot.cli import app
from ruledrobot.place.regions import AS_CLAMPED, Region, transforms
from ruledrobot.place.search import job_passes
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.reach.evaluate import Evaluator
from ruledrobot.wirecut.reach.margins import Rules

from .conftest import deadline

pytest.importorskip("distributed")

runner = CliRunner()


@pytest.fixture(scope="module")
def setting(tmp_path_factory):
    src = tmp_path_factory.mktemp("place") / "job.toml"
    src.write_text(DEMO_JOB.replace("steps = 4", "steps = 3"))
    job = load_job(src)
    model = job.robot_model()
    ev = Evaluator(job, job_passes(job, model), model, rulings=24, rolls=12, rules=Rules())
    region = Region((0.3, 0.9), (-0.4, 0.4), (-np.pi / 2, np.pi / 2), "stock")
    T = transforms(job, region.grid((4, 4, 3)), "stock", AS_CLAMPED)
    return src, ev, T


def test_scores_on_the_workers_are_those_of_one_process(setting):
    _, ev, T = setting
    here = ev(T)
    with deadline(240), Engine(2) as eng:
        workers = eng.client.run(lambda: __import__("os").environ["MALLOC_TRIM_THRESHOLD_"])
        assert set(workers.values()) == {str(WORKER_MALLOC["MALLOC_TRIM_THRESHOLD_"])}
        d = DistributedEvaluator(ev, eng)
        there = d(T)
        assert eng.describe()["workers"] == 2
        # a failing worker task (here: nothing to call) is scored again in this process
        d._shared = eng.client.scatter(None, broadcast=True)
        again = d(T)
    for name in ("margin", "score", "pass_margin", "column", "exact"):
        np.testing.assert_array_equal(getattr(there, name), getattr(here, name), err_msg=name)
        np.testing.assert_array_equal(getattr(again, name), getattr(here, name), err_msg=name)
    assert d.notes and all("scored in this process: the worker failed" in n for n in d.notes)
    assert not any(np.isnan(here.margin))


def test_place_with_workers_ranks_as_without(setting, tmp_path):
    src = setting[0]
    args = ["place", str(src), "--x", "0.3:0.9", "--y", "-0.4:0.4", "--yaw", "-90:90",
            "--grid", "4x4x3", "--refine", "1", "--turns", "", "--no-verify",
            "--rulings", "24", "--rolls", "12"]  # fmt: skip
    with deadline(300):
        a = runner.invoke(app, [*args, "--out", str(tmp_path / "here")])
        b = runner.invoke(app, [*args, "--out", str(tmp_path / "there"), "--workers", "2"])
    assert a.exit_code == 0, a.output
    assert b.exit_code == 0, b.output
    here = json.loads((tmp_path / "here" / "place.json").read_text())
    there = json.loads((tmp_path / "there" / "place.json").read_text())
    assert here["ranked"] == there["ranked"] and here["as_placed"] == there["as_placed"]
    assert here["search"]["engine"] == {"kind": "in-process"}
    assert there["search"]["engine"]["kind"] == "local"
    assert there["search"]["engine"]["workers"] == 2


def test_workers_and_scheduler_together_are_bad_input(setting, tmp_path):
    res = runner.invoke(app, ["place", str(setting[0]), "--workers", "2", "--scheduler",
                              "tcp://127.0.0.1:1", "--out", str(tmp_path / "x")])  # fmt: skip
    assert res.exit_code == 2
    assert "--workers sizes the local cluster" in res.output
    assert not (tmp_path / "x").exists()


def test_an_unreachable_scheduler_is_bad_input(setting, tmp_path, monkeypatch):
    """Nothing listens there: refused within the engine's timeout, made 2 s here (the
    default's 10 s were the test's whole time)."""
    from ruledrobot.batch import engine

    monkeypatch.setattr(engine, "TIMEOUT_S", 2.0)
    with deadline(120):
        res = runner.invoke(app, ["place", str(setting[0]), "--scheduler",
                                  "tcp://127.0.0.1:9", "--out", str(tmp_path / "x")])  # fmt: skip
    assert res.exit_code == 2
    assert "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in res.output
    assert not (tmp_path / "x").exists()
