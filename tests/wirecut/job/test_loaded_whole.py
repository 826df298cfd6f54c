"""The job loaded whole, once (issue 34): :func:`load_job` reads and checks every file the job
names, the job carries their data, and planning opens none of them -- a job whose folder is
gone after loading still plans, and a bad file is refused by ``load_job`` itself, naming the
job file, the table, the field and the file with its line."""

from __future__ import annotations

import hashlib
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from ruledrobot.geometry.lines import Lines
from ruledrobot.geometry.surfaces import sample_surface
from ruledrobot.io.calibration import save_calibration
from ruledrobot.io.lines import save_lines
from ruledrobot.robot import random_calibration
from ruledrobot.wirecut import load_job, plan
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.spec import SurfaceSpec
from tests.formats.test_job_cli import job_with
from tests.support.file_reads import opened_under

POSE = "pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]\n"


def _demo_rulings() -> Lines:
    """The demo's input rulings in its surface's frame (its [surface] table's sample)."""
    assert 'builtin = "hyperbolic_paraboloid"\nparams = { c = 0.4 }\nu = [-0.12, 0.12]' in DEMO_JOB
    return sample_surface("hyperbolic_paraboloid", n=9, start=-0.12, stop=0.12, c=0.4).lines


def _job_folder(folder: Path, rulings: Lines) -> Path:
    """A job folder: the demo cut from a lines file, on a calibrated arm (two files named)."""
    folder.mkdir()
    save_lines(folder / "rulings.json", rulings)
    save_calibration(folder / "robot.calib.json", random_calibration("ur5e", seed=3))
    text = job_with('file = "rulings.json"\n' + POSE)
    text = text.replace("[robot]\n", '[robot]\ncalibration = "robot.calib.json"\n')
    (folder / "job.toml").write_text(text)
    return folder / "job.toml"


def test_a_job_plans_with_its_folder_gone(tmp_path):
    """Planning opens no file of the job's folder: the folder is deleted after load_job and
    the plan's attempts to open anything under it are recorded (audit hook): none.  The
    plan writes job.toml from the bytes loaded and hashes them."""
    rulings = _demo_rulings()
    job_file = _job_folder(tmp_path / "job", rulings)
    data = job_file.read_bytes()
    job = load_job(job_file)
    shutil.rmtree(job_file.parent)
    with opened_under(tmp_path / "job") as seen:
        res = plan(job, tmp_path / "out", simulate=False)
    assert seen == []
    np.testing.assert_allclose(job.surface.read_lines.plucker, rulings.plucker, atol=1e-12)
    assert job.robot.calibration is not None and job.source_bytes == data
    assert res.plan.reachable, res.plan.reasons
    assert (tmp_path / "out" / "job.toml").read_bytes() == data
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    assert report["job"]["sha256"] == hashlib.sha256(data).hexdigest()


def test_the_hook_sees_a_read(tmp_path):
    """The recorder is not blind: reading the job's files again is seen."""
    job_file = _job_folder(tmp_path / "job", _demo_rulings())
    with opened_under(tmp_path / "job") as seen:
        load_job(job_file)
    assert sorted(Path(p).name for p in seen) == ["job.toml", "robot.calib.json", "rulings.json"]


#: a bad lines file of each kind -> what load_job says after the job file, table and field
BAD_LINES = {
    "malformed JSON": ("w.json", '{"lines": [\n  {"point": [0, 0, 0],\n', "",
                       r"line 3: not valid JSON"),
    "short direction": ("w.json", '{"lines": [{"point": [0, 0, 0], "direction": [0, 0]}]}', "",
                        r"lines\[0\]\.direction: expected a list of 3 numbers"),
    "CSV row": ("w.csv", "px,py,pz,dx,dy,dz\n0,0,0,0,0,1\n0,0,x,0,0,1\n", "",
                r"line 3: not a number"),
    # the table says closed: the file was only read by the cut stage before (issue 34)
    "closed by the table": ("w.csv", "px,py,pz,dx,dy,dz\n0,0,0,0,0,1\n0,0,x,0,0,1\n",
                            "closed = true\n", r"line 3: not a number"),
    "missing": (None, "", "", r"no such lines file"),
}  # fmt: skip


@pytest.mark.parametrize("case", list(BAD_LINES))
def test_a_bad_lines_file_is_refused_by_load_job(tmp_path, case):
    name, content, extra, said = BAD_LINES[case]
    target = tmp_path / (name or "gone.json")
    if name is not None:
        target.write_text(content)
    job_file = tmp_path / "job.toml"
    job_file.write_text(job_with(f'file = "{target.name}"\n{extra}' + POSE))
    with pytest.raises(ValueError) as err:
        load_job(job_file)
    msg = str(err.value)  # the job file, the table and the field; the file and its line
    assert msg.startswith(f"{job_file}: [surface] file: ") and str(target) in msg, msg
    assert re.search(said, msg), msg


def test_a_bad_calibration_is_refused_by_load_job(tmp_path):
    save_lines(tmp_path / "w.json", _demo_rulings())
    (tmp_path / "c.json").write_text('{"model": "ur5e", "dh": [1, 2\n')
    job_file = tmp_path / "job.toml"
    job_file.write_text(job_with('file = "w.json"\n' + POSE)
                        .replace("[robot]\n", '[robot]\ncalibration = "c.json"\n'))  # fmt: skip
    with pytest.raises(ValueError, match="^" + re.escape(f"{job_file}: [robot] calibration: "
                                                         f"{tmp_path / 'c.json'}: ") + ".*line 2"):
        load_job(job_file)


def test_a_surface_named_by_a_file_carries_its_rulings():
    """The value type refuses a file without its rulings: no later stage could read it."""
    with pytest.raises(ValueError, match=r"x\.json: .*load_job"):
        SurfaceSpec(file=Path("x.json"))
    built = SurfaceSpec(builtin="hyperbolic_paraboloid", params={"c": 0.4}, u=(-0.1, 0.1))
    assert len(built.lines()) == 9  # a built-in surface made in memory is sampled (no file)


def test_a_built_in_surface_is_sampled_when_loaded(tmp_path):
    (tmp_path / "demo.toml").write_text(DEMO_JOB)
    loaded = load_job(tmp_path / "demo.toml").surface.read_lines
    np.testing.assert_allclose(loaded.plucker, _demo_rulings().plucker, atol=1e-12)
