"""part.stl is a closed 2-manifold (issue 22, item 6): read back from the file as any CAD
program reads it (float32 coordinates, vertices welded where they are equal), every edge
lies in exactly two triangles of opposite orientation, none has zero area, and every body
has Euler characteristic 2 (a sphere's: no holes, no handles, no pinches).  Before, a
surface through a grid point gave marching cubes coincident vertices: the part demo's
file had 1,144 zero-area triangles and edges shared by 4 to 10 faces.

The checks below are the test's own (no mesh library): the STL parsed with numpy, edges
counted, bodies as the connected components of the edge graph."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ruledrobot.io.demo_cell import DEMO_CELL
from ruledrobot.io.mesh import write_stl
from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.job.demo import PART_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.report.part_mesh import part_mesh

#: a part of our own: a block with a saddle top and a column cut all the way round it
COLUMN_JOB = DEMO_CELL + """\
mass = 1.0

[[cut]]
name = "top"
keep = [0.5, 0.0, 0.3]
[cut.surface]
builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]
rulings = 9
pose = [0.5, 0.0, 0.335, 0.0, 0.0, 0.0]
steps = 4

[[cut]]
name = "column"
keep = "inside"
[cut.surface]
builtin = "hyperboloid"
params = { a = 0.08, c = 0.25 }
rulings = 16
closed = true
pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]
steps = 5
"""

#: the part demo's volume [L] before the fix (right then already: the fault was topology)
DEMO_LITRES = 1.79127


def _column_litres(a: float, c: float = 0.25, step: float = 0.0005) -> float:
    """The column part's volume [L] by the midpoint rule on a 0.5 mm grid: the block
    (0.2 x 0.2 x 0.15 m about its centre) below the saddle z = 0.035 + x y / 0.4 and
    inside the hyperboloid x^2 + y^2 <= a^2 (1 + z^2 / c^2)."""
    x = np.arange(-0.1 + step / 2, 0.1, step)
    z = np.arange(-0.075 + step / 2, 0.075, step)
    X, Y = np.meshgrid(x, x, indexing="ij")
    total = 0
    for zk in z:
        total += np.count_nonzero((X**2 + Y**2 <= a * a * (1.0 + zk * zk / (c * c)))
                                  & (zk <= 0.035 + X * Y / 0.4))  # fmt: skip
    return total * step**3 * 1e3


def _two_passes(cp):
    """The one pass round a loop as :mod:`ruledrobot.wirecut.cut.closed` splits a loop no
    single pass can cut: two passes from the slit ruling, each out to the ruling
    opposite and back along its own kerf (the wide column of the issue was cut so)."""
    S = cp.target_frames
    a, b = cp.extended
    loop = S[a : len(S) - b]  # the slit ruling to itself, M + 1 frames
    half = (len(loop) - 1) // 2
    out = []
    for arc in (loop[: half + 1], loop[::-1][: len(loop) - half]):
        there_and_back = np.concatenate([arc, arc[-2::-1]])
        out.append(dataclasses.replace(cp, frames=there_and_back, surface_frames=None,
                                       extended=(0, 0), kerf_error=None, param=None))  # fmt: skip
    return tuple(out)


def _stl_triangles(path: Path) -> np.ndarray:
    """(F, 3, 3) float32 corners of a binary STL, parsed here."""
    raw = path.read_bytes()
    count = int(np.frombuffer(raw, "<u4", 1, 80)[0])
    assert len(raw) == 84 + 50 * count
    facet = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    return np.frombuffer(raw, facet, count, 84)["v"]


def _check_closed_manifold(tri: np.ndarray) -> dict:
    """Weld equal float32 corners, then the checks of the module doc; returns figures."""
    corners, index = np.unique(tri.reshape(-1, 3), axis=0, return_inverse=True)
    f = index.reshape(-1, 3).astype(np.int64)
    v = corners.astype(np.float64)
    nf, nv = len(f), len(v)
    assert (f[:, 0] != f[:, 1]).all() and (f[:, 1] != f[:, 2]).all() and (f[:, 2] != f[:, 0]).all()
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    assert area.min() > 0.0, f"{int(np.sum(area <= 0.0))} zero-area triangles"
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = directed[:, 0] * nv + directed[:, 1]
    _, once = np.unique(key, return_counts=True)
    assert once.max() == 1, "a directed edge in two faces: not consistently oriented"
    undirected = np.sort(directed, axis=1)
    edges, count = np.unique(undirected[:, 0] * nv + undirected[:, 1], return_counts=True)
    assert (count == 2).all(), f"edges in {sorted(set(count.tolist()) - {2})} faces"
    assert np.isin(directed[:, 1] * nv + directed[:, 0], key).all()  # each reverse exists
    # bodies: the connected components of the vertices joined by the faces' edges
    graph = coo_matrix((np.ones(len(directed)), (directed[:, 0], directed[:, 1])), (nv, nv))
    _, label = connected_components(graph, directed=False)
    body = label[f[:, 0]]
    bodies = np.unique(body)
    euler = []
    for b in bodies:
        fb = f[body == b]
        eb = np.unique(np.sort(np.concatenate([fb[:, [0, 1]], fb[:, [1, 2]], fb[:, [2, 0]]]),
                                axis=1), axis=0)  # fmt: skip
        euler.append(len(np.unique(fb)) - len(eb) + len(fb))
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    volume = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
    return {"bodies": len(bodies), "euler": euler, "volume": volume, "faces": nf,
            "edges": len(edges), "min_area": float(area.min())}  # fmt: skip


@pytest.fixture(scope="module")
def planned(tmp_path_factory) -> dict:
    """The passes (the redundancy search, no timing) of the part demo and the column."""
    out = {}
    for name, text in (("demo", PART_JOB), ("column", COLUMN_JOB)):
        path = tmp_path_factory.mktemp(name) / "job.toml"
        path.write_text(text)
        job = load_job(path)
        model = job.robot_model()
        out[name] = job, tuple(cp for cut in job.cuts for cp in cut_paths(job, cut, model))
    return out


@pytest.mark.parametrize("name", ["demo", "column", "column in two passes"])
def test_part_stl_is_one_closed_two_manifold_of_the_right_volume(planned, name, tmp_path):
    job, passes = planned[name.split()[0]]
    if name == "column in two passes":
        assert [cp.name for cp in passes] == ["top", "column"]  # one pass round the loop
        passes = (passes[0], *_two_passes(passes[1]))
    mesh = part_mesh(job, passes)
    assert mesh is not None
    stl = write_stl(tmp_path / "part.stl", mesh.vertices, mesh.faces)
    got = _check_closed_manifold(_stl_triangles(stl))
    assert got["bodies"] == 1  # each of these parts is one piece
    assert got["euler"] == [2] * got["bodies"]
    assert got["edges"] * 2 == got["faces"] * 3
    expected = DEMO_LITRES if name == "demo" else _column_litres(0.08)
    assert got["volume"] * 1e3 == pytest.approx(expected, rel=0.005)


def test_the_independent_check_finds_what_was_wrong():
    """The check itself: two tetrahedra glued on a face (its edges in four faces), and a
    triangle of zero area, are refused."""
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    faces = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    one = tet[faces]
    _check_closed_manifold(one)  # a closed tetrahedron passes
    other = one.copy()
    other[..., 2] *= -1.0  # mirrored below the face z = 0...
    other = other[:, ::-1]  # ...and turned back outwards
    with pytest.raises(AssertionError):
        _check_closed_manifold(np.concatenate([one, other]))
    flat = one.copy()
    flat[0, 2] = 0.5 * (flat[0, 0] + flat[0, 1])
    with pytest.raises(AssertionError):
        _check_closed_manifold(flat)
