"""Strip and box-clipped meshes of ruled surfaces; STL/OBJ files."""

from __future__ import annotations

import os
from collections import Counter

import numpy as np
import pytest

from ruledrobot.geometry.lines import Lines
from ruledrobot.geometry.mesh import (
    box_clipped_mesh,
    mesh_normals,
    strip_mesh,
    validate_mesh,
)
from ruledrobot.geometry.ruled import RuledSurface
from ruledrobot.geometry.surfaces import helicoid, hyperboloid, mobius_band
from ruledrobot.io.mesh import read_obj, read_stl, write_obj, write_stl


def _boundary_loops(faces: np.ndarray) -> list[int]:
    """Lengths of the boundary loops of a triangle mesh (edges used by one face)."""
    edges = Counter()
    for a, b, c in faces.tolist():
        for e in ((a, b), (b, c), (c, a)):
            edges[tuple(sorted(e))] += 1
    assert max(edges.values()) <= 2  # a manifold strip
    boundary = [e for e, k in edges.items() if k == 1]
    nbrs: dict[int, list[int]] = {}
    for a, b in boundary:
        nbrs.setdefault(a, []).append(b)
        nbrs.setdefault(b, []).append(a)
    assert all(len(v) == 2 for v in nbrs.values())
    seen: set[int] = set()
    loops = []
    for start in nbrs:
        if start in seen:
            continue
        n, prev, cur = 0, None, start
        while True:
            seen.add(cur)
            n += 1
            nxt = nbrs[cur][0] if nbrs[cur][0] != prev else nbrs[cur][1]
            prev, cur = cur, nxt
            if cur == start:
                break
        loops.append(n)
    return sorted(loops)


# -- strip meshes --------------------------------------------------------------


def test_open_strip_counts_vertices_and_orientation():
    u = np.linspace(0, 2, 9)
    lines = helicoid(u, pitch=0.3)
    surf = RuledSurface(lines)
    V, F = strip_mesh(surf, half_width=0.25)
    assert V.shape == (18, 3) and F.shape == (16, 3) and F.dtype == np.int64
    s = surf.striction_points()
    np.testing.assert_allclose(V[0::2], s - 0.25 * lines.direction)
    np.testing.assert_allclose(V[1::2], s + 0.25 * lines.direction)
    # every triangle joins rulings i and i+1
    ruling_of = F // 2
    assert np.all(ruling_of.max(axis=1) - ruling_of.min(axis=1) == 1)
    # consistent orientation: normals along x_u x x_v (sequence x ruling direction)
    n = mesh_normals(V, F)
    i = ruling_of.min(axis=1)
    xu = s[i + 1] - s[i]
    ref = np.cross(xu, lines.direction[i])
    assert np.all(np.einsum("ni,ni->n", n, ref) > 0)
    assert _boundary_loops(F) == [18]
    # Lines are meshed as an open surface
    V2, F2 = strip_mesh(lines, half_width=0.25)
    np.testing.assert_array_equal(F2, F)
    np.testing.assert_allclose(V2, V)


def test_closed_strip_is_a_band_with_two_boundaries():
    lines = hyperboloid(2 * np.pi * np.arange(10) / 10, a=1.0, c=1.0)
    mesh = strip_mesh(RuledSurface(lines, closed=True), half_width=0.5)
    assert mesh.vertices.shape == (20, 3) and mesh.faces.shape == (20, 3)
    assert _boundary_loops(mesh.faces) == [10, 10]
    # last quad joins ruling 9 to ruling 0 without reversal: a_9 .. a_0
    assert [18, 0, 1] in mesh.faces.tolist()


def test_closed_with_flip_joins_the_first_ruling_reversed():
    n = 12
    lines = mobius_band(2 * np.pi * np.arange(n) / n)
    surf = RuledSurface(lines, closed=True)
    assert surf.flip
    V, F = strip_mesh(surf, half_width=0.3, centre=_centres(lines))
    assert F.shape == (2 * n, 3)
    # a Möbius band has ONE boundary loop of length 2N
    assert _boundary_loops(F) == [2 * n]
    a_last, b0, a0 = 2 * (n - 1), 1, 0
    assert [a_last, b0, a0] in F.tolist()  # a_{N-1} joined to b_0: ruling 0 reversed
    # the joining quad's sides are short: joining without the reversal would twist it
    b_last = a_last + 1
    joined = np.linalg.norm(V[a_last] - V[b0]) + np.linalg.norm(V[b_last] - V[a0])
    twisted = np.linalg.norm(V[a_last] - V[a0]) + np.linalg.norm(V[b_last] - V[b0])
    assert joined < 0.75 * twisted


def _centres(lines: Lines) -> np.ndarray:
    """Points of the Möbius rulings on the centre circle."""
    n = len(lines)
    u = 2 * np.pi * np.arange(n) / n
    return np.stack([np.cos(u), np.sin(u), 0 * u], 1)


def test_strip_centre_options_and_widths():
    lines = helicoid(np.linspace(0, 1, 5))
    m1 = strip_mesh(lines, half_width=0.1, centre="nearest_origin")
    np.testing.assert_allclose(m1.vertices[0::2], lines.point - 0.1 * lines.direction)
    pts = lines.point + 0.3 * lines.direction + [0.0, 0.0, 0.0]
    off = pts + np.cross(lines.direction, [0.0, 0.0, 1.0]) * 0.05  # off-line: projected
    m2 = strip_mesh(lines, half_width=np.array([0.1, 0.2, 0.3, 0.4, 0.5]), centre=off)
    np.testing.assert_allclose(m2.vertices[9], pts[4] + 0.5 * lines.direction[4], atol=1e-12)
    with pytest.raises(ValueError, match="centre: expected 'striction'"):
        strip_mesh(lines, 0.1, centre="middle")
    with pytest.raises(ValueError, match=r"centre: expected points of shape \(5, 3\)"):
        strip_mesh(lines, 0.1, centre=np.zeros((4, 3)))
    with pytest.raises(ValueError, match=r"half_width\[2\]: expected a positive"):
        strip_mesh(lines, np.array([0.1, 0.1, -0.1, 0.1, 0.1]))
    with pytest.raises(ValueError, match="half_width: expected a positive"):
        strip_mesh(lines, 0.0)
    with pytest.raises(ValueError, match=r"one per ruling \(5,\)"):
        strip_mesh(lines, np.ones(3))
    with pytest.raises(ValueError, match=r"surface: expected ruledrobot\.RuledSurface or Lines"):
        strip_mesh(np.zeros((5, 6)), 0.1)


# -- box clipping --------------------------------------------------------------


def test_box_clipping_hand_computed_chords():
    r2 = np.sqrt(2.0)
    lines = Lines.from_point_direction(
        [[0, 0, 0], [0, 0.5, 0], [0, 0, 5], [0.5, 0.5, 0], [3, 3, 0]],
        [[1, 0, 0], [1, 1, 0], [1, 0, 0], [0, 0, 1], [0, 0, 1]],
    )
    res = box_clipped_mesh(lines, box_centre=[0, 0, 0], box_size=[2, 2, 2])
    np.testing.assert_array_equal(res.hit, [True, True, False, True, False])
    np.testing.assert_array_equal(res.missed, [2, 4])
    np.testing.assert_allclose(res.chords[0], [[-1, 0, 0], [1, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(res.chords[1], [[-1, -0.5, 0], [0.5, 1, 0]], atol=1e-15)
    np.testing.assert_allclose(res.chords[3], [[0.5, 0.5, -1], [0.5, 0.5, 1]], atol=1e-15)
    assert np.isnan(res.chords[2]).all() and np.isnan(res.chords[4]).all()
    # quads only between consecutive hitting rulings: (0, 1)
    assert res.vertices.shape == (6, 3)
    np.testing.assert_array_equal(res.faces, [[0, 2, 3], [0, 3, 1]])
    # a box turned by 45 degrees about z and moved: the x axis crosses it diagonally
    c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    res = box_clipped_mesh(lines[:1], box_centre=[0.5, 0, 0], box_size=[2, 2, 2], box_rotation=R)
    np.testing.assert_allclose(res.chords[0], [[0.5 - r2, 0, 0], [0.5 + r2, 0, 0]], atol=1e-14)
    # a line through the box's edge-to-edge only touches a face plane: tangent lines
    # in a face (|p_k| = s_k/2) still count, lines beyond it do not
    edge = Lines.from_point_direction([[0, 1.0, 0], [0, 1.0 + 1e-9, 0]], [[1, 0, 0], [1, 0, 0]])
    np.testing.assert_array_equal(box_clipped_mesh(edge, [0, 0, 0], [2, 2, 2]).hit, [True, False])


def test_box_clipping_closed_surfaces_join_back():
    n = 16
    lines = mobius_band(2 * np.pi * np.arange(n) / n)
    res = box_clipped_mesh(RuledSurface(lines, closed=True), [0, 0, 0], [3, 3, 0.5])
    assert res.hit.all()
    assert res.faces.shape == (2 * n, 3)
    assert _boundary_loops(res.faces) == [2 * n]
    assert [2 * (n - 1), 1, 0] in res.faces.tolist()
    # an open strip through a slab that misses some rulings
    lines = helicoid(np.linspace(0, 2 * np.pi, 13), pitch=0.2)
    res = box_clipped_mesh(lines, [0, 0, 0.2], [2, 2, 0.5])
    z = 0.2 * np.linspace(0, 2 * np.pi, 13)
    np.testing.assert_array_equal(res.hit, np.abs(z - 0.2) <= 0.25)
    assert res.faces.shape == (2 * (res.hit.sum() - 1), 3)


def test_box_clipping_bad_input():
    lines = helicoid(np.linspace(0, 1, 4))
    with pytest.raises(ValueError, match=r"box_size\[1\]: expected a positive edge length"):
        box_clipped_mesh(lines, [0, 0, 0], [1, 0, 1])
    with pytest.raises(ValueError, match="box_centre: expected 3 numbers"):
        box_clipped_mesh(lines, [0, 0], [1, 1, 1])
    with pytest.raises(ValueError, match="box_rotation: expected a rotation matrix"):
        box_clipped_mesh(lines, [0, 0, 0], [1, 1, 1], box_rotation=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match=r"box_rotation: expected a 3x3"):
        box_clipped_mesh(lines, [0, 0, 0], [1, 1, 1], box_rotation=np.eye(4))


# -- files ---------------------------------------------------------------------


def _mesh():
    lines = mobius_band(2 * np.pi * np.arange(10) / 10)
    return strip_mesh(RuledSurface(lines, closed=True), half_width=0.3)


def test_stl_round_trip(tmp_path):
    V, F = _mesh()
    path = write_stl(tmp_path / "band.stl", V, F)
    raw = path.read_bytes()
    assert len(raw) == 84 + 50 * F.shape[0]
    assert not raw[:5].lower().startswith(b"solid")
    back = read_stl(path)
    assert back.faces.shape == F.shape and back.vertices.shape == V.shape
    np.testing.assert_allclose(back.vertices[back.faces], V[F], atol=1e-6)
    np.testing.assert_allclose(back.normals, mesh_normals(V, F), atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(back.normals, axis=1), 1.0, atol=1e-6)


def test_ascii_stl_is_read_too(tmp_path):
    text = (
        "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
        "   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n"
    )
    (tmp_path / "a.stl").write_text(text)
    back = read_stl(tmp_path / "a.stl")
    np.testing.assert_array_equal(back.vertices[back.faces[0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    (tmp_path / "b.stl").write_bytes(b"garbage")
    with pytest.raises(ValueError, match=r"b\.stl: not an STL file"):
        read_stl(tmp_path / "b.stl")


def test_obj_round_trip_is_exact(tmp_path):
    V, F = _mesh()
    path = write_obj(tmp_path / "band.obj", V, F)
    back = read_obj(path)
    np.testing.assert_array_equal(back.vertices, V)
    np.testing.assert_array_equal(back.faces, F)
    (tmp_path / "q.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2/2 3/3 -1\n")
    q = read_obj(tmp_path / "q.obj")
    np.testing.assert_array_equal(q.faces, [[0, 1, 2], [0, 2, 3]])
    (tmp_path / "bad.obj").write_text("v 0 0 0\nf 1 2 x\n")
    with pytest.raises(ValueError, match=r"bad\.obj, line 2"):
        read_obj(tmp_path / "bad.obj")
    (tmp_path / "range.obj").write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match=r"range\.obj: faces\[0\]: vertex index 1 out of range"):
        read_obj(tmp_path / "range.obj")


@pytest.mark.parametrize("writer", [write_stl, write_obj])
def test_writes_are_atomic(tmp_path, writer, monkeypatch):
    V, F = _mesh()
    target = tmp_path / "out.mesh"
    writer(target, V, F)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.mesh"]
    before = target.read_bytes()
    # bad input: nothing written, the old file untouched
    with pytest.raises(ValueError, match=r"faces\[3\]: vertex index 99 out of range"):
        bad = F.copy()
        bad[3, 1] = 99
        writer(target, V, bad)
    assert target.read_bytes() == before

    # a failure while moving into place leaves neither a temp file nor a changed target
    def boom(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError, match="disk full"):
        writer(target, V[:4], F[:2])
    monkeypatch.undo()
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.mesh"]
    # parent folders are created
    writer(tmp_path / "sub" / "x.mesh", V, F)
    assert (tmp_path / "sub" / "x.mesh").stat().st_size > 0


@pytest.mark.parametrize(
    ("vertices", "faces", "match"),
    [
        (np.zeros((4, 2)), [[0, 1, 2]], r"vertices: expected shape \(V, 3\)"),
        ([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], [[0, 1, 2]], r"vertices\[2\]: contains NaN"),
        (np.zeros((3, 3)), [[0, 1]], r"faces: expected shape \(F, 3\)"),
        (
            np.zeros((3, 3)),
            [[0, 1, 2], [0, 1, -1]],
            r"faces\[1\]: vertex index -1 out of range 0..2",
        ),
        (np.zeros((3, 3)), [[0, 1, 2.5]], "faces: expected integer vertex indices"),
        (np.zeros((3, 3)), [[True, False, True]], "faces: expected integer vertex indices"),
    ],
)
def test_bad_meshes_raise_value_error_naming_the_item(vertices, faces, match, tmp_path):
    with pytest.raises(ValueError, match=match):
        validate_mesh(vertices, faces)
    with pytest.raises(ValueError, match=match):
        write_stl(tmp_path / "x.stl", vertices, faces)
    assert not any(tmp_path.iterdir())


def test_empty_and_float_faces():
    _, f = validate_mesh(np.zeros((3, 3)), np.array([[0.0, 1.0, 2.0]]))
    assert f.dtype == np.int64
    _, f = validate_mesh(np.zeros((0, 3)), [])
    assert f.shape == (0, 3)
