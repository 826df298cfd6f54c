"""make on bad input: exit 2, the file and the field named, nothing written."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from ruledrobot.carve.demo import write_demo_cell
from ruledrobot.cli import app


def _make(cell, out):
    res = CliRunner().invoke(app, ["make", str(cell), "--out", str(out)])
    return res, " ".join(res.output.split())


@pytest.mark.parametrize("old, new, named", [
    ('units = "mm"', 'units = "ft"', "[part] units"),
    ("size = [0.2, 0.2, 0.15]", "size = [0.2, -0.2, 0.15]", "size"),
    ('file = "column.stl"', 'file = "gone.stl"', "[part] file"),
    ("[robot]", "[robots]", "robots"),
    ("tolerance = 0.0005", "tolerance = -1", "[part] tolerance"),
])  # fmt: skip
def test_a_broken_cell_file_names_the_field_and_writes_nothing(tmp_path, old, new, named):
    cell = write_demo_cell(tmp_path / "part")
    text = cell.read_text()
    assert old in text
    cell.write_text(text.replace(old, new, 1))
    res, out = _make(cell, tmp_path / "made")
    assert res.exit_code == 2, res.output
    assert "cell.toml" in out and named in out, out
    assert not (tmp_path / "made").exists()


def test_not_toml_is_bad_input(tmp_path):
    cell = tmp_path / "cell.toml"
    cell.write_text("[part\nfile = ")
    res, out = _make(cell, tmp_path / "made")
    assert res.exit_code == 2 and "not valid TOML" in out
    assert not (tmp_path / "made").exists()


def test_a_part_larger_than_the_block_is_refused_and_nothing_written(tmp_path):
    cell = write_demo_cell(tmp_path / "part", length=0.3)  # 300 mm column, 200 mm block
    res, out = _make(cell, tmp_path / "made")
    assert res.exit_code == 2, res.output
    assert "does not fit the block" in out and "along the block's axis y" in out
    assert not (tmp_path / "made").exists()


def test_a_folder_of_the_users_files_is_never_replaced(tmp_path):
    cell = write_demo_cell(tmp_path / "part")
    made = tmp_path / "made"
    made.mkdir()
    (made / "notes.txt").write_text("mine")
    res, out = _make(cell, made)
    assert res.exit_code == 2 and "notes.txt" in out
    assert sorted(p.name for p in made.iterdir()) == ["notes.txt"]


def test_a_cell_inside_the_output_folder_is_refused(tmp_path):
    cell = write_demo_cell(tmp_path / "made" / "part")
    res, out = _make(cell, tmp_path / "made")
    assert res.exit_code == 2 and "lies in the output folder" in out
    assert (tmp_path / "made" / "part" / "cell.toml").is_file()
