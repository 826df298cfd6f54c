"""carve.png (carve.plot) on a small carving: the part's faces coloured by the cut that
makes them (each coloured face on its cut's surface: the geometry decides, not the
picture), a legend naming the cuts, the carved block a shaded surface coloured by cut,
the titles inside the figure.  No pixel comparisons."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.colors import to_rgba
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ruledrobot.carve.carved import carve_block
from ruledrobot.carve.measure import surface_distance
from ruledrobot.carve.meshquery import MeshQuery
from ruledrobot.carve.plan_cuts import find_cuts
from ruledrobot.carve.plot import (
    BLOCK_FACE,
    _carved_colours,
    _part_colours,
    carve_figure,
    cut_colours,
    draw,
)
from ruledrobot.carve.readers import PartMesh
from ruledrobot.geometry.box import Box

from .parts import prism

STOCK = Box(np.array([0.5, 0.0, 0.3]), np.array([0.2, 0.2, 0.15]))


@pytest.fixture(scope="module")
def carving():
    """A hexagonal prism along y as long as the block: six plane cuts, two faces of the
    block."""
    v, f, _ = prism(radius=0.05, half=0.1, sides=6, turn=0.2)
    part = PartMesh(v[:, [0, 2, 1]] * [1.0, -1.0, 1.0] + STOCK.centre, f)  # z -> y: a turn
    plan = find_cuts(part, STOCK, MeshQuery(part), 0.0005, 4)
    carved = carve_block(plan.cuts, STOCK, plan.loops).mesh
    report = {"whole": {"part_volume_l": 1.0, "carved_volume_l": 1.0, "excess": 0.0}}
    return part, plan, carved, report


def test_the_parts_faces_take_the_colour_of_the_cut_on_whose_surface_they_lie(carving):
    part, plan, _, _ = carving
    assert len(plan.cuts) == 6 and all(c.kind == "exact" for c in plan.cuts)
    colours = cut_colours(len(plan.cuts))
    got = _part_colours(part, plan, colours)
    centroids = part.triangles.mean(axis=1)
    for k, cut in enumerate(plan.cuts):
        mine = np.all(got == colours[k], axis=1)
        assert mine.any()
        assert surface_distance(centroids[mine], cut.lines, cut.closed).max() < 1e-6
    grey = np.all(got == to_rgba(BLOCK_FACE), axis=1)
    assert grey.sum() > 0  # the two ends, on the block's faces y = +-0.1
    np.testing.assert_allclose(np.abs(centroids[grey, 1]), 0.1, atol=1e-9)
    assert (np.all(got == colours[:, None], axis=2).any(axis=0) | grey).all()


def test_the_carved_blocks_faces_are_coloured_by_the_cut_surface_they_lie_on(carving):
    _, plan, carved, _ = carving
    colours = cut_colours(len(plan.cuts))
    tri = carved.vertices[carved.faces]
    got = _carved_colours(tri, plan, colours)
    c = tri.mean(axis=1)
    on_block = np.abs(np.abs(STOCK.to_box(c)) - 0.5 * STOCK.size).min(axis=1) < 1e-6
    grey = np.all(got == to_rgba(BLOCK_FACE), axis=1)
    assert np.array_equal(grey, on_block)  # the carved prism: every other face a cut's
    for k, cut in enumerate(plan.cuts):
        mine = np.all(got == colours[k], axis=1)
        assert surface_distance(c[mine], cut.lines, cut.closed).max() < 1e-6


def test_the_picture_names_the_cuts_and_draws_the_carved_block_as_a_surface(carving, tmp_path):
    part, plan, carved, report = carving
    fig = carve_figure(part, plan, carved, STOCK, report)
    fig.canvas.draw()
    left, right = fig.axes
    words = [t.get_text() for t in left.get_legend().get_texts()]
    assert [w.split()[1] for w in words[: len(plan.cuts)]] == [c.name for c in plan.cuts]
    assert "face of the block" in words
    surfaces = [c for c in right.collections if isinstance(c, Poly3DCollection)]
    assert len(surfaces) == 2  # the block's faces, the carved block
    assert len(surfaces[1].get_paths()) >= 0.25 * min(len(carved.faces), 12_000)
    r = fig.canvas.get_renderer()
    for ax in (left, right):
        t = ax.title.get_window_extent(r)
        assert fig.bbox.x0 <= t.x0 and t.x1 <= fig.bbox.x1 and t.y1 <= fig.bbox.y1
    out = draw(tmp_path / "carve.png", part, plan, carved, STOCK, report)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
