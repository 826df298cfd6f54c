"""A command never writes over the file it reads (issue 22, item 7): refine, chain and
convert refuse an output that is their input, by name or through a link, and leave it
as it was."""

from __future__ import annotations

import os

import pytest
from typer.testing import CliRunner

from ruledrobot.cli import app

from .naca import naca4, selig_text

runner = CliRunner()


@pytest.fixture
def rulings(tmp_path):
    (tmp_path / "r.dat").write_text(selig_text("NACA 0012", naca4("0012", 21)))
    r = runner.invoke(app, ["convert", str(tmp_path / "r.dat"), "--span", "0.3",
                            "--root-chord", "0.1", "--to", str(tmp_path / "w.json")])
    assert r.exit_code == 0, r.output
    os.symlink(tmp_path / "w.json", tmp_path / "link.json")
    return tmp_path / "w.json"


@pytest.mark.parametrize("args", [
    ["refine", "{w}", "--out", "{w}"],
    ["refine", "{w}", "--out", "{d}/./w.json"],
    ["refine", "{w}", "--out", "{d}/r.json", "--mesh", "{w}"],
    ["refine", "{w}", "--out", "{d}/link.json"],
    ["chain", "{w}", "--out", "{w}"],
    ["convert", "{w}", "--to", "{d}/sub/../w.json"],
    ["convert", "{d}/r.dat", "--span", "0.3", "--root-chord", "0.1", "--to", "{d}/r.dat"],
])  # fmt: skip
def test_an_output_that_is_the_input_is_refused(rulings, args):
    before = rulings.read_bytes()
    argv = [a.format(w=rulings, d=rulings.parent) for a in args]
    r = runner.invoke(app, argv)
    assert r.exit_code == 2, r.output
    assert "is the input file" in r.output and "would write over what it reads" in r.output
    assert rulings.read_bytes() == before
