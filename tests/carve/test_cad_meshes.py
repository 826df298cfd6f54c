"""Meshes as CAD exports them (issue 32): a units mistake named with the unit that fits,
facets turned the other way and seams left unwelded refused with where they are, and
mended with ``[part] repair = true`` (noted); the table names shown in ``--help``.

What is read is checked where it is read (carve's input stage, :func:`read_input`, and
its cuts without the robot): one whole run of ``carve`` (the turned facets mended) shows
that what the repair did reaches the console and ``carve.json``; the robot's wire-pose
search of the box's six cuts is the same for every mended box (their meshes are the
box's own) and runs once here."""

from __future__ import annotations

import re

import numpy as np
from typer.testing import CliRunner

from ruledrobot.carve.run import read_input
from ruledrobot.cli import app

from .conftest import AT_CENTRE, cuts_alone, run_carve, write_cell
from .parts import box, write_obj, write_stl_ascii


def _with_repair(cell):
    cell.write_text(cell.read_text().replace("rough_cuts = 4", "rough_cuts = 4\nrepair = true"))
    return cell


def test_units_mistakes_are_named_with_the_unit_that_fits(tmp_path):
    v, f, _ = box()  # 120 x 100 x 80 mm
    write_stl_ascii(tmp_path / "box_m.stl", v, f)  # a file in metres
    write_stl_ascii(tmp_path / "box_mm.stl", v, f, scale=0.001)  # in millimetres
    cases = (("box_m.stl", "mm", 'the part (box_m.stl) is 0.12 mm across in a 200 mm block: '
              'did you mean units = "m"?'),
             ("box_mm.stl", "m", 'the part (box_mm.stl) is 120,000 mm across in a 200 mm '
              'block: did you mean units = "mm"?'),
             ("box_mm.stl", "cm", 'is 1,200 mm across in a 200 mm block: did you mean '
              'units = "mm"?'))  # fmt: skip
    for k, (name, units, words) in enumerate(cases):
        cell = write_cell(tmp_path, name, AT_CENTRE, units=units, name=f"c{k}.toml")
        res, _ = run_carve(cell, tmp_path / f"out{k}")
        assert res.exit_code == 2, res.output
        assert f"c{k}.toml: [part] units = '{units}'" in res.output
        assert words in " ".join(res.output.split()), res.output
        assert "encloses no volume" not in res.output
        assert not (tmp_path / f"out{k}").exists()
    # the right unit reads the box at its size, and its six faces are cut exactly
    cell, part, plan = cuts_alone(write_cell(tmp_path, "box_m.stl", AT_CENTRE, units="m",
                                             name="ok.toml"))  # fmt: skip
    assert np.allclose(np.ptp(part.vertices, axis=0), [0.12, 0.1, 0.08], atol=1e-12)
    assert [c.kind for c in plan.cuts] == ["exact"] * 6


def _flipped_box():
    v, f, _ = box(n=2)
    turned = np.array([3, 4, 17, 30, 31, 45])
    g = f.copy()
    g[turned] = g[turned, ::-1]
    return v, f, g, turned


def _unwelded_box(gap=1e-6):
    """The box with its top face's vertices copied 1 um aside for the top's facets: the
    mesh is open along the top's rim (a seam CAD tessellated apart)."""
    v, f, _ = box(n=2)
    top = np.flatnonzero(np.isclose(v[:, 2], 0.04))
    moved = np.arange(len(v))
    moved[top] = len(v) + np.arange(len(top))
    on_top = np.all(np.isclose(v[f][:, :, 2], 0.04), axis=1)
    g = f.copy()
    g[on_top] = moved[f[on_top]]
    return np.vstack([v, v[top] + [gap, 0.0, 0.0]]), g, int(on_top.sum())


def test_flipped_facets_are_refused_with_where_and_turned_with_repair(tmp_path):
    v, f, g, _ = _flipped_box()
    write_obj(tmp_path / "box.obj", v, g, scale=0.001)
    cell = write_cell(tmp_path, "box.obj", AT_CENTRE)
    res, _ = run_carve(cell, tmp_path / "refused")
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert "box.obj: the triangles' orientations disagree across 18 edges" in text
    assert "6 facets turned the other way from their neighbours, facets 3-4, 17, 30-31, 45" in text
    assert "centred at (" in text and " mm)" in text
    assert "repair = true in [part] turns the facets" in text
    assert not (tmp_path / "refused").exists()
    res, report = run_carve(_with_repair(cell), tmp_path / "out")
    assert res.exit_code == 0, res.output
    note = "turned 6 facets to agree with their neighbours (3-4, 17, 30-31, 45)"
    _, part = read_input(cell)  # the box's own facets, each turned back
    assert np.array_equal(part.faces, f)
    assert report["part"]["repair"] is True and report["part"]["repaired"] == [note]
    assert f"note: repaired: {note}" in " ".join(res.output.split())
    assert report["notes"][0] == f"repaired: {note}"
    assert report["whole"]["exact_cuts"] == 6 and report["whole"]["setups"] == 1


def test_unwelded_seams_are_refused_with_where_and_merged_with_repair(tmp_path):
    v, g, _ = _unwelded_box()
    write_stl_ascii(tmp_path / "box.stl", v, g, scale=0.001)
    cell = write_cell(tmp_path, "box.stl", AT_CENTRE)
    res, _ = run_carve(cell, tmp_path / "refused")
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert "box.stl: not a closed 2-manifold mesh: 16 boundary edges" in text
    assert "on facets" in text and "centred at (" in text
    assert "8 vertices lie within 0.005 mm of another (seams not welded): repair = true" in text
    assert not (tmp_path / "refused").exists()
    # mended: the box's own mesh (what carve makes of it, the flipped box's whole run)
    cell, part, plan = cuts_alone(_with_repair(cell))
    assert part.repairs == ("merged 8 vertices into another within 0.005 mm",)
    box_v, box_f, _ = box(n=2)  # its facets in order and turned alike, within the seam's gap
    assert len(part.faces) == 48 and len(part.vertices) == len(box_v)
    assert np.abs(part.vertices[part.faces] - box_v[box_f] - AT_CENTRE[:3]).max() <= 1.01e-6
    assert [c.kind for c in plan.cuts] == ["exact"] * 6


def test_repair_is_a_boolean_and_off_by_default(tmp_path):
    v, f, _ = box()
    write_stl_ascii(tmp_path / "box.stl", v, f, scale=0.001)
    cell = write_cell(tmp_path, "box.stl", AT_CENTRE)
    cell.write_text(cell.read_text().replace("rough_cuts = 4", 'rough_cuts = 4\nrepair = "yes"'))
    res, _ = run_carve(cell, tmp_path / "bad")
    assert res.exit_code == 2
    assert "cell.toml: [part] repair: expected true or false, got 'yes'" in res.output
    # off unless asked (the refusals above are of cells that do not ask): nothing mended
    cell, part = read_input(write_cell(tmp_path, "box.stl", AT_CENTRE))
    assert cell.part.repair is False and part.repairs == ()


def test_carve_help_shows_the_table_names():
    res = CliRunner().invoke(app, ["carve", "--help"], env={"COLUMNS": "80"})
    text = " ".join(re.sub("[│╭╮╰╯─]", " ", res.output).split())  # the panel's borders off
    assert "[part] file, units, pose" in text
    assert "the [stock], [robot], [tool], [cut] of a job" in text
