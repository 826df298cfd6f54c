"""The values URScript programs hold in the interpreter and their conversions: poses
(:class:`PoseValue`), vectors and matrices for the built-ins, arguments for the table's
checks (:func:`~.functions.bind`)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ...geometry import se3
from .program import Pose, ScriptRuntimeError

__all__ = ["PoseValue", "argument_of", "matrix_of", "pose_of", "vector_of"]


class PoseValue(list):
    """A URScript pose ``p[x, y, z, rx, ry, rz]``: a list of 6 numbers that knows it is a pose."""

    def __repr__(self) -> str:
        return "p" + super().__repr__()


def argument_of(v: object) -> object:
    """A runtime value as the argument checks take it (numbers as float, poses as Pose)."""
    if isinstance(v, bool) or isinstance(v, str):
        return v
    if isinstance(v, (int, float)):
        return float(v)
    if isinstance(v, PoseValue):
        return Pose(tuple(float(x) for x in v))
    if isinstance(v, list):
        return [argument_of(x) for x in v]
    return v


def vector_of(v: object, n: int, what: str) -> np.ndarray:
    """``v`` as an (n,) float array; a runtime error naming ``what`` when it is not n numbers."""
    if not isinstance(v, list) or len(v) != n:
        raise ScriptRuntimeError(f"{what}: expected a list of {n} numbers, got {v!r}")
    try:
        return np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ScriptRuntimeError(f"{what}: expected numbers, got {v!r}") from None


def pose_of(v: np.ndarray | Iterable[float]) -> PoseValue:
    """6 numbers as a URScript pose."""
    return PoseValue(float(x) for x in v)


def matrix_of(p: object, what: str) -> np.ndarray:
    """A pose (6 numbers, UR pose vector) as a 4x4 matrix."""
    return se3.pose_from_ur_vector(vector_of(p, 6, what))
