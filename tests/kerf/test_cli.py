"""``ruledrobot kerf ladder`` and ``kerf fit``: exit codes, messages naming line and column,
the [material] table written only when the fit is good enough."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app
from ruledrobot.robot.wire.kerf import Material

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

TRUE = Material(0.4e-3, 1.1e-7, 8.0)


def _csv(path, speeds=(2, 3, 4, 6), powers=(15, 25, 35), noise=0.01, seed=0):
    rng = np.random.default_rng(seed)
    rows = ["speed_mm_s,power_w_m,kerf_mm"]
    for p in powers:
        for v in speeds:
            w = TRUE.kerf(v * 1e-3, p) * 1e3 + rng.normal(0.0, noise)
            rows.append(f"{v},{p},{w:.3f}")
    path.write_text("\n".join(rows) + "\n")
    return path


def test_fit_prints_constants_and_writes_the_material_table(tmp_path):
    csv = _csv(tmp_path / "measured.csv")
    res = CliRunner().invoke(app, ["kerf", "fit", str(csv)], env={"COLUMNS": "120"})
    assert res.exit_code == 0, res.output
    for word in ("kerf_base", "kerf_gain", "power_threshold", "standard error", "residual",
                 "held out", "verdict: PASS"):  # fmt: skip
        assert word in res.output
    doc = tomllib.loads((tmp_path / "material.toml").read_text())
    mat = Material(**doc["material"])  # the table pastes into a job as it is
    assert mat.kerf_gain == pytest.approx(TRUE.kerf_gain, rel=0.05)


def test_one_power_warns_fails_and_writes_nothing(tmp_path):
    csv = _csv(tmp_path / "measured.csv", powers=(25,))
    res = CliRunner().invoke(app, ["kerf", "fit", str(csv)])
    assert res.exit_code == 1
    assert "one power only" in res.output and "undetermined" in res.output
    assert not (tmp_path / "material.toml").exists()


@pytest.mark.parametrize(("line", "match"), [
    ("4,abc,1.0", "line 4, column power_w_m: expected a number, got 'abc'"),
    ("-4,25,1.0", "line 4, column speed_mm_s: expected a finite number > 0"),
    ("4,25,", "line 4, column kerf_mm: empty"),
    ("4,25,1.0,7", "line 4: expected 3 values"),
    ("4,25,0.0012", "line 4, column kerf_mm: expected the slot's width in millimetres, 0.05 "
                    "to 50, got '0.0012' (a reading in metres or inches?)"),
    ("4,25,75", "line 4, column kerf_mm: expected the slot's width in millimetres"),
])  # fmt: skip
def test_a_bad_row_exits_2_naming_file_line_and_column(tmp_path, line, match):
    csv = tmp_path / "m.csv"
    csv.write_text("speed_mm_s,power_w_m,kerf_mm\n2,25,1.5\n# a comment\n" + line + "\n")
    res = CliRunner().invoke(app, ["kerf", "fit", str(csv)], env={"COLUMNS": "300"})
    assert res.exit_code == 2
    assert f"{csv}: {match}" in " ".join(res.output.split())
    assert not (tmp_path / "material.toml").exists()


def test_a_missing_column_and_a_bad_failed_flag_exit_2(tmp_path):
    csv = tmp_path / "m.csv"
    csv.write_text("speed_mm_s,kerf_mm\n2,1.5\n")
    res = CliRunner().invoke(app, ["kerf", "fit", str(csv)], env={"COLUMNS": "300"})
    assert res.exit_code == 2 and "line 1: the header has no column power_w_m" in res.output
    csv.write_text("speed_mm_s,power_w_m,kerf_mm,failed\n2,25,1.5,maybe\n")
    res = CliRunner().invoke(app, ["kerf", "fit", str(csv)], env={"COLUMNS": "300"})
    assert res.exit_code == 2 and "line 2, column failed: expected yes or no" in res.output


def test_ladder_writes_the_jobs_and_the_sheet(job_file, tmp_path):
    out = tmp_path / "lad"
    res = CliRunner().invoke(app, ["kerf", "ladder", str(job_file()), "--out", str(out),
                                   "--speeds", "2,4,6,8", "--powers", "15,30",
                                   "--full-scale", "60"], env={"COLUMNS": "200"})  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "8 cuts" in res.output
    sheet = (out / "ladder.md").read_text()
    assert "inside jaws of a caliper" in sheet and "power2/job.toml" in sheet
    assert (out / "measured.csv").read_text().count("\n") == 9


def test_ladder_bad_input_exits_2(job_file, tmp_path):
    res = CliRunner().invoke(app, ["kerf", "ladder", str(job_file()), "--out",
                                   str(tmp_path / "lad"), "--speeds", "2,x",
                                   "--powers", "15,30"], env={"COLUMNS": "200"})  # fmt: skip
    assert res.exit_code == 2 and "--speeds: expected comma-separated numbers" in res.output
    assert not (tmp_path / "lad").exists()


def test_fit_writes_over_its_own_table_but_never_over_a_users_file(tmp_path):
    path = _csv(tmp_path / "measured.csv")
    mine = tmp_path / "material.toml"
    mine.write_text("[material]\nkerf_base = 0.0004  # my own, edited\n")
    res = CliRunner().invoke(app, ["kerf", "fit", str(path)])
    assert res.exit_code == 2 and "was not written by kerf fit" in res.output
    assert mine.read_text() == "[material]\nkerf_base = 0.0004  # my own, edited\n"
    mine.unlink()
    for _ in range(2):  # the fit's own table is replaced by the next fit
        assert CliRunner().invoke(app, ["kerf", "fit", str(path)]).exit_code == 0
    assert mine.read_text().startswith("# ruledrobot kerf fit")
