"""Subdivision schemes on R^n, S^2, SE(3) and the manifold of lines.

:func:`subdivide` is the user entry point; the schemes live in :mod:`.schemes`
(paper §2.5–2.6), the spaces in :mod:`.spaces` (§2.7–2.8), the open, closed and
flip-closed boundary handling in :mod:`.engine`.  :func:`refine_plucker` is the
projection algorithm of §3.1; the size guards (:func:`check_steps`,
:func:`check_length`, :func:`check_size`) are shared with
:mod:`ruledrobot.algorithms`.
"""

from __future__ import annotations

from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray, as_float_array
from ..geometry.lines import Lines, plucker_project
from .engine import refine_sequence
from .schemes import SCHEME_NAMES, Scheme, get_scheme
from .spaces import EuclideanSpace, SE3Space, Space, SphereSpace

__all__ = [
    "SCHEME_NAMES",
    "EuclideanSpace",
    "SE3Space",
    "Scheme",
    "Space",
    "SphereSpace",
    "check_size",
    "get_scheme",
    "refine_plucker",
    "refined_count",
    "subdivide",
]

SpaceName = Literal["euclidean", "sphere", "se3"]


def check_steps(steps: int) -> int:
    """Validate a number of subdivision steps.

    Parameters
    ----------
    steps : int
        Number of refinement steps (dimensionless); ``bool`` is refused.

    Returns
    -------
    steps : int
        The same number as a Python ``int``.

    Raises
    ------
    ValueError
        When ``steps`` is not an integer with ``0 <= steps <= 20``.
    """
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or not 0 <= steps <= 20:
        raise ValueError(f"steps: expected an integer 0 <= steps <= 20, got {steps!r}")
    return int(steps)


#: Most elements a refinement may produce (about 1 kB each while refining, frames and
#: lines included: ~5 GB); beyond it :func:`check_size` refuses before any work.
MAX_REFINED = 5_000_000
#: Bytes per refined element used for the memory estimate (measured peak of the dh
#: algorithm: ~300 B per ruling, times margin for the output and its file).
BYTES_PER_ELEMENT = 1000


def refined_count(scheme: Scheme, n: int, steps: int, closed: bool) -> int:
    """Count the elements ``steps`` steps of ``scheme`` make of ``n`` (exact).

    Parameters
    ----------
    scheme : Scheme
        The subdivision scheme (its arity and end rule decide the count).
    n : int
        Number of input elements.
    steps : int
        Number of refinement steps.
    closed : bool
        Whether the sequence is periodic (closed, with or without a flip).

    Returns
    -------
    count : int
        Number of elements after ``steps`` steps, by
        :meth:`Scheme.refined_length` applied ``steps`` times.
    """
    for _ in range(steps):
        n = scheme.refined_length(n, closed)
    return n


def check_size(
    scheme: Scheme, n: int, steps: int, closed: bool, what: str, limit: int = MAX_REFINED,
    bytes_per_element: float | None = BYTES_PER_ELEMENT,
) -> int:
    """Check that a refinement stays within the element limit, before any work.

    Parameters
    ----------
    scheme : Scheme
        The subdivision scheme.
    n : int
        Number of input elements.
    steps : int
        Number of refinement steps asked for.
    closed : bool
        Whether the sequence is periodic.
    what : str
        Name of the argument the error message blames (e.g. ``"steps"``).
    limit : int, default MAX_REFINED
        Most elements allowed after refinement.
    bytes_per_element : float or None, default BYTES_PER_ELEMENT
        Memory per refined element [bytes] for the estimate quoted in the
        error message; None leaves the estimate out.

    Returns
    -------
    count : int
        The refined count (:func:`refined_count`), when it is at most ``limit``.

    Raises
    ------
    ValueError
        When the refined count exceeds ``limit``; the message gives the count,
        the limit (with memory estimates when ``bytes_per_element`` is given)
        and the most steps that fit.
    """
    count = refined_count(scheme, n, steps, closed)
    if count <= limit:
        return count
    fit = max((k for k in range(steps + 1) if refined_count(scheme, n, k, closed) <= limit),
              default=0)  # fmt: skip
    def mem(k: int) -> str:
        return f" (about {k * bytes_per_element / 1e9:.3g} GB)" if bytes_per_element else ""

    raise ValueError(
        f"{what}: {steps} steps of {scheme.name} on {n} elements make {count:,}{mem(count)}; "
        f"the limit is {limit:,}{mem(limit)}: use at most {fit} steps, or fewer input elements"
    )


def check_length(scheme: Scheme, n: int, what: str) -> None:
    """Check that ``n`` elements are enough for ``scheme``.

    Parameters
    ----------
    scheme : Scheme
        The subdivision scheme (its :attr:`Scheme.min_points`).
    n : int
        Number of input elements.
    what : str
        Name of the argument the error message blames (``"lines"``, ``"points"``).

    Raises
    ------
    ValueError
        When ``n < scheme.min_points``.
    """
    if n < scheme.min_points:
        raise ValueError(
            f"{what}: scheme {scheme.name!r} needs at least {scheme.min_points} elements, got {n}"
        )


def refine_plucker(
    plucker: FloatArray, scheme: Scheme, steps: int, closed: bool, flip: bool
) -> FloatArray:
    """Refine lines by the projection algorithm (paper §3.1).

    One step of ``scheme`` on the Plücker rows as points of R^6, then every
    element projected back onto the line manifold M^4 by Eq. 4
    (:func:`~ruledrobot.geometry.lines.plucker_project`); repeated ``steps``
    times.  A flip reverses a line by negating its row.

    Parameters
    ----------
    plucker : ndarray, shape (N, 6)
        Plücker coordinates ``[l, m]`` of the rulings (``|l| = 1``,
        ``l · m = 0``, Eq. 1); ``l`` unit direction, ``m`` moment [m].
    scheme, steps, closed, flip
        The scheme, the number of steps, whether the sequence is periodic and
        whether it closes with a flip (only with ``closed``), as in
        :func:`~ruledrobot.subdivision.engine.refine_sequence`.

    Returns
    -------
    plucker : ndarray, shape (M, 6)
        Plücker rows of the refined rulings, on M^4 to rounding.
    """
    return refine_sequence(
        EuclideanSpace(negate_on_flip=True), plucker, scheme, steps, closed, flip, plucker_project
    )


@overload
def subdivide(
    elements: Lines,
    scheme: str = ...,
    steps: int = ...,
    closed: bool = ...,
    space: SpaceName | None = ...,
    flip: bool | None = ...,
    **params: float,
) -> Lines: ...
@overload
def subdivide(
    elements: ArrayLike,
    scheme: str = ...,
    steps: int = ...,
    closed: bool = ...,
    space: SpaceName | None = ...,
    flip: bool | None = ...,
    **params: float,
) -> FloatArray: ...


def subdivide(
    elements: Lines | ArrayLike,
    scheme: str = "four_point",
    steps: int = 4,
    closed: bool = False,
    space: SpaceName | None = None,
    flip: bool | None = None,
    **params: float,
) -> Lines | FloatArray:
    """Refine a sequence by ``steps`` steps of a subdivision scheme.

    The space follows from the elements unless ``space`` is given:

    * (N, d) points -> Euclidean R^d (the linear scheme);
    * (N, 3) unit vectors with ``space="sphere"`` -> geodesic scheme on S^2
      (paper §2.7);
    * (N, 4, 4) poses -> geodesic scheme in SE(3), screw motions (§2.8);
    * :class:`~ruledrobot.Lines` -> the projection algorithm (R^6 + Eq. 4, §3.1).

    Parameters
    ----------
    elements : Lines or array-like, shape (N, d), (N, 3) or (N, 4, 4)
        The sequence: lines, points (any unit, usually [m]), unit vectors, or
        poses (rigid motions, all in one common frame).
    scheme : str, default "four_point"
        One of :data:`SCHEME_NAMES`.
    steps : int, default 4
        Number of refinement steps, ``0 <= steps <= 20``.
    closed : bool, default False
        Make the sequence periodic.  Open sequences keep their first and last
        elements.
    space : {"euclidean", "sphere", "se3"} or None, default None
        The space of array elements; None infers ``"se3"`` for (N, 4, 4) and
        ``"euclidean"`` otherwise.  Ignored for :class:`~ruledrobot.Lines`.
    flip : bool or None, default None
        Close with an orientation flip (Möbius band): the element after the
        last is the first one flipped (a line reversed, a unit vector negated,
        a frame turned by pi about its x axis).  None: for lines, detected when
        the last line points against the first; for arrays, no flip.
    **params : float
        Scheme parameters: ``w`` (four_point), ``mu`` (ternary_four_point);
        see :func:`get_scheme`.

    Returns
    -------
    refined : Lines or ndarray, shape (M, d), (M, 3) or (M, 4, 4)
        Refined elements of the same kind, in the same frame.

    Raises
    ------
    ValueError
        For an unknown scheme, space or parameter, a bad shape, non-unit
        vectors or non-rigid poses, too few elements, more than
        :data:`MAX_REFINED` refined elements, or (arrays) ``flip=True``
        without ``closed=True``; for lines a flip without ``closed`` is ignored.
    """
    sch = get_scheme(scheme, **params)
    steps = check_steps(steps)
    if isinstance(elements, Lines):
        x = elements.plucker
        check_length(sch, len(x), "lines")
        check_size(sch, len(x), steps, closed, "steps")
        if flip is None:
            flip = bool(closed and x[-1, :3] @ x[0, :3] < 0.0)
        return Lines(refine_plucker(x, sch, steps, closed, bool(flip) and closed))
    arr = np.asarray(elements, dtype=np.float64)
    if space is None:
        space = "se3" if arr.ndim == 3 and arr.shape[1:] == (4, 4) else "euclidean"
    spaces: dict[str, Space] = {
        "euclidean": EuclideanSpace(),
        "sphere": SphereSpace(),
        "se3": SE3Space(),
    }
    if space not in spaces:
        raise ValueError(f"space: expected one of {', '.join(spaces)}, got {space!r}")
    sp = spaces[space]
    if space == "se3":
        arr = as_float_array(arr, "poses", (4, 4))
        if arr.ndim != 3:
            raise ValueError(f"poses: expected shape (N, 4, 4), got {arr.shape}")
    else:
        if arr.ndim != 2:
            raise ValueError(f"points: expected shape (N, d), got {arr.shape}")
        arr = as_float_array(arr, "points", (arr.shape[1],))
        if space == "sphere" and arr.shape[1] != 3:
            raise ValueError(f"unit vectors: expected shape (N, 3), got {arr.shape}")
    check_length(sch, arr.shape[0], (space == "se3" and "poses") or "points")
    check_size(sch, arr.shape[0], steps, closed, "steps")
    if flip and not closed:
        raise ValueError("flip=True needs closed=True")
    x = sp.encode(arr)
    out = refine_sequence(sp, x, sch, steps, closed, bool(flip))
    return sp.decode(out)
