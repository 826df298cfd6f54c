"""Roughing loops on their own: the silhouette's polygon and its even rulings, the choice
that asks the robot, and the voxels the exact cuts already took (issue 32)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

from ruledrobot.carve.rough import LOOP_STEP, choose_loops, loop_lines, silhouette
from ruledrobot.carve.samples import box, fairing
from ruledrobot.geometry.box import Box

STOCK = Box([0.5, 0.0, 0.3], [0.2, 0.2, 0.15])
STANDOFF = 0.00025


def _hull(v: np.ndarray) -> np.ndarray:
    return v[ConvexHull(v).vertices]


def test_a_box_seen_along_an_edge_is_its_rectangle_moved_out_by_the_standoff():
    v, _ = box((0.12, 0.1, 0.08))
    loop = silhouette(np.array([0.0, 0.0, 1.0]), _hull(v), STANDOFF)
    assert loop.parallel and len(loop.normals) == 4
    # each plane: a face of the box's side, moved out by the standoff (closed form)
    for n, h in zip(loop.normals, loop.support, strict=True):
        k = int(np.argmax(np.abs(n)))
        assert np.isclose(abs(n[k]), 1.0) and k < 2
        assert np.isclose(h, [0.06, 0.05][k] + STANDOFF)
    lines = loop_lines(loop, np.zeros(3))
    p = lines.point
    # the corners are rulings: the rectangle's, at (+-(0.06 + s), +-(0.05 + s))
    corners = np.array([[sx * (0.06 + STANDOFF), sy * (0.05 + STANDOFF)]
                        for sx in (-1, 1) for sy in (-1, 1)])  # fmt: skip
    assert np.abs(p[:, None, :2] - corners[None]).sum(-1).min(axis=0).max() < 1e-12
    assert np.allclose(np.abs(lines.direction[:, 2]), 1.0)


@settings(max_examples=20, deadline=None)
@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.05, 1))
def test_a_silhouette_holds_the_part_and_its_rulings_are_even(ax, ay, az):
    v, _ = fairing()
    hull = _hull(v)
    axis = np.array([ax, ay, az]) / np.linalg.norm([ax, ay, az])
    loop = silhouette(axis, hull, STANDOFF)
    # every vertex of the part at least the standoff inside every plane
    assert (hull @ loop.normals.T - loop.support).max() <= -STANDOFF + 1e-12
    lines = loop_lines(loop, v.mean(axis=0))
    p = lines.point
    gaps = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    assert gaps.max() <= LOOP_STEP + 1e-12
    # no clusters: no gap below a fifth of the step (the corners' tiny arcs are gone) ...
    assert gaps.min() >= LOOP_STEP / 5
    # ... and every ruling on the polygon (on one of its planes, inside all others)
    on = np.abs(p @ loop.normals.T - loop.support).min(axis=1)
    assert on.max() < 1e-9
    assert (p @ loop.normals.T - loop.support).max() < 1e-9


def test_the_choice_asks_the_robot_and_never_takes_a_loop_it_refuses():
    v, _ = fairing()
    hull = _hull(v + STOCK.centre)
    free, _ = choose_loops(hull, STOCK, 2, STANDOFF, seams=False)
    asked: list[tuple[float, ...]] = []

    def accept(loop) -> bool:
        asked.append(tuple(np.round(loop.axis, 9)))
        return not np.allclose(loop.axis, free[0].axis)

    chosen, _ = choose_loops(hull, STOCK, 2, STANDOFF, seams=False, accept=accept)
    assert len(chosen) == 2
    assert not any(np.allclose(c.axis, free[0].axis) for c in chosen)
    assert len(asked) == len(set(asked))  # each loop asked once
    assert asked[0] == tuple(np.round(free[0].axis, 9))


def test_what_the_exact_cuts_took_counts_for_no_loop():
    v, _ = fairing()
    hull = _hull(v + STOCK.centre)
    assert len(choose_loops(hull, STOCK, 3, STANDOFF, seams=False)[0]) == 3

    def everything(points, shape):
        assert len(points) == int(np.prod(shape))
        return np.ones(len(points), bool)

    chosen, kept = choose_loops(hull, STOCK, 3, STANDOFF, seams=False, gone=everything)
    assert chosen == [] and kept == []
