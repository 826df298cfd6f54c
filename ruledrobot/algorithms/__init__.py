"""The paper's three refinement algorithms for discrete ruled surfaces (section 3).

* ``projection`` (§3.1): Plücker coordinates refined in R^6, every step
  projected back onto the line manifold M^4 by Eq. 4;
* ``combined`` (§3.2): the discrete striction curve (§2.4, computed once)
  refined in R^3, the spherical image refined geodesically on S^2 (§2.7),
  lines rebuilt from both;
* ``dh`` (§3.3): the DH frames of the rulings refined by geodesic subdivision
  in SE(3) (§2.8); the refined frames give the lines (their z axes), an
  approximate striction curve (their origins) and a smooth frame motion.  The
  frames are taken with sign-continuous x axes
  (``RuledSurface.dh_frames("continuous")``): the same origins and z axes as
  the design's DH frames, without the half turns where the distribution
  parameter changes sign (a decision, see ``docs/conventions.md``).

All lengths are metres, in the frame the input lines are given in.
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
    """Refined discrete ruled surface, the result of :func:`refine`.

    All in the frame of the input lines, lengths [m].

    Attributes
    ----------
    lines : Lines
        The refined rulings (M lines).
    frames : ndarray, shape (M, 4, 4), or None
        Refined DH frames (z along the ruling, origin on it) for ``"dh"``,
        else None.
    striction : ndarray, shape (M, 3), or None
        The refined striction polygon [m]: ``combined``, the refined discrete
        striction curve; ``dh``, the frame origins; ``projection``, None
        (compute it from the lines with :class:`RuledSurface` if needed).
    closed, flip : bool
        Topology of the result (the input's): periodic, and closed with an
        orientation flip (Möbius band).
    algorithm : str
        ``"projection"``, ``"combined"`` or ``"dh"``.
    scheme : str
        The subdivision scheme's name.
    steps : int
        Number of refinement steps.
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
        """Return the refined rulings as a :class:`RuledSurface`.

        Returns
        -------
        surface : RuledSurface
            ``lines`` with the result's ``closed`` and ``flip``.
        """
        return RuledSurface(self.lines, closed=self.closed, flip=self.flip if self.closed else None)


def check_distinct_neighbours(plucker: FloatArray, closed: bool, what: str = "lines") -> None:
    """Check that no two consecutive lines coincide.

    A duplicated ruling has no DH frame (its common normal with the next is
    undefined) and the refined surface kinks there.  Lines count as coincident
    when their gap (:func:`~ruledrobot.geometry.lines.neighbour_gaps`) is below
    ``COINCIDENT_REL`` times the median gap or ``COINCIDENT_ABS`` [m];
    orientation does not count.

    Parameters
    ----------
    plucker : ndarray, shape (N, 6)
        Plücker rows ``[l, m]`` of the rulings (moment [m]).
    closed : bool
        Also compare the last line with the first.
    what : str, default "lines"
        Name of the argument the error message blames.

    Raises
    ------
    ValueError
        Naming up to six coincident pairs (indices from 0) with their gaps [m]
        and the median gap.
    """
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

    Parameters
    ----------
    lines : Lines or RuledSurface
        The rulings, in any frame (lengths [m]).  A :class:`RuledSurface`
        brings its own ``closed`` and ``flip``; for :class:`Lines` a closed
        sequence whose last line points against its first is closed with a
        flip (Möbius band).
    algorithm : {"projection", "combined", "dh"}, default "dh"
        ``projection``: Plücker rows subdivided in R^6 and projected by Eq. 4
        after every step (paper §3.1); ``combined``: the discrete striction
        curve (§2.4) in R^3 and the spherical image on S^2 (§2.7), the lines
        through the refined points along the refined directions (§3.2);
        ``dh``: the sign-continuous DH frames subdivided along screw motions
        in SE(3) (§2.8, §3.3).
    scheme : str, default "four_point"
        One of :data:`~ruledrobot.subdivision.SCHEME_NAMES`.
    steps : int, default 4
        Number of refinement steps, ``0 <= steps <= 20``.
    closed : bool or None, default None
        For :class:`Lines`: periodic (None means False).  For a
        :class:`RuledSurface` it must agree with the surface's own flag.
    **params : float
        Scheme parameters: ``w`` (four_point), ``mu`` (ternary_four_point);
        see :func:`ruledrobot.subdivision.get_scheme`.

    Returns
    -------
    result : RefineResult
        The refined rulings, with the frames (``dh``) and the striction
        polygon (``combined``, ``dh``).  Open sequences keep their first and
        last rulings.

    Raises
    ------
    ValueError
        For an input that is neither :class:`Lines` nor :class:`RuledSurface`,
        a ``closed`` that contradicts the surface, an unknown algorithm, scheme
        or parameter, a bad step count, coincident consecutive rulings
        (:func:`check_distinct_neighbours`), too few rulings for the scheme,
        or more than :data:`~ruledrobot.subdivision.MAX_REFINED` refined rulings.
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
