"""Bookkeeping of the gallery: checks, what a picture shows, shared measurements."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..geometry.checks import FloatArray
from ..geometry.lines import Lines
from ..geometry.mesh import Mesh, strip_mesh
from ..geometry.ruled import RuledSurface

# --------------------------------------------------------------------------
# bookkeeping
# --------------------------------------------------------------------------


def _check(name: str, value: float, op: str, limit: float) -> dict[str, Any]:
    """One check: passes when ``value op limit`` (NaN never passes)."""
    v, lim = float(value), float(limit)
    if op == "<":
        ok = v < lim
    elif op == ">":
        ok = v > lim
    elif op == "==":
        ok = v == lim
    else:  # pragma: no cover - programming error
        raise ValueError(f"op: expected '<', '>' or '==', got {op!r}")
    return {
        "name": name,
        "value": v,
        "op": op,
        "limit": lim,
        "passed": bool(ok and math.isfinite(v)),
    }


@dataclass
class _Scene:
    """What one picture shows (all world coordinates, metres)."""

    title: str
    input_segments: FloatArray  # (K, 2, 3) thick: the initial rulings
    mesh: Mesh | None = None  # translucent refined strip
    rulings: FloatArray | None = None  # (M, 2, 3) thin refined rulings
    curves: list[tuple[FloatArray, str, str]] = field(default_factory=list)  # points, colour, label
    points: list[tuple[FloatArray, str, str]] = field(default_factory=list)


@dataclass
class _Example:
    record: dict[str, Any]
    scene: _Scene


def _segments(lines: Lines, centres: FloatArray, half: float) -> FloatArray:
    """Segments (N, 2, 3) of ``lines`` from ``centre - half l`` to ``centre + half l``."""
    l = lines.direction
    return np.stack([centres - half * l, centres + half * l], axis=1)


def _thin(lines: Lines, centres: FloatArray, half: float, every: int = 1) -> FloatArray:
    return _segments(lines[::every], centres[::every], half)


def _picture(
    title: str,
    lines: Lines,
    input_centres: FloatArray,
    surface: RuledSurface,
    centres: FloatArray,
    half: float,
    every: int,
    mesh_centre: str | FloatArray = "striction",
    **shown: Any,
) -> _Scene:
    """A refinement's picture: the input ``lines`` about ``input_centres``, the strip of the
    refined ``surface`` about ``mesh_centre``, every ``every``-th refined ruling about
    ``centres``, each ``half`` (m) to either side; ``shown``: the curves and points."""
    return _Scene(
        title,
        _segments(lines, input_centres, half),
        mesh=strip_mesh(surface, half_width=half, centre=mesh_centre),
        rulings=_thin(surface.lines, centres, half, every=every),
        **shown,
    )


def _record(
    name: str, title: str, res_like: Any, n_input: int, checks: list[dict[str, Any]], **extra: Any
) -> dict[str, Any]:
    return {
        "name": name,
        "title": title,
        "algorithm": res_like.algorithm,
        "scheme": res_like.scheme,
        "steps": int(res_like.steps),
        "n_input": int(n_input),
        "n_refined": len(res_like.lines),
        "closed": bool(res_like.closed),
        "flip": bool(res_like.flip),
        "checks": checks,
        **extra,
    }


def _manifold_residuals(x: FloatArray) -> tuple[float, float]:
    """max | |l| - 1 | and max |l . m| of Plücker rows (N, 6)."""
    l, m = x[:, :3], x[:, 3:]
    return (
        float(np.abs(np.linalg.norm(l, axis=1) - 1.0).max()),
        float(np.abs(np.einsum("ni,ni->n", l, m)).max()),
    )
