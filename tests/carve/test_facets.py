"""A faceted part as a new user brought it: a twisted hexagonal frustum (the convex hull of a
hexagon and a smaller one turned 0.3 rad above it: 12 flat side triangles meeting at 18
degree creases, two flat caps), in a block off the robot's x axis.

Found by hand (issue 32): its side triangles were joined in pairs at the 25 degree
segmentation (no surface fits two planes at a crease: six regions roughed), and every
planar cut's rulings turned from the preferred direction to the nearest tangent basis
vector after the first (a fan about the first ruling: the planner's kerf offset
divided by zero, "poses[19]: contains NaN").  Now: 14 exact planar cuts with parallel
rulings, and a fan of rulings gets a finite offset whose shortfall the face check names.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from ruledrobot.carve.meshquery import MeshQuery
from ruledrobot.carve.plan_cuts import find_cuts
from ruledrobot.carve.readers import PartMesh
from ruledrobot.geometry.box import Box
from ruledrobot.wirecut.cut.kerf import kerf_offsets

#: the block to the robot's right (the preferred wire direction is not a basis vector)
STOCK = Box(np.array([0.62, -0.25, 0.28]), np.array([0.18, 0.18, 0.13]))


def twisted_frustum(r0: float = 0.07, r1: float = 0.045, half: float = 0.05,
                    turn: float = 0.3) -> PartMesh:  # fmt: skip
    """The convex hull of two hexagons (module doc), outward triangles, in the block."""
    a = np.linspace(0.0, 2 * np.pi, 7)[:-1]
    P = np.r_[np.c_[r0 * np.cos(a), r0 * np.sin(a), np.full(6, -half)],
              np.c_[r1 * np.cos(a + turn), r1 * np.sin(a + turn), np.full(6, half)]]  # fmt: skip
    hull = ConvexHull(P)
    f = hull.simplices.copy()
    n = np.cross(P[f[:, 1]] - P[f[:, 0]], P[f[:, 2]] - P[f[:, 0]])
    out = np.einsum("ij,ij->i", n, P[f].mean(axis=1)) < 0.0
    f[out] = f[out][:, ::-1]
    return PartMesh(P + STOCK.centre, f)


@pytest.fixture(scope="module")
def plan():
    part = twisted_frustum()
    return part, find_cuts(part, STOCK, MeshQuery(part), 0.0005, 4)


def test_every_facet_of_a_faceted_part_is_an_exact_planar_cut(plan):
    part, got = plan
    assert len(part.faces) == 20
    assert [c.kind for c in got.cuts] == ["exact"] * 14, got.notes
    assert not got.loops
    assert sum("creases" in n for n in got.notes) == 6
    # each cut lies on its facet's plane: every triangle's vertices on one cut's lines
    for cut in got.cuts:
        L = np.asarray(cut.lines)
        d, m = L[:, :3], L[:, 3:]
        p = np.cross(d, m)  # the point of each line nearest the origin
        normal = np.cross(d[0], p[-1] - p[0])
        normal /= np.linalg.norm(normal)
        assert np.abs((p - p[0]) @ normal).max() < 1e-9  # the lines span one plane


def test_a_planar_cuts_rulings_are_parallel_off_the_robots_axis(plan):
    """The block's preferred wire direction here is (0.37, 0.93, 0), between the tangent
    basis vectors of a horizontal cap: every ruling takes it, not only the first."""
    _, got = plan
    for cut in got.cuts:
        d = np.asarray(cut.lines)[:, :3]
        assert np.abs(np.cross(d, d[0])).max() < 1e-12, cut.name


def test_a_fan_of_rulings_gets_a_finite_offset_and_its_shortfall_named():
    """Rulings pivoting about a point inside the block (a fan in a plane): the normals along
    a ruling turn by 180 degrees there; the offset is held to the mitre cap, finite, and
    the error reports what it leaves."""
    M = 41
    ang = np.linspace(-0.4, 0.4, M)
    frames = np.tile(np.eye(4), (M, 1, 1))
    d = np.stack([np.sin(ang), np.cos(ang), np.zeros(M)], axis=1)
    x = np.cross(d, [0.0, 0.0, 1.0])
    frames[:, :3, 2], frames[:, :3, 0] = d, x
    frames[:, :3, 1] = np.cross(d, x)
    frames[:, :3, 3] = STOCK.centre - 0.2 * d  # the pivot at the block's centre
    off = kerf_offsets(frames, STOCK, 0.0008, STOCK.centre + np.array([0.0, 0.0, 0.05]), False)
    assert np.isfinite(off.offset).all() and np.isfinite(off.error).all()
    assert off.error.max() > 0.0004 * 0.5  # the fan's pivot cannot be offset: named
