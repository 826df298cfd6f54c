"""Which faces are cut exactly does not hang on how finely CAD triangulated them
(issue 32): a box of 12 triangles is six planar cuts as one of 192 is; end caps of a few
large triangles (fanned from a rim vertex) are cut; the distance to the part is exact
on triangles of any size."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.carve.carved import carve_block
from ruledrobot.carve.jobs import setups_of
from ruledrobot.carve.meshquery import MeshQuery, point_triangle_distance
from ruledrobot.carve.quadric import fit_region
from ruledrobot.carve.readers import PartMesh
from ruledrobot.carve.segment import segment
from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box

from .conftest import AT_CENTRE, AXIS_Y, cuts_alone, run_carve, write_cell
from .parts import _grid, _weld, box, prism, write_stl_ascii

STOCK = Box(np.array([0.5, 0.0, 0.3]), np.array([0.2, 0.2, 0.15]))


def test_a_box_is_six_planar_cuts_whatever_its_triangles(tmp_path):
    """The box of 12 triangles (issue 32's: 4 roughing loops before) carved whole, the
    robot asked of every cut; the box of 192 gives the same six cuts on the same planes
    (the geometry alone: what the triangles could change is which faces are fitted and
    cut, not the robot's reach of a plane across the block, asked of the first)."""
    plans = {}
    for n in (1, 4):
        v, f, _ = box(n=n)
        assert len(f) == 12 * n * n
        write_stl_ascii(tmp_path / f"box{n}.stl", v, f, scale=0.001)
        cell = write_cell(tmp_path, f"box{n}.stl", AT_CENTRE, name=f"box{n}.toml")
        plans[n] = cuts_alone(cell)[2]
        assert plans[n].faces == dict.fromkeys(range(6), "exact")
        assert [c.kind for c in plans[n].cuts] == ["exact"] * 6 and not plans[n].notes
    for a, b in zip(plans[1].cuts, plans[4].cuts, strict=True):  # on the same plane
        normal = np.cross(a.lines.direction[0], a.lines.point[-1] - a.lines.point[0])
        for q in (b.lines.point, b.lines.point + b.lines.direction):
            assert np.abs((q - a.lines.point[0]) @ normal).max() < 1e-12 * np.linalg.norm(normal)
    res, report = run_carve(tmp_path / "box1.toml", tmp_path / "out")
    assert res.exit_code == 0, res.output
    assert report["part"]["faces"] == {str(k): "exact" for k in range(6)}
    w = report["whole"]
    assert (w["cuts"], w["exact_cuts"], w["setups"]) == (6, 6, 1)
    assert all("plane" in c["what"] and c["gouge_mm"] == 0.0 for c in report["cuts"])
    assert abs(w["excess"]) < 0.005
    assert "faces: 6 cut exactly" in res.output


@pytest.mark.parametrize(("sides", "rings", "turn"), [(6, 2, 0.3), (96, 8, 0.0)])
def test_end_caps_of_few_large_triangles_are_cut(tmp_path, sides, rings, turn):
    """A hexagonal prism (caps of 4 triangles: fitted as never before) and a 96-sided
    column (caps of 94 slivers fanned from one rim vertex: dropped before, as 'no point
    of the part found behind the face' — the point tried lay below a rim vertex, on the
    side).  The geometry alone (carve's cut plan and carved block, without the robot's
    search of each cut: how the caps are triangulated is the fit's and the cut's matter)."""
    v, f, _ = prism(sides=sides, rings=rings, turn=turn)
    write_stl_ascii(tmp_path / "prism.stl", v, f, scale=0.001)
    cell, _, plan = cuts_alone(write_cell(tmp_path, "prism.stl", AXIS_Y))
    assert set(plan.faces.values()) == {"exact"}, plan.faces
    assert len(setups_of(plan.cuts)) == 1 and plan.notes == ()
    assert carve_block(plan.cuts, cell.stock, plan.loops).note() is None
    # the caps' cuts lie in the caps' planes (the part's z = +-70 mm is the base's y)
    pose = se3.pose_from_ur_vector(AXIS_Y)
    caps = 0
    for c in plan.cuts:
        local = (c.lines.point - pose[:3, 3]) @ pose[:3, :3]
        if np.ptp(local[:, 2]) < 1e-9 and abs(abs(local[0, 2]) - 0.07) < 1e-9:
            caps += 1
            assert np.abs((c.lines.direction @ pose[:3, :3])[:, 2]).max() < 1e-9
    assert caps == 2


def _brute(v, f, p):
    t = v[f]
    return np.concatenate([point_triangle_distance(q[:, None], t[None, :, 0], t[None, :, 1],
                                                   t[None, :, 2]).min(axis=1)
                           for q in np.array_split(p, max(1, len(p) // 500))])  # fmt: skip


@pytest.mark.parametrize("make", [lambda: box(), lambda: prism(sides=96, rings=3),
                                  lambda: prism(sides=5)])
def test_distance_and_side_exact_on_large_triangles(make):
    """Points anywhere in the block — on the faces' planes, deep inside, far outside —
    against every triangle (brute force) and the closed form's inside."""
    v, f, inside = make()
    q = MeshQuery(PartMesh(v, f))
    rng = np.random.default_rng(7)
    p = rng.uniform(-0.5, 0.5, size=(3000, 3)) * STOCK.size
    on_planes = p[:600].copy()
    on_planes[:, 2] = np.where(on_planes[:, 2] > 0, v[:, 2].max(), v[:, 2].min())
    p = np.concatenate([p, on_planes, v + rng.normal(size=v.shape) * 1e-4])
    sd = q.signed(p)
    assert np.allclose(np.abs(sd), _brute(v, f, p), rtol=0.0, atol=1e-12)
    clear = np.abs(sd) > 1e-9
    assert np.array_equal(sd[clear] < 0.0, inside(p[clear]))


def test_a_quadric_needs_a_region_that_determines_it():
    """Two triangles folded 10 degrees hold more than one quadric that differ between
    their vertices: undetermined (roughed); a narrow arc of a cylinder, 12 facets over
    23 degrees, is pinned down on the face (its continuation is measured, not fitted)."""
    a = np.radians(10.0)
    v = np.array([[0, -0.03, 0], [0, 0.03, 0], [0.05, 0, 0],
                  [-0.05 * np.cos(a), 0, 0.05 * np.sin(a)]])  # fmt: skip
    (region,) = segment(PartMesh(v, np.array([[0, 2, 1], [0, 1, 3]])))
    fit = fit_region(region, 0.0005)
    assert fit.kind == "undetermined" and fit.residual > 0.0005
    u = np.linspace(0.0, 0.4, 13)
    P = np.stack([np.broadcast_to(0.05 * np.cos(u)[:, None], (13, 2)),
                  np.broadcast_to(0.05 * np.sin(u)[:, None], (13, 2)),
                  np.broadcast_to([-0.05, 0.05], (13, 2))], -1)  # fmt: skip
    (region,) = segment(PartMesh(*_weld(_grid(P))))
    assert fit_region(region, 0.0005).kind == "ruled"
