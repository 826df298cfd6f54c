"""No file of a user's is ever lost (issue 22, item 7): re-planning keeps the recordings of
runs in the output folder and refuses to replace a folder holding a user's file; re-planning
and re-exporting next to a user's files leaves every one of them unchanged."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.export import recording_path_for
from ruledrobot.io.outdir import read_manifest
from ruledrobot.io.trajectory import read_trajectory, sidecar_path, write_trajectory
from ruledrobot.wirecut.job.demo import DEMO_JOB

runner = CliRunner()


def _digests(folder: Path) -> dict[str, str]:
    return {p.relative_to(folder).as_posix(): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}  # fmt: skip


def _record(out: Path) -> Path:
    """A recording of a run beside the plan's trajectory, named as the runner names it."""
    rec = recording_path_for(out / "trajectory.csv")
    assert rec.name == "trajectory.run-001.csv"
    write_trajectory(rec, read_trajectory(out / "trajectory.csv"))
    side = sidecar_path(rec)
    side.write_text(json.dumps(json.loads(side.read_text()) | {"run": {"ok": True}}))
    return rec


def test_replanning_keeps_recordings_and_every_users_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("job.toml").write_text(DEMO_JOB)
    out, exports, mine = Path("out/cut"), Path("exports"), Path("exports/notes.txt")
    assert runner.invoke(app, ["plan", "job.toml", "--out", str(out)]).exit_code == 0
    rec = _record(out)
    exports.mkdir()
    mine.write_text("the block from the left shelf\n")
    for name in ("d_full.json", "cut.csv", "cut.script"):
        r = runner.invoke(app, ["export", str(out / "trajectory.csv"), "--out",
                                str(exports / name)])  # fmt: skip
        assert r.exit_code == 0, r.output
    (exports / "d_full.json").rename(exports / "user_copy.json")  # now the user's
    users = _digests(exports)
    recorded = {rec.name: rec.read_bytes(), sidecar_path(rec).name: sidecar_path(rec).read_bytes()}

    r = runner.invoke(app, ["plan", "job.toml", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert f"kept {out / rec.name}  (a recording of an earlier run)" in r.output
    for name, data in recorded.items():
        assert (out / name).read_bytes() == data, name
    man = read_manifest(out)
    assert sorted(man["kept"]) == sorted(recorded) and not set(man["kept"]) & set(man["files"])
    assert recording_path_for(out / "trajectory.csv").name == "trajectory.run-002.csv"
    (out / "trajectory.run-002.csv").unlink()

    # re-export next to the user's files: the same exports again, and one refused
    for name in ("cut.csv", "cut.script"):
        r = runner.invoke(app, ["export", str(out / "trajectory.csv"), "--out",
                                str(exports / name)])  # fmt: skip
        assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["export", str(out / "trajectory.csv"), "--out",
                            str(exports / "user_copy.csv")])  # fmt: skip
    assert r.exit_code == 2, r.output
    assert _digests(exports) == users

    # a user's file put into the plan folder: the plan is refused, nothing replaced
    (out / "notes.txt").write_text("mine\n")
    before = _digests(out)
    r = runner.invoke(app, ["plan", "job.toml", "--out", str(out)])
    assert r.exit_code == 2
    assert "holds files that ruledrobot did not write (notes.txt)" in " ".join(r.output.split())
    assert _digests(out) == before
