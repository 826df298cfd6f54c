"""An export never replaces a file it did not write (issue 22, item 7): a user's file, a
JSON export where a CSV's sidecar would go, a run's recording -- refused, exit 2, the
file named and unchanged, unless --force; an earlier export of the same kind is replaced."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.export import WouldReplace, export_trajectory
from ruledrobot.io.export_targets import file_kind
from ruledrobot.io.trajectory import write_trajectory
from tests.support.emulators import smooth_trajectory

runner = CliRunner()


@pytest.fixture
def planned(tmp_path):
    """A trajectory CSV and its sidecar in ``plan/``."""
    (tmp_path / "plan").mkdir()
    return write_trajectory(tmp_path / "plan" / "trajectory.csv", smooth_trajectory())


def _export(src, out, *more):
    return runner.invoke(app, ["export", str(src), "--out", str(out), *more])


def test_a_csv_export_does_not_replace_a_json_export_of_the_same_name(tmp_path, planned):
    """The field report: `--out exports/d_full.csv` replaced the user's 2.5 MB d_full.json
    (an export of its own) with a sidecar."""
    exports = tmp_path / "exports"
    exports.mkdir()
    r = _export(planned, exports / "d_full.json")
    assert r.exit_code == 0 and f"wrote {exports / 'd_full.json'}" in r.output, r.output
    before = (exports / "d_full.json").read_bytes()
    r = _export(planned, exports / "d_full.csv")
    assert r.exit_code == 2, r.output
    text = " ".join(r.output.split())
    assert f"{exports / 'd_full.json'}: exists and is a JSON trajectory export" in text
    assert "sidecar of d_full.csv" in text and "--force" in text
    assert (exports / "d_full.json").read_bytes() == before
    assert sorted(p.name for p in exports.iterdir()) == ["d_full.json"]  # nothing written
    r = _export(planned, exports / "d_full.csv", "--force")
    assert r.exit_code == 0, r.output
    assert f"wrote {exports / 'd_full.json'}  (the sidecar of d_full.csv; replaced an " \
           "earlier export)" in r.output
    assert file_kind(exports / "d_full.json") == "sidecar"


@pytest.mark.parametrize("name", ["cut.script", "cut.csv", "cut.json", "cut.npz", "cut.txt"])
def test_a_users_file_is_never_replaced(tmp_path, planned, name):
    user = tmp_path / name
    user.write_bytes(b"my own notes\n")
    args = ["--format", "urscript"] if name.endswith(".txt") else []
    r = _export(planned, user, *args)
    assert r.exit_code == 2, r.output
    assert f"{user}: exists and is a file ruledrobot did not write" in " ".join(r.output.split())
    assert user.read_bytes() == b"my own notes\n"
    with pytest.raises(WouldReplace, match="a file ruledrobot did not write"):
        export_trajectory(smooth_trajectory(), user, "urscript" if args else None)


def test_a_csv_beside_a_users_json_is_refused_and_writes_nothing(tmp_path, planned):
    (tmp_path / "cut.json").write_text('{"mine": true}\n')
    r = _export(planned, tmp_path / "cut.csv")
    assert r.exit_code == 2 and "sidecar of cut.csv" in " ".join(r.output.split())
    assert not (tmp_path / "cut.csv").exists()
    assert json.loads((tmp_path / "cut.json").read_text()) == {"mine": True}


@pytest.mark.parametrize("name", ["cut.csv", "cut.json", "cut.npz", "cut.script"])
def test_an_earlier_export_of_the_same_kind_is_replaced(tmp_path, planned, name):
    assert _export(planned, tmp_path / name).exit_code == 0
    r = _export(planned, tmp_path / name)
    assert r.exit_code == 0 and "replaced an earlier export" in r.output, r.output


def test_a_recording_is_never_replaced(tmp_path, planned):
    rec = write_trajectory(tmp_path / "plan" / "trajectory.run-001.csv", smooth_trajectory())
    before = rec.read_bytes(), rec.with_suffix(".json").read_bytes()
    r = _export(planned, rec)
    assert r.exit_code == 2 and "is the recording of a run" in " ".join(r.output.split())
    assert (rec.read_bytes(), rec.with_suffix(".json").read_bytes()) == before
    # a recording under another name is told by its sidecar's "run"
    side = tmp_path / "plan" / "actual.json"
    rec2 = write_trajectory(tmp_path / "plan" / "actual.csv", smooth_trajectory())
    side.write_text(json.dumps(json.loads(side.read_text()) | {"run": {"ok": True}}))
    r = _export(planned, rec2)
    assert r.exit_code == 2 and f"{side}: exists and is the recording of a run" in \
        " ".join(r.output.split())
