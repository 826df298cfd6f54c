"""Subdivision schemes on R^n, S^2, SE(3) and the manifold of lines.

``subdivide`` is the user entry point; schemes live in :mod:`.schemes`, the
spaces in :mod:`.spaces`, the boundary handling in :mod:`.engine`.
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
    """Validate a number of subdivision steps (0 <= steps <= 20)."""
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
    """How many elements ``steps`` steps of ``scheme`` make of ``n`` (exact)."""
    for _ in range(steps):
        n = scheme.refined_length(n, closed)
    return n


def check_size(
    scheme: Scheme, n: int, steps: int, closed: bool, what: str, limit: int = MAX_REFINED,
    bytes_per_element: float | None = BYTES_PER_ELEMENT,
) -> int:
    """The refined count, or ValueError with the numbers (and the memory estimate when
    ``bytes_per_element`` is given) and the most steps that fit."""
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
    """Raise ValueError when ``n`` elements are too few for ``scheme``."""
    if n < scheme.min_points:
        raise ValueError(
            f"{what}: scheme {scheme.name!r} needs at least {scheme.min_points} elements, got {n}"
        )


def refine_plucker(
    plucker: FloatArray, scheme: Scheme, steps: int, closed: bool, flip: bool
) -> FloatArray:
    """The projection algorithm on Plücker rows (N, 6): one step of ``scheme`` in R^6,
    then every element projected onto M^4 by Eq. 4; repeated ``steps`` times."""
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

    * (N, 3) or (N, d) points -> Euclidean R^d (the linear scheme);
    * (N, 3) unit vectors with ``space="sphere"`` -> geodesic scheme on S^2;
    * (N, 4, 4) poses -> geodesic scheme in SE(3) (screw motions);
    * :class:`~ruledrobot.Lines` -> the projection algorithm (R^6 + Eq. 4).

    ``closed`` makes the sequence periodic; ``flip=True`` closes it with an
    orientation flip (Möbius band; for lines detected automatically when the
    last line points against the first).  Open sequences keep their ends.
    Scheme parameters: ``w`` (four_point), ``mu`` (ternary_four_point).
    Returns refined elements of the same kind.
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
