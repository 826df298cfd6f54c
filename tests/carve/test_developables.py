"""Cylinders and cones as CAD exports mesh them — every vertex on the two rims, the side
in long slivers — are cut exactly along their own rulings (issue 24: "planes, cylinders,
cones"), checked against their closed forms.  Their vertices alone do not fix a quadric
(``x^2 + y^2 - r^2`` and ``z (z - h)`` both vanish on the rims): the fit reads the
normals too.  Before, such a cylinder fitted to 4e-14 mm was refused as "not a ruled
quadric within tolerance" and roughed."""

from __future__ import annotations

import numpy as np
import pytest

from .conftest import AXIS_Y, run_carve, write_cell
from .parts import write_stl_ascii
from .test_exact import _local


def frustum(r0: float, r1: float, h: float, n: int = 96):
    """A cone frustum (a cylinder when ``r0 == r1``) of axis z from ``z = -h/2`` to
    ``h/2``, radii ``r0`` at the bottom and ``r1`` at the top [m], capped; its side as
    ``n`` slivers from rim to rim.  Returns vertices, faces and the side's distance."""
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    bot = np.c_[r0 * np.cos(t), r0 * np.sin(t), np.full(n, -h / 2)]
    top = np.c_[r1 * np.cos(t), r1 * np.sin(t), np.full(n, h / 2)]
    v = np.vstack([bot, top, [[0.0, 0.0, -h / 2], [0.0, 0.0, h / 2]]])
    i = np.arange(n)
    j = (i + 1) % n
    f = np.concatenate([np.c_[i, j, n + j], np.c_[i, n + j, n + i],
                        np.c_[np.full(n, 2 * n), j, i], np.c_[np.full(n, 2 * n + 1), n + i, n + j]])

    def distance(x):  # from the side's cone (or cylinder), exact
        rho = np.hypot(x[:, 0], x[:, 1])
        r = r0 + (r1 - r0) * (x[:, 2] + h / 2) / h
        return np.abs(rho - r) * h / np.hypot(h, r1 - r0)

    return v, f, distance


@pytest.mark.parametrize(("r0", "r1"), [(0.04, 0.04), (0.05, 0.03)], ids=["cylinder", "cone"])
def test_a_faceted_cylinder_and_cone_are_cut_along_their_rulings(tmp_path, r0, r1):
    # the geometry alone (find_cuts without the robot): one exact loop on the closed form
    from ruledrobot.carve import load_cell
    from ruledrobot.carve.meshquery import MeshQuery
    from ruledrobot.carve.plan_cuts import find_cuts
    from ruledrobot.carve.readers import read_part

    v, f, distance = frustum(r0, r1, 0.12)
    write_stl_ascii(tmp_path / "part.stl", v, f, scale=0.001)
    cell = load_cell(write_cell(tmp_path, "part.stl", AXIS_Y, rough=2))
    part = read_part(cell.part, cell.stock, cell.where)
    plan = find_cuts(part, cell.stock, MeshQuery(part), cell.part.tolerance, 2)
    side = [c for c in plan.cuts if c.closed]
    assert len(side) == 1 and side[0].kind == "exact"
    assert not [c for c in plan.cuts if c.kind == "rough"]  # nothing left to rough
    p, d = side[0].lines.point, side[0].lines.direction
    t0, t1, hit = cell.stock.clip_lines(p, d)
    pts = np.concatenate([p[i] + np.arange(t0[i], t1[i], 0.001)[:, None] * d[i]
                          for i in np.flatnonzero(hit)])  # fmt: skip
    # on the closed form within the mesh's own faceting (96 sides: 0.02 mm at r = 40 mm)
    assert distance(_local(pts, AXIS_Y)).max() < 0.0005


def test_carve_writes_the_cylinders_loop_and_names_the_cone_the_arm_cannot_go_round(tmp_path):
    """With the robot (issue 32's cuts chosen with the robot): the demo cell's UR5e goes
    round the cylinder (exact loop, excess under 3 %); round the cone it finds no
    continuous IK, so carve roughs that face and names it with the planner's words."""
    for name, (r0, r1) in {"cylinder": (0.04, 0.04), "cone": (0.05, 0.03)}.items():
        folder = tmp_path / name
        folder.mkdir()
        v, f, _ = frustum(r0, r1, 0.12)
        write_stl_ascii(folder / "part.stl", v, f, scale=0.001)
        cell = write_cell(folder, "part.stl", AXIS_Y, rough=2)
        # the cone's face named only (the turns of the block are tests/carve/test_turns.py's)
        cell.write_text(cell.read_text().replace("rough_cuts = 2", "rough_cuts = 2\nturns = false"))
        res, report = run_carve(cell, folder / "out")
        assert res.exit_code == 0, res.output
        exact_loops = [c for c in report["cuts"] if c["closed"] and c["kind"] == "exact"]
        if name == "cylinder":
            assert len(exact_loops) == 1 and exact_loops[0]["gouge_mm"] == 0.0
            assert report["whole"]["rough_cuts"] == 0
            assert abs(report["whole"]["excess"]) < 0.03
        else:
            assert not exact_loops and report["whole"]["rough_cuts"] >= 1
            assert any("the arm cannot make its cut" in n and "no continuous IK" in n
                       for n in report["notes"])  # fmt: skip
