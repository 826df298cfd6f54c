"""``ruledrobot view`` on the command line, and where the view package sits in the layers."""

from __future__ import annotations

from typer.testing import CliRunner

from ruledrobot.cli import app
from tests.architecture.imports import graph

runner = CliRunner()

#: What ruledrobot.view may import: its own modules and the layers below it, plus the
#: one parser of job files (the job in a plan folder names the cell).
ALLOWED = ("ruledrobot.view", "ruledrobot.sim", "ruledrobot.robot", "ruledrobot.io",
           "ruledrobot.geometry", "ruledrobot.wirecut.job.load")  # fmt: skip


#: Who may import ruledrobot.view: the CLI, and ``make`` (it writes each setup's viewer
#: file, as ``view --export`` does; docs/make.md)
IMPORTERS = ("ruledrobot.cli", "ruledrobot.make")


def test_view_imports_point_down_and_only_the_cli_and_make_import_view():
    edges = graph()
    for mod, deps in edges.items():
        if mod.startswith("ruledrobot.view"):
            bad = sorted(d for d in deps if not d.startswith(ALLOWED))
            assert not bad, f"{mod} imports {bad}"
        elif not mod.startswith(IMPORTERS):
            assert not any(d.startswith("ruledrobot.view") for d in deps), mod


def test_view_refuses_what_is_not_a_plan_folder(tmp_path):
    res = runner.invoke(app, ["view", str(tmp_path)])
    assert res.exit_code == 2 and "not a plan folder" in res.output
    res = runner.invoke(app, ["view", str(tmp_path / "missing")])
    assert res.exit_code == 2 and "no such folder" in res.output


def test_view_refuses_a_remote_address_without_the_flag(plan_folder):
    res = runner.invoke(app, ["view", str(plan_folder), "--host", "0.0.0.0"])
    assert res.exit_code == 2
    assert "not a loopback address" in res.output and "--allow-remote" in res.output


def test_view_serves_on_loopback_for_a_while_and_stops(plan_folder):
    res = runner.invoke(app, ["view", str(plan_folder), "--port", "0", "--duration", "0.5"])
    assert res.exit_code == 0, res.output
    assert "at http://127.0.0.1:" in res.output and "Ctrl-C" in res.output


def test_view_export_writes_one_file(plan_folder, tmp_path):
    out = tmp_path / "scene.html"
    res = runner.invoke(app, ["view", str(plan_folder), "--export", str(out)])
    assert res.exit_code == 0, res.output
    assert f"wrote {out}" in res.output
    text = out.read_text()
    assert "__VISER_EMBED_DATA__" in text and "ruledrobot-panel" in text
    assert "<script src=" not in text  # nothing loaded from anywhere
    help_ = runner.invoke(app, ["view", "--help"])
    assert help_.exit_code == 0 and "Example:" in help_.output
