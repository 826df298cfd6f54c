"""From a part to its cuts: the faces cut exactly, the rest roughed, the baseline beside.

:func:`find_cuts` segments the part (:mod:`.segment`), fits every region
(:mod:`.quadric`), cuts the ruled ones exactly (:mod:`.exact`; faces of the block need
no cut), and when any face is left — not ruled, not determined by its vertices, or a
cut that would gouge the part elsewhere — roughs the part by ``rough_cuts`` loops
(:mod:`.rough`) and the baseline (the visual hull of as many parallel directions) for
comparison.  Every region is fitted, whatever its number of triangles.  Open
cuts come first and closed loops last: a loop that keeps its inside frees the part,
and every later loop needs the piece clamped again (a setup of its own).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from .carved import cut_away
from .exact import block_face, exact_cut
from .measure import measure_cut
from .meshquery import MeshQuery
from .model import CarveCut, CutMeasure
from .quadric import Fit, fit_region
from .readers import PartMesh
from .rough import SEAMS, Loop, choose_loops, loop_lines
from .segment import CREASES, MAX_PIECES, Region, segment

__all__ = ["MAX_REFUSED", "CutPlan", "find_cuts", "prefer_direction"]

#: roughing loops the robot may refuse in one carve before no further loop is asked
MAX_REFUSED = 4


@dataclass(frozen=True)
class CutPlan:
    """A carve's cut plan: the cuts in order, the roughing loops, the regions and notes.

    The cuts in the order they are made with their measures, the roughing loops and the
    baseline's (great circles), the regions and what became of each (``faces``: region
    index -> ``"block face"``, ``"exact"``, or why it was roughed), notes, the voxel
    estimates of the block kept after the roughing loops [m^3] (``kept_voxel``,
    ``baseline_kept_voxel``)."""

    cuts: tuple[CarveCut, ...]
    measures: tuple[CutMeasure, ...]
    loops: tuple[Loop, ...] = field(repr=False)
    baseline: tuple[Loop, ...] = field(repr=False)
    regions: tuple[Region, ...] = field(repr=False)
    faces: dict[int, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    kept_voxel: float = float("nan")
    baseline_kept_voxel: float = float("nan")
    #: the exact cuts the robot check refused, largest face first (the first is probed for
    #: a turn of the block, :func:`.robotcheck.next_best`)
    refused: tuple[CarveCut, ...] = field(default=(), repr=False)


def prefer_direction(stock: Box) -> FloatArray:
    """Return the horizontal direction across the line from the robot base to the block.

    The wire held sideways in front of the arm, as in the demo jobs."""
    c = np.array([stock.centre[0], stock.centre[1], 0.0])
    if np.linalg.norm(c) < 1e-6:
        return np.array([0.0, 1.0, 0.0])
    d = np.cross([0.0, 0.0, 1.0], c)
    return d / np.linalg.norm(d)


def radial_direction(stock: Box) -> FloatArray:
    """The horizontal direction from the robot's base to the block (x when above it)."""
    c = np.array([stock.centre[0], stock.centre[1], 0.0])
    n = np.linalg.norm(c)
    return c / n if n > 1e-6 else np.array([1.0, 0.0, 0.0])


def _unfitted(fit: Fit) -> str:
    """Why a region's fit gives no cut, in words (``carve.json``'s ``faces``)."""
    if fit.kind == "curved":
        return "not ruled (a quadric with no lines on it)"
    if fit.kind == "undetermined":
        return (f"its vertices and normals do not determine one surface (another quadric "
                f"holds them within {fit.residual * 1e3:.3g} mm too: a strip too narrow or "
                "a fold of a few triangles)")  # fmt: skip
    return f"not a ruled quadric within tolerance ({fit.residual * 1e3:.3g} mm)"


def _robot_accepts(check: Callable[[CarveCut], str] | None, centre: FloatArray,
                   notes: list[str]) -> Callable[[Loop], bool] | None:
    """Whether the robot can cut a roughing loop (``check`` on its cut); a refusal noted.
    After :data:`MAX_REFUSED` refusals no loop is asked (nor chosen)."""
    if check is None:
        return None
    refused: list[str] = []

    def accept(loop: Loop) -> bool:
        if len(refused) >= MAX_REFUSED:
            return False
        why = check(CarveCut("rough", "rough", loop_lines(loop, centre), True, "inside",
                             loop.describe()))  # fmt: skip
        if why:
            refused.append(why)
            notes.append(f"roughing loop {loop.describe()}: not chosen, the arm cannot cut it "
                         f"where the block stands ({why})"
                         + (f"; {MAX_REFUSED} loops refused, no further loop is tried"
                            if len(refused) == MAX_REFUSED else ""))  # fmt: skip
        return not why

    return accept


def _fitted(part: PartMesh, regions: list[Region], tolerance: float,
            notes: list[str]) -> list[tuple[Region, Fit]]:  # fmt: skip
    """Every region with its fit.

    A region no ruled surface fits is split at the finer creases of
    :data:`~.segment.CREASES` and replaced by its pieces (new indices, after the last
    region's) when each piece fits (a plane or a ruled quadric;
    :data:`~.segment.MAX_PIECES` at most), said in ``notes``."""
    out: list[tuple[Region, Fit]] = []
    first = max((r.index for r in regions), default=-1) + 1
    for r in regions:
        fit = fit_region(r, tolerance)
        pieces = [] if fit.kind in ("plane", "ruled") else _pieces(part, r, tolerance, first)
        if pieces:
            first += len(pieces)
            notes.append(f"region {r.index} (no one surface fits it) is {len(pieces)} faces "
                         f"meeting at creases: regions {pieces[0][0].index}-"
                         f"{pieces[-1][0].index}")  # fmt: skip
        out += pieces or [(r, fit)]
    return out


def _pieces(part: PartMesh, region: Region, tolerance: float,
            first: int) -> list[tuple[Region, Fit]]:  # fmt: skip
    """The pieces of ``region`` split at the first crease angle of :data:`~.segment.CREASES`
    where each fits, with their fits; [] when none does."""
    if len(region.faces) < 2:
        return []
    for sharp in CREASES:
        pieces = segment(part, sharp, region.faces, first=first)
        if 2 <= len(pieces) <= MAX_PIECES:
            fits = [fit_region(p, tolerance) for p in pieces]
            if all(f.kind in ("plane", "ruled") for f in fits):
                return list(zip(pieces, fits, strict=True))
    return []


def find_cuts(part: PartMesh, stock: Box, query: MeshQuery, tolerance: float,
              rough_cuts: int, lead: float = 0.02, progress=lambda msg: None,
              check: Callable[[CarveCut], str] | None = None) -> CutPlan:  # fmt: skip
    """The cuts of a part in a block (module doc).

    ``check(cut)``: why the robot cannot make a cut where the block stands ("" when it
    can; :class:`.robotcheck.RobotCheck`): an exact cut it refuses leaves its face to the
    roughing loops, a loop it refuses is not chosen, and both are named in the notes."""
    regions = segment(part)
    prefer = prefer_direction(stock)
    faces: dict[int, str] = {}
    exact: list[tuple[CarveCut, CutMeasure]] = []
    refused: list[CarveCut] = []
    notes: list[str] = []
    progress(f"fitting {len(regions)} regions")
    fitted = _fitted(part, regions, tolerance, notes)
    regions = [r for r, _ in fitted]
    for r, fit in fitted:
        if fit.kind == "plane" and block_face(fit, stock, tolerance):
            faces[r.index] = "block face"
            continue
        if fit.kind not in ("plane", "ruled"):
            faces[r.index] = _unfitted(fit)
            continue
        got = exact_cut(fit, r, stock, query, prefer, f"face{r.index}", lead)
        if isinstance(got, str):
            faces[r.index] = got
            notes.append(got)
            continue
        m = measure_cut(got, stock, query, tolerance, r)
        if m.gouge > 0.0:
            why = (f"region {r.index}: its rulings run {m.gouge * 1e3:.2f} mm into the part "
                   "beyond the face: roughed instead")  # fmt: skip
            faces[r.index] = why
            notes.append(why)
            continue
        why = check(got) if check is not None else ""
        if why:
            why = (f"region {r.index}: the arm cannot make its cut where the block stands "
                   f"({why}): roughed instead; `ruledrobot place` searches for a placement "
                   "or turn of the block where it can")  # fmt: skip
            faces[r.index] = why
            notes.append(why)
            refused.append(got)
            continue
        faces[r.index] = "exact"
        exact.append((got, m))
    rough_needed = any(v not in ("exact", "block face") for v in faces.values())
    loops: list[Loop] = []
    base: list[Loop] = []
    kept = base_kept = float("nan")
    rough: list[tuple[CarveCut, CutMeasure]] = []
    if rough_needed and rough_cuts > 0:
        from scipy.spatial import ConvexHull

        hull = part.vertices[ConvexHull(part.vertices).vertices]
        standoff = 0.5 * tolerance
        centre = part.vertices.mean(axis=0)
        progress(f"choosing {rough_cuts} roughing loops")
        made = tuple(c for c, _ in exact)

        def gone(points: FloatArray, shape: tuple[int, int, int]) -> np.ndarray:
            return cut_away(made, stock, points, shape)

        loops, k1 = choose_loops(hull, stock, rough_cuts, standoff, seams=SEAMS,
                                 radial=radial_direction(stock),
                                 accept=_robot_accepts(check, centre, notes),
                                 gone=gone)  # fmt: skip
        if not loops:
            notes.append("no roughing loop: the exact cuts leave nothing outside the part's "
                         "convex hull that a loop could take, or the robot can make none")
        progress("choosing the baseline's directions")
        base, k2 = choose_loops(hull, stock, rough_cuts, standoff, seams=False, gone=gone)
        kept = k1[-1] if k1 else kept
        base_kept = k2[-1] if k2 else base_kept
        for k, loop in enumerate(loops):
            cut = CarveCut(f"rough{k + 1}", "rough", loop_lines(loop, centre), True, "inside",
                           loop.describe())  # fmt: skip
            rough.append((cut, measure_cut(cut, stock, query, tolerance)))
    elif rough_needed:
        notes.append("faces are left uncut (rough_cuts = 0)")
    ordered = ([c for c in exact if not c[0].closed] + [c for c in exact if c[0].closed]
               + rough)  # fmt: skip
    return CutPlan(tuple(c for c, _ in ordered), tuple(m for _, m in ordered), tuple(loops),
                   tuple(base), tuple(regions), faces, tuple(notes), kept,
                   base_kept, tuple(refused))  # fmt: skip
