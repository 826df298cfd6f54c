"""Which orders of cuts a wire can make, checked before planning.

A hot wire passes through the whole block, so every cut divides it; the part is
what lies on the kept side of every cut.  Two rules follow (``docs/wirecut.md``):

1. **A closed cut that keeps its inside frees the part.**  Once the loop closes,
   the part no longer hangs on the clamped block: a later cut through it would
   cut a loose piece.  A later cut whose wire crosses the loop's inside is
   refused, naming both cuts — make it first.
2. **A closed cut that keeps its outside (a hole) is refused**: its wire must
   enter through a slit, and the slit would run through the part.

The inside of a loop is tested in the plane normal to its mean ruling direction,
on the polygon of its chord midpoints (tube-like loops: columns, bands).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...geometry.checks import FloatArray
from ...io.lines import LinesDocument
from ..job.spec import Job
from .wire_geometry import chords

__all__ = ["check_cut_order"]


def _points_in_polygon(p: FloatArray, poly: FloatArray) -> np.ndarray:
    """(N,) bool: 2-D points ``p`` (N, 2) inside the closed polygon ``poly`` (K, 2)
    (crossing number)."""
    a, b = poly, np.roll(poly, -1, axis=0)
    x, y = p[:, None, 0], p[:, None, 1]
    crosses = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = a[None, :, 0] + (y - a[None, :, 1]) * (b[None, :, 0] - a[None, :, 0]) / (
            b[None, :, 1] - a[None, :, 1]
        )
    return (crosses & (x < xi)).sum(axis=1) % 2 == 1


def _frames_of(doc: LinesDocument) -> FloatArray:
    from ...geometry.ruled import RuledSurface

    return RuledSurface(doc.lines, closed=bool(doc.closed)).dh_frames("continuous")


def check_cut_order(job: Job, documents: Sequence[LinesDocument] | None = None) -> None:
    """ValueError naming the cuts when the job's order breaks a rule of the module doc.

    ``documents``: the cuts' input rulings (``cut.surface.document()`` of each, in the job's
    order) when the caller read them already."""
    where = str(job.source or "job")
    docs = list(documents) if documents is not None else [None] * len(job.cuts)
    for k, cut in enumerate(job.cuts):
        if docs[k] is None:  # read each surface once, when the rules need it
            docs[k] = cut.surface.document()
    for i, cut in enumerate(job.cuts):
        closed = bool(docs[i].closed)
        if not closed or cut.keep is None:
            continue
        if isinstance(cut.keep, str) and cut.keep == "outside":
            raise ValueError(
                f"{where}: cut '{cut.name}': keep = \"outside\" (a hole) cannot be cut with a "
                "wire: it enters the loop through a slit, and the slit would cut the part"
            )
        if not (isinstance(cut.keep, str) and cut.keep == "inside"):
            continue
        F = _frames_of(docs[i])
        c0, c1, hit = chords(F, job.stock)
        if not hit.any():
            continue
        axis = F[hit, :3, 2].mean(axis=0)
        axis /= np.linalg.norm(axis)
        u = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        mid = F[hit, :3, 3] + (0.5 * (c0 + c1))[hit, None] * F[hit, :3, 2]
        poly = np.stack([mid @ u, mid @ v], axis=1)
        for j, later in enumerate(job.cuts[i + 1 :], start=i + 1):
            G = _frames_of(docs[j])
            g0, g1, ghit = chords(G, job.stock)
            if not ghit.any():
                continue
            t = np.linspace(0.0, 1.0, 9)
            pts = (G[ghit, None, :3, 3] + (g0[ghit, None] + t * (g1 - g0)[ghit, None])[..., None]
                   * G[ghit, None, :3, 2]).reshape(-1, 3)  # fmt: skip
            inside = _points_in_polygon(np.stack([pts @ u, pts @ v], axis=1), poly)
            if inside.mean() > 0.02:
                raise ValueError(
                    f"{where}: cut '{later.name}' comes after cut '{cut.name}', a closed cut "
                    f"that keeps its inside: the part is loose once '{cut.name}' closes, and "
                    f"'{later.name}' would cut through it; list '{later.name}' before "
                    f"'{cut.name}'"
                )
