"""The paper's three refinement algorithms for discrete ruled surfaces (section 3).

* ``projection``: Plücker coordinates refined in R^6, every step projected back
  onto the line manifold by Eq. 4;
* ``combined``: the discrete striction curve (computed once) refined in R^3,
  the spherical image refined geodesically on S^2, lines rebuilt from both;
* ``dh``: the DH frames of the rulings refined by geodesic subdivision in
  SE(3); the refined frames give the lines (their z axes), an approximate
  striction curve (their origins) and a smooth frame motion.  The frames are
  taken with sign-continuous x axes (``RuledSurface.dh_frames("continuous")``):
  the same origins and z axes as the design's DH frames, without the half
  turns where the distribution parameter changes sign.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..geometry import se3
from ..geometry._arrays import cross
from ..geometry.checks import FloatArray
from ..geometry.lines import (
    Lines,
    coincident_neighbours,
    neighbour_gaps,
    plucker_from_point_direction,
)
from ..geometry.ruled import RuledSurface
from ..subdivision import check_length, check_size, check_steps, get_scheme, refine_plucker
from ..subdivision.engine import refine_sequence
from ..subdivision.spaces import EuclideanSpace, SE3Space, SphereSpace

__all__ = ["ALGORITHMS", "RefineResult", "check_distinct_neighbours", "refine"]

ALGORITHMS = ("projection", "combined", "dh")
Algorithm = Literal["projection", "combined", "dh"]


@dataclass(frozen=True)
class RefineResult:
    """Result of :func:`refine`.

    * ``lines``: the refined rulings (M lines);
    * ``frames``: (M, 4, 4) refined DH frames for ``"dh"``, else None;
    * ``striction``: (M, 3) the refined striction polygon (``combined``: the
      refined discrete striction curve; ``dh``: the frame origins; ``projection``:
      None — compute it from the lines with :class:`RuledSurface` if needed);
    * ``closed``, ``flip``: topology of the result (the input's).
    """

    lines: Lines
    frames: FloatArray | None = field(default=None, repr=False)
    striction: FloatArray | None = field(default=None, repr=False)
    closed: bool = False
    flip: bool = False
    algorithm: str = "dh"
    scheme: str = "four_point"
    steps: int = 0

    def surface(self) -> RuledSurface:
        """The refined rulings as a :class:`RuledSurface`."""
        return RuledSurface(self.lines, closed=self.closed, flip=self.flip if self.closed else None)


def check_distinct_neighbours(plucker: FloatArray, closed: bool, what: str = "lines") -> None:
    """ValueError naming consecutive lines that coincide (a duplicated ruling: its DH
    frame is undefined and the refined surface kinks there; remove one of them)."""
    bad = coincident_neighbours(plucker, closed)
    if bad.size:
        n = len(plucker)
        gaps = neighbour_gaps(plucker, closed)
        pairs = ", ".join(f"{i} and {(i + 1) % n} (gap {gaps[i]:.2g} m)" for i in bad[:6])
        more = f" and {bad.size - 6} more" if bad.size > 6 else ""
        raise ValueError(
            f"{what}: consecutive rulings coincide: {pairs}{more}; the median gap is "
            f"{np.median(gaps):.2g} m. Remove the duplicates (indices from 0)"
        )


def refine(
    lines: Lines | RuledSurface,
    algorithm: Algorithm = "dh",
    scheme: str = "four_point",
    steps: int = 4,
    closed: bool | None = None,
    **params: float,
) -> RefineResult:
    """Refine a discrete ruled surface by one of the paper's algorithms.

    ``lines``: :class:`Lines` (with ``closed``, default False) or a
    :class:`RuledSurface` (its own ``closed``/``flip``).  A closed sequence
    whose last line points against its first is closed with a flip.
    ``scheme``/``params``: see :func:`ruledrobot.subdivide`.  Open sequences
    keep their first and last rulings.
    """
    if isinstance(lines, RuledSurface):
        if closed is not None and bool(closed) != lines.closed:
            raise ValueError("closed: contradicts the RuledSurface's own closed flag")
        surf = lines
    elif isinstance(lines, Lines):
        surf = RuledSurface(lines, closed=bool(closed))
    else:
        raise ValueError(
            f"lines: expected ruledrobot.Lines or RuledSurface, got {type(lines).__name__}"
        )
    if algorithm not in ALGORITHMS:
        raise ValueError(f"algorithm: expected one of {', '.join(ALGORITHMS)}, got {algorithm!r}")
    sch = get_scheme(scheme, **params)
    steps = check_steps(steps)
    check_distinct_neighbours(surf.lines.plucker, surf.closed)
    check_length(sch, len(surf.lines), "lines")
    check_size(sch, len(surf.lines), steps, surf.closed, "steps")
    flip = bool(surf.flip)
    common = dict(closed=surf.closed, flip=flip, algorithm=algorithm, scheme=scheme, steps=steps)
    if algorithm == "projection":
        x = refine_plucker(surf.lines.plucker, sch, steps, surf.closed, flip)
        return RefineResult(Lines(x), **common)
    if algorithm == "combined":
        s = refine_sequence(
            EuclideanSpace(), surf.striction_points(), sch, steps, surf.closed, flip
        )
        sph = SphereSpace()
        l = refine_sequence(sph, surf.spherical_image(), sch, steps, surf.closed, flip)
        return RefineResult(Lines(plucker_from_point_direction(s, l)), striction=s, **common)
    space = SE3Space()
    # frames built here are rigid by construction: encode without re-validating
    frames = se3.qt_from_matrix(surf.dh_frames(x_axis="continuous"))
    q = refine_sequence(space, frames, sch, steps, surf.closed, flip)
    frames = space.decode(q)
    origin, z = frames[:, :3, 3], frames[:, :3, 2]
    lines_out = Lines(np.concatenate([z, cross(origin, z)], axis=1))
    return RefineResult(lines_out, frames=frames, striction=origin.copy(), **common)
