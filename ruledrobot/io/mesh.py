"""Triangle mesh files: binary STL and Wavefront OBJ (metres); all writes are atomic.

* :func:`write_stl`: binary STL, little endian: 80-byte header, ``uint32``
  facet count, per facet the unit normal ``(b - a) x (c - a)`` normalised (zero
  for a degenerate triangle) and the three vertices as ``float32``, then a
  ``uint16`` attribute (0).  Units are metres (STL itself has none; the header
  says ``units=m``).
* :func:`write_obj`: ``v x y z`` lines and ``f i j k`` lines (1-based indices).
* :func:`read_stl` (binary or ASCII) and :func:`read_obj` read them back.

Files are written to a temporary name in the target folder and moved into
place (``os.replace``); bad meshes raise ValueError naming the item before
anything is written.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray
from ..geometry.mesh import IntArray, Mesh, mesh_normals, validate_mesh
from .atomic import atomic_write_bytes, atomic_write_text

__all__ = ["StlMesh", "read_obj", "read_stl", "write_obj", "write_stl"]

_STL_FACET = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])


class StlMesh(NamedTuple):
    """A mesh read from STL.

    Shared ``vertices`` (V, 3) (identical float32 coordinates merged), ``faces`` (F, 3) int64,
    stored facet ``normals`` (F, 3)."""

    vertices: FloatArray
    faces: IntArray
    normals: FloatArray


def write_stl(
    path: str | os.PathLike[str],
    vertices: ArrayLike,
    faces: ArrayLike,
    header: str = "ruledrobot mesh, units=m",
) -> Path:
    """Write a binary STL of ``vertices`` (V, 3) m and ``faces`` (F, 3); returns the path."""
    v, f = validate_mesh(vertices, faces)
    head = header.encode("ascii", errors="replace")[:80].ljust(80, b" ")
    if head.lower().startswith(b"solid"):
        head = b"binary " + head[:73]  # keep readers from taking it for ASCII STL
    data = np.zeros(f.shape[0], dtype=_STL_FACET)
    data["normal"] = mesh_normals(v, f)
    data["vertices"] = v[f]
    payload = head + np.uint32(f.shape[0]).astype("<u4").tobytes() + data.tobytes()
    return atomic_write_bytes(path, payload)


def write_obj(path: str | os.PathLike[str], vertices: ArrayLike, faces: ArrayLike) -> Path:
    """Write a Wavefront OBJ of ``vertices`` (V, 3) m and ``faces`` (F, 3); returns the path.

    Coordinates use 17 significant digits, so they read back exactly.
    """
    v, f = validate_mesh(vertices, faces)
    lines = [f"# ruledrobot mesh, units=m, {v.shape[0]} vertices, {f.shape[0]} faces"]
    lines += [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in v.tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (f + 1).tolist()]
    return atomic_write_text(path, "\n".join(lines) + "\n")


def read_stl(path: str | os.PathLike[str]) -> StlMesh:
    """Read a binary or ASCII STL; identical vertices are merged.  Returns :class:`StlMesh`.

    A file that is neither (wrong size for its facet count, no ``facet`` lines)
    raises ValueError naming the file.
    """
    p = Path(path)
    raw = p.read_bytes()
    if len(raw) >= 84:
        count = int(np.frombuffer(raw, "<u4", 1, 80)[0])
        if len(raw) == 84 + 50 * count:
            data = np.frombuffer(raw, _STL_FACET, count, 84)
            tri = data["vertices"].astype(np.float64)
            return _merge(tri, data["normal"].astype(np.float64))
    if raw.lstrip().lower().startswith(b"solid"):
        return _read_ascii_stl(p, raw.decode("ascii", errors="replace"))
    raise ValueError(
        f"{p}: not an STL file (binary size {len(raw)} does not match its facet count, "
        "and it does not start with 'solid')"
    )


def _read_ascii_stl(p: Path, text: str) -> StlMesh:
    normals: list[list[float]] = []
    verts: list[list[float]] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        tok = line.split()
        if not tok:
            continue
        try:
            if tok[0] == "facet" and len(tok) >= 5 and tok[1] == "normal":
                normals.append([float(t) for t in tok[2:5]])
            elif tok[0] == "vertex":
                if len(tok) != 4:
                    raise ValueError("expected 'vertex x y z'")
                verts.append([float(t) for t in tok[1:4]])
        except ValueError as exc:
            raise ValueError(f"{p}, line {lineno}: {exc}") from None
    if len(verts) != 3 * len(normals) or not normals:
        raise ValueError(
            f"{p}: ASCII STL with {len(normals)} facets and {len(verts)} vertices; "
            "expected three vertices per facet"
        )
    tri = np.asarray(verts, dtype=np.float64).reshape(-1, 3, 3)
    return _merge(tri, np.asarray(normals, dtype=np.float64))


def _merge(tri: FloatArray, normals: FloatArray) -> StlMesh:
    flat = tri.reshape(-1, 3)
    if flat.shape[0] == 0:
        return StlMesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), normals.reshape(0, 3))
    vertices, inverse = np.unique(flat, axis=0, return_inverse=True)
    return StlMesh(vertices, inverse.reshape(-1, 3).astype(np.int64), normals)


def read_obj(path: str | os.PathLike[str]) -> Mesh:
    """Read the vertices and faces of a Wavefront OBJ.

    ``v`` and ``f`` lines; other records ignored.  Faces with more than three corners are
    fanned into triangles; ``f 1/2/3`` corner forms and negative (relative) indices are
    accepted.  Errors name the file and line.
    """
    p = Path(path)
    verts: list[list[float]] = []
    faces: list[list[int]] = []
    with p.open(encoding="utf-8") as fh:
        for lineno, line in enumerate(fh, 1):
            tok = line.split()
            if not tok or tok[0].startswith("#"):
                continue
            try:
                if tok[0] == "v":
                    if len(tok) < 4:
                        raise ValueError("expected 'v x y z'")
                    verts.append([float(t) for t in tok[1:4]])
                elif tok[0] == "f":
                    if len(tok) < 4:
                        raise ValueError("expected at least three face corners")
                    idx = []
                    for t in tok[1:]:
                        k = int(t.split("/")[0])
                        idx.append(k - 1 if k > 0 else len(verts) + k)
                    faces += [[idx[0], idx[i], idx[i + 1]] for i in range(1, len(idx) - 1)]
            except ValueError as exc:
                raise ValueError(f"{p}, line {lineno}: {exc}") from None
    v = np.asarray(verts, dtype=np.float64).reshape(-1, 3)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    try:
        return validate_mesh(v, f)
    except ValueError as exc:
        raise ValueError(f"{p}: {exc}") from None
