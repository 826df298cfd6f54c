"""Free-form parts roughed without gouging, against the visual hull; bad input refused."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.carve.meshquery import MeshQuery, point_triangle_distance
from ruledrobot.carve.readers import PartMesh
from ruledrobot.carve.rough import MAX_TILT
from ruledrobot.geometry.box import Box
from ruledrobot.io.lines import read_lines_document

from .conftest import AT_CENTRE, run_carve, write_cell
from .parts import ellipsoid, hyperboloid_column, write_obj, write_stl_ascii

AXES = np.array([0.09, 0.06, 0.045])
STOCK = Box(np.array([0.5, 0.0, 0.3]), np.array([0.2, 0.2, 0.15]))


def test_ellipsoid_roughed_without_gouge_and_tighter_than_the_visual_hull(tmp_path):
    v, f, _ = ellipsoid(AXES)
    write_obj(tmp_path / "egg.obj", v, f, scale=0.001)
    cell = write_cell(tmp_path, "egg.obj", AT_CENTRE, rough=4)
    res, report = run_carve(cell, tmp_path / "out")
    assert res.exit_code == 0, res.output
    assert [c["kind"] for c in report["cuts"]] == ["rough"] * 4
    assert report["whole"]["setups"] == 4  # every loop frees the piece: one setup each
    for k, c in enumerate(report["cuts"], start=1):
        lines = read_lines_document(tmp_path / "out" / f"setup{k}" / f"{c['name']}.json").lines
        t0, t1, hit = STOCK.clip_lines(lines.point, lines.direction)
        pts = np.concatenate([lines.point[i] + np.linspace(t0[i], t1[i], 400)[:, None]
                              * lines.direction[i] for i in np.flatnonzero(hit)])  # fmt: skip
        local = pts - STOCK.centre
        # no ruling point inside the closed-form ellipsoid (the mesh is inside it)
        assert (((local / AXES) ** 2).sum(axis=1)).min() > 1.0
    base = report["baseline"]
    assert report["whole"]["excess"] < base["excess"]
    assert len(base["directions"]) == 4
    # every loop's rulings within MAX_TILT of the vertical plane across the arm's reach
    # (the block is in front of the base along x): the bow and arm stay clear of the
    # block and the table (docs/carve.md)
    for k, c in enumerate(report["cuts"], start=1):
        doc = read_lines_document(tmp_path / "out" / f"setup{k}" / f"{c['name']}.json")
        d = doc.lines.direction
        assert np.degrees(np.arcsin(np.abs(d[:, 0]).max())) <= MAX_TILT + 1e-6
    assert (tmp_path / "out" / "carved.stl").is_file()


def test_open_and_non_manifold_meshes_are_refused(tmp_path):
    v, f, _ = hyperboloid_column(nu=32, nz=6)
    write_stl_ascii(tmp_path / "open.stl", v, f[:-3], scale=0.001)
    fin = np.vstack([v, [[0.0, 0.0, 0.3]]])
    e = f[0, :2]
    write_stl_ascii(tmp_path / "fin.stl", fin, np.vstack([f, [[e[0], e[1], len(v)]]]), scale=0.001)
    flipped = f.copy()
    flipped[5] = flipped[5, ::-1]
    write_obj(tmp_path / "flipped.obj", v, flipped, scale=0.001)
    pose = [0.5, 0.0, 0.3, float(np.pi / 2), 0.0, 0.0]
    for name, words in (("open.stl", "boundary edge"), ("fin.stl", "non-manifold edge"),
                        ("flipped.obj", "orientations disagree across 3 edge")):
        cell = write_cell(tmp_path, name, pose, name=f"{name}.toml")
        res, _ = run_carve(cell, tmp_path / f"out-{name}")
        assert res.exit_code == 2, res.output
        assert name in res.output and words in res.output
        assert not (tmp_path / f"out-{name}").exists()  # nothing written


def test_bad_cells_name_the_file_table_and_field(tmp_path):
    v, f, _ = ellipsoid(AXES, nu=16, nv=8)
    write_stl_ascii(tmp_path / "egg.stl", v, f, scale=0.001)
    cases = [
        ('units = "mm"', 'units = "ft"', "[part] units"),
        ("centre = [0.5", "centre = [0.5, 0.0]\nsize0 = [0.5", "[stock]"),
        ("feed_speed = 0.012", "feed_speed = -1.0", "[cut] feed_speed"),
    ]
    for k, (old, new, words) in enumerate(cases):
        cell = write_cell(tmp_path, "egg.stl", AT_CENTRE, name=f"c{k}.toml")
        cell.write_text(cell.read_text().replace(old, new, 1))
        res, _ = run_carve(cell, tmp_path / f"out{k}")
        assert res.exit_code == 2, res.output
        assert f"c{k}.toml" in res.output and words in res.output
    # a part larger than the block: millimetres read as centimetres (the unit that fits named)
    cell = write_cell(tmp_path, "egg.stl", AT_CENTRE, units="cm", name="big.toml")
    res, _ = run_carve(cell, tmp_path / "big")
    assert res.exit_code == 2 and 'did you mean units = "mm"?' in res.output
    # a part a little too large for its block is a placement or a block, not a unit
    cell = write_cell(tmp_path, "egg.stl", AT_CENTRE, name="over.toml")
    cell.write_text(cell.read_text().replace("size = [0.2, 0.2, 0.15]", "size = [0.2, 0.2, 0.08]"))
    res, _ = run_carve(cell, tmp_path / "over")
    assert res.exit_code == 2 and "does not fit the block" in res.output


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31 - 1))
def test_mesh_distance_and_inside_match_brute_force(seed):
    v, f, _ = ellipsoid(AXES, nu=24, nv=12)
    q = MeshQuery(PartMesh(v, f))
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(200, 3)) * AXES * rng.uniform(0.5, 1.5, size=(200, 1))
    t = v[f]
    brute = point_triangle_distance(p[:, None], t[None, :, 0], t[None, :, 1], t[None, :, 2])
    near = brute.min(axis=1) < 0.015
    assert np.allclose(q.distance(p)[near], brute.min(axis=1)[near], atol=1e-12)
    # inside by the closed form, away from the facets' chord error
    level = ((p / AXES) ** 2).sum(axis=1)
    clear = np.abs(level - 1.0) > 0.05
    assert np.array_equal(q.inside(p)[clear], (level < 1.0)[clear])
