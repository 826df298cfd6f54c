"""The undistorted 3-D view (ruledrobot.io.axes3d): a cube about the centre, equal
aspect, the axes labelled with the unit."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.io.axes3d import cube_axes


def test_the_axes_show_the_cube_about_the_centre():
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    ax = Figure().add_subplot(projection="3d")
    cube_axes(ax, np.array([0.1, -0.2, 0.3]), 0.5, "(m)")
    np.testing.assert_allclose(ax.get_xlim(), (-0.4, 0.6))
    np.testing.assert_allclose(ax.get_ylim(), (-0.7, 0.3))
    np.testing.assert_allclose(ax.get_zlim(), (-0.2, 0.8))
    aspect = ax.get_box_aspect()
    np.testing.assert_allclose(aspect, aspect[0])
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("x (m)", "y (m)", "z (m)")


# --------------------------------------------------------------------------
# meshes and the block drawn (shared by plots.png and carve.png)
# --------------------------------------------------------------------------


def _sphere(subdivisions: int = 5, radius: float = 0.05):
    trimesh = pytest.importorskip("trimesh")
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(s.vertices), np.asarray(s.faces, dtype=np.int64), radius


def test_a_coarse_mesh_keeps_the_shape_in_fewer_faces():
    from ruledrobot.geometry.mesh import signed_volume
    from ruledrobot.io.axes3d import coarse_mesh

    v, f, r = _sphere()  # 20480 faces
    most = 2000
    cv, cf, kept = coarse_mesh(v, f, most)
    assert most // 4 <= len(cf) <= 2 * most
    # vertices stay on the sphere within a cell's diagonal (the cell: sqrt(2 A / most))
    cell = np.sqrt(2.0 * 4.0 * np.pi * r**2 / most)
    assert np.abs(np.linalg.norm(cv[np.unique(cf)], axis=1) - r).max() <= np.sqrt(3) * cell
    # no degenerate or repeated triangle; the volume within 5 % of the ball's
    assert (cf[:, 0] != cf[:, 1]).all() and (cf[:, 1] != cf[:, 2]).all()
    assert (cf[:, 0] != cf[:, 2]).all()
    assert len(np.unique(np.sort(cf, axis=1), axis=0)) == len(cf)
    assert signed_volume(cv, cf) == pytest.approx(4.0 / 3.0 * np.pi * r**3, rel=0.05)
    # each kept face turns the way its original did (per-face colours follow ``kept``)
    n0 = np.cross(v[f[kept, 1]] - v[f[kept, 0]], v[f[kept, 2]] - v[f[kept, 0]])
    n1 = np.cross(cv[cf[:, 1]] - cv[cf[:, 0]], cv[cf[:, 2]] - cv[cf[:, 0]])
    assert (np.einsum("ij,ij->i", n0, n1) > 0).mean() > 0.95


def test_a_small_mesh_is_drawn_as_it_is():
    from ruledrobot.io.axes3d import coarse_mesh

    v, f, _ = _sphere(subdivisions=2)
    cv, cf, kept = coarse_mesh(v, f, len(f))
    assert cv is not None and np.array_equal(cf, f) and np.array_equal(kept, np.arange(len(f)))


def test_faces_are_lit_by_lamberts_law_from_matplotlibs_light():
    pytest.importorskip("matplotlib")
    from matplotlib.colors import LightSource

    from ruledrobot.io.axes3d import AMBIENT, LIGHT_ALTITUDE, LIGHT_AZIMUTH, lambert

    light = LightSource(LIGHT_AZIMUTH, LIGHT_ALTITUDE).direction
    side = np.cross(light, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)  # a unit normal square to the light
    b = lambert(np.array([3.0 * light, -light, side, light + side]))
    np.testing.assert_allclose(b[:3], [1.0, AMBIENT, AMBIENT], atol=1e-12)
    np.testing.assert_allclose(b[3], AMBIENT + (1 - AMBIENT) * np.sqrt(0.5), atol=1e-12)


def test_the_block_and_a_mesh_are_drawn_with_their_colours():
    pytest.importorskip("matplotlib")
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import to_rgba
    from matplotlib.figure import Figure

    from ruledrobot.geometry.box import Box
    from ruledrobot.io.axes3d import draw_box, draw_mesh, lambert

    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(projection="3d")
    box = Box(np.array([0.5, 0.0, 0.3]), np.array([0.2, 0.2, 0.15]))
    faces, edges = draw_box(ax, box, 1e3)
    v, f, _ = _sphere(subdivisions=2)
    colours = np.where((np.arange(len(f)) % 2 == 0)[:, None], to_rgba("tab:red"),
                       to_rgba("tab:blue"))  # fmt: skip
    surface = draw_mesh(ax, v, f, colours, 1e3, alpha=0.5)
    t = v[f]
    shade = lambert(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]))
    fig.canvas.draw()
    assert len(faces.get_paths()) == 6 and len(edges.get_segments()) == 12
    want = np.c_[colours[:, :3] * shade[:, None], np.full(len(f), 0.5)]
    got = surface.get_facecolor()  # depth-sorted: compare as sets of rows
    assert got.shape == want.shape

    def rows(a):
        return a[np.lexsort(np.round(a, 9).T[::-1])]

    np.testing.assert_allclose(rows(got), rows(want), atol=1e-9)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 40), st.integers(1, 4), st.sampled_from([3, 1_000, 2**40]),
       st.integers(0, 2**32))  # fmt: skip
def test_unique_rows_by_keys_are_numpys_unique_rows(n, k, spread, seed):
    """The key shortcut gives np.unique(rows, axis=0)'s rows order, inverse and first
    indices (the oracle), also where the keys would overflow (rows sorted as records)."""
    from ruledrobot.io.axes3d import _unique_rows

    rows = np.random.default_rng(seed).integers(-spread, spread, (n, k))
    for kw in ({"return_inverse": True}, {"return_index": True}):
        want = np.unique(rows, axis=0, **kw)[1].reshape(-1)
        np.testing.assert_array_equal(_unique_rows(rows, **kw)[1].reshape(-1), want)
