"""The paper's six examples (Odehnal, section 4): each refines, measures and records."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ..algorithms import RefineResult, refine
from ..geometry.checks import FloatArray
from ..geometry.lines import Lines, plucker_transform
from ..geometry.ruled import RuledSurface
from ..geometry.surfaces import (
    SURFACES,
    cylindroid,
    helical_developable,
    helical_motion,
    helical_surface,
    hyperboloid,
    hyperboloid_residual,
    mobius_band,
)
from .scene import _check, _Example, _manifold_residuals, _picture, _record, _Scene

# --------------------------------------------------------------------------
# the line-manifold checks of examples 3, 4 and 5
# --------------------------------------------------------------------------


def _manifold_checks(x: FloatArray, prefix: str = "") -> list[dict[str, Any]]:
    """The two checks that refined Plücker rows ``x`` (M, 6) lie on the line manifold:
    ``max | |l| - 1 | < 1e-12`` and ``max |l . m| < 1e-12`` [m], named after ``prefix``."""
    lm, lmm = _manifold_residuals(x)
    return [
        _check(f"{prefix}max | |l| - 1 |", lm, "<", 1e-12),
        _check(f"{prefix}max |l . m|", lmm, "<", 1e-12),
    ]


# --------------------------------------------------------------------------
# example 1: cylindroid, projection algorithm
# --------------------------------------------------------------------------


def _example_cylindroid() -> _Example:
    c = 0.5
    phi = np.arange(8) * np.pi / 8.0
    lines = cylindroid(phi, c=c)
    res = refine(lines, algorithm="projection", scheme="four_point", steps=5, closed=True)
    surf = RuledSurface(res.lines, closed=True)
    s = surf.striction_points()
    axis_dist = float(np.hypot(s[:, 0], s[:, 1]).max())
    # every refined ruling meets the z axis at a right angle: horizontal, and its
    # point nearest the origin lies on the axis
    x = res.lines.plucker
    horiz = float(np.abs(x[:, 2]).max())
    p = res.lines.point
    line_axis = float(np.hypot(p[:, 0], p[:, 1]).max())
    z_span = float((s[:, 2].max() - s[:, 2].min()) / (2.0 * c))
    checks = [
        _check(
            "max distance of refined striction points from the z axis (m)", axis_dist, "<", 1e-9
        ),
        _check("max distance of refined rulings from the z axis (m)", line_axis, "<", 1e-9),
        _check("max |l_z| of refined rulings (horizontal)", horiz, "<", 1e-12),
        _check("flip detected (closed with a flip)", float(res.flip), "==", 1.0),
    ]
    record = _record(
        "cylindroid",
        "Example 1: cylindroid, projection algorithm (four_point, 5 steps)",
        res,
        len(lines),
        checks,
        measurements={"striction_z_span_over_2c": z_span, "c": c},
    )
    s0 = RuledSurface(lines, closed=True).striction_points()
    scene = _picture(record["title"], lines, s0, surf, s, 1.0, 4,
                     points=[(s, "crimson", "refined striction points")])
    return _Example(record, scene)


# --------------------------------------------------------------------------
# example 2: helical developable, projection algorithm
# --------------------------------------------------------------------------


def _helix(u: FloatArray, r: float, h: float) -> FloatArray:
    return np.stack([r * np.cos(u), r * np.sin(u), h * u], axis=-1)


def _distance_to_helix(
    q: FloatArray, r: float, h: float, guess: FloatArray, span: float
) -> tuple[FloatArray, FloatArray]:
    """Distance (M,) of points ``q`` (M, 3) to the helix ``(r cos u, r sin u, h u)``
    and the nearest parameter (M,): a grid search over ``guess +- span`` (65
    samples) followed by Newton's method on ``(c(u) - q) . c'(u) = 0``."""
    grid = guess[:, None] + np.linspace(-span, span, 65)[None, :]
    d2 = np.sum((_helix(grid, r, h) - q[:, None, :]) ** 2, axis=-1)
    u = grid[np.arange(len(q)), np.argmin(d2, axis=1)]
    for _ in range(8):
        cu, su = np.cos(u), np.sin(u)
        e = _helix(u, r, h) - q
        d1 = np.stack([-r * su, r * cu, np.full_like(u, h)], axis=-1)
        dd = np.stack([-r * cu, -r * su, np.zeros_like(u)], axis=-1)
        f = np.einsum("ni,ni->n", e, d1)
        fp = np.einsum("ni,ni->n", d1, d1) + np.einsum("ni,ni->n", e, dd)
        u = u - f / np.where(fp > 0.0, fp, np.inf)
    return np.linalg.norm(_helix(u, r, h) - q, axis=1), u


def _example_helical_developable() -> _Example:
    r, h = 1.0, 0.3
    u0, u1 = 0.0, 1.5 * np.pi
    steps = 4
    densities = (6, 12, 24)
    inner: list[float] = []
    ends: list[float] = []
    shown = None
    for n in densities:
        u = np.linspace(u0, u1, n)
        lines = helical_developable(u, radius=r, pitch=h)
        res = refine(lines, algorithm="projection", scheme="four_point", steps=steps)
        s = RuledSurface(res.lines).striction_points()
        m = len(s)
        d, _ = _distance_to_helix(s, r, h, np.linspace(u0, u1, m), span=(u1 - u0) / (n - 1))
        inner.append(float(d[1:-1].max()))
        ends.append(float(max(d[0], d[-1])))
        if n == 12:
            shown = (lines, res, s)
    ratios = [inner[i] / inner[i + 1] for i in range(len(inner) - 1)]
    where = "interior rulings 1..M-2, end rulings excluded: single-foot striction"
    checks = [
        _check(
            f"max distance striction->helix, {densities[0]} lines, {where} (m)",
            inner[0],
            "<",
            0.1 * r,
        ),
    ]
    for i in range(1, len(densities)):
        checks.append(
            _check(
                f"max distance striction->helix, {densities[i]} lines, interior (m); "
                f"limit: the {densities[i - 1]}-line value",
                inner[i],
                "<",
                inner[i - 1],
            )
        )
    for i, q in enumerate(ratios):
        checks.append(
            _check(
                f"error ratio {densities[i]}->{densities[i + 1]} lines (>= 4: at least 2nd order)",
                q,
                ">",
                4.0,
            )
        )
    assert shown is not None
    lines, res, s = shown
    record = _record(
        "helical_developable",
        "Example 2: helical developable, projection algorithm (four_point, 4 steps)",
        res,
        len(lines),
        checks,
        measurements={
            "input_lines": list(densities),
            "max_distance_interior": inner,
            "max_distance_end_rulings": ends,
            "ratios": ratios,
            "observed_order": [math.log2(q) for q in ratios],
            "radius": r,
            "pitch": h,
            "arc": [u0, u1],
            "picture_input_lines": 12,
        },
    )
    s0 = RuledSurface(lines).striction_points()
    helix = _helix(np.linspace(u0, u1, 400), r, h)
    scene = _picture(record["title"] + ", 12 input lines", lines, s0, res.surface(), s, 0.6, 4,
                     curves=[(helix, "black", "helix (curve of regression)")],
                     points=[(s, "crimson", "refined striction points")])
    return _Example(record, scene)


# --------------------------------------------------------------------------
# example 3: four arbitrary lines, combined algorithm
# --------------------------------------------------------------------------


def _example_four_lines() -> _Example:
    rng = np.random.default_rng(7)
    points = rng.normal(scale=0.5, size=(4, 3))
    directions = rng.normal(size=(4, 3))
    lines = Lines.from_point_direction(points, directions)
    checks = []
    diffs: dict[str, float] = {}
    res = None
    for k in (1, 2, 4):
        res = refine(lines, algorithm="combined", scheme="four_point", steps=k)
        d = float(np.abs(res.lines.plucker[:: 2**k] - lines.plucker).max())
        diffs[str(k)] = d
        checks.append(
            _check(
                f"{k} step(s): max Plücker difference at the input positions "
                f"(refined lines 0, {2**k}, {2 * 2**k}, ...)",
                d,
                "<",
                1e-12,
            )
        )
    assert res is not None
    checks.extend(_manifold_checks(res.lines.plucker, "4 steps: "))
    record = _record(
        "four_lines",
        "Example 3: four lines (seed 7), combined algorithm (four_point, 1/2/4 steps)",
        res,
        len(lines),
        checks,
        steps_checked=[1, 2, 4],
        measurements={"max_plucker_difference": diffs, "seed": 7},
    )
    s0 = RuledSurface(lines).striction_points()
    s = res.striction
    assert s is not None
    scene = _picture(record["title"], lines, s0, res.surface(), s, 0.7, 2, mesh_centre=s,
                     curves=[(s, "crimson", "refined striction curve")])
    return _Example(record, scene)


# --------------------------------------------------------------------------
# example 4: Möbius band, combined algorithm with Chaikin
# --------------------------------------------------------------------------


def _mobius_nearest(s: FloatArray, l: FloatArray, radius: float, grid: int = 1024) -> FloatArray:
    """Parameter (M,) of the exact Möbius ruling nearest each refined ruling.

    Nearness: ``|s - L(u)|^2 / R^2 + 2 (1 - |l . l(u)|)`` (distance of the refined
    striction point ``s`` to the ruling ``L(u)`` and the angle between the lines;
    orientation ignored); a grid search over ``[0, 2 pi)`` then 60 steps of a
    vectorised golden-section search in the bracketing grid cells."""
    spec = SURFACES["mobius_band"]

    def objective(u: FloatArray, s: FloatArray, l: FloatArray) -> FloatArray:
        b, d = spec.points_directions(u, radius=radius)
        v = s - b
        v = v - np.einsum("...i,...i->...", v, d)[..., None] * d
        return np.einsum("...i,...i->...", v, v) / radius**2 + 2.0 * (
            1.0 - np.abs(np.einsum("...i,...i->...", l, d))
        )

    g = np.linspace(0.0, 2.0 * np.pi, grid, endpoint=False)
    f = objective(g[None, :], s[:, None, :], l[:, None, :])
    j = np.argmin(f, axis=1)
    step = g[1] - g[0]
    a, b = g[j] - step, g[j] + step
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(60):
        c1 = b - ratio * (b - a)
        c2 = a + ratio * (b - a)
        left = objective(c1, s, l) < objective(c2, s, l)
        b = np.where(left, c2, b)
        a = np.where(left, a, c1)
    return 0.5 * (a + b)


def _mobius_errors(n: int, radius: float, steps: int) -> tuple[Any, float, float, FloatArray]:
    """Refine ``n`` Möbius rulings (combined/chaikin, closed); return the result, the
    max distance of refined striction points to the exact ruling at the nearest
    parameter, the max angle to it (rad), and that ruling's centre-circle points."""
    u = 2.0 * np.pi * np.arange(n) / n
    res = refine(mobius_band(u, radius=radius), "combined", "chaikin", steps, closed=True)
    x, s = res.lines.plucker, res.striction
    assert s is not None
    uu = _mobius_nearest(s, x[:, :3], radius)
    b, d = SURFACES["mobius_band"].points_directions(uu, radius=radius)
    v = s - b
    v = v - np.einsum("ni,ni->n", v, d)[:, None] * d
    dist = float(np.linalg.norm(v, axis=1).max())
    cosang = np.clip(np.abs(np.einsum("ni,ni->n", x[:, :3], d)), -1.0, 1.0)
    return res, dist, float(np.arccos(cosang).max()), b


def _example_mobius() -> _Example:
    radius = 1.0
    n = 12
    steps = 4
    u = 2.0 * np.pi * np.arange(n) / n
    lines = mobius_band(u, radius=radius)
    res, dist, angle, b = _mobius_errors(n, radius, steps)
    x = res.lines.plucker
    s = res.striction
    assert s is not None
    # the same measure for coarser and finer input (Chaikin: O(h^2) expected)
    others = {str(k): _mobius_errors(k, radius, steps)[1:3] for k in (8, 16)}
    last_first = float(x[-1, :3] @ x[0, :3])
    checks = [
        _check("result closed with a flip (res.flip)", float(res.flip), "==", 1.0),
        _check(
            "l_last . l_first (last refined ruling points against the first)", last_first, "<", 0.0
        ),
        *_manifold_checks(x),
        _check(
            "max distance refined striction point -> exact ruling at nearest parameter (m)",
            dist,
            "<",
            0.1 * radius,
        ),
        _check(
            "max angle refined ruling vs exact ruling at nearest parameter (rad)", angle, "<", 0.05
        ),
    ]
    record = _record(
        "mobius_band",
        "Example 4: Möbius band, combined algorithm (chaikin, 4 steps)",
        res,
        len(lines),
        checks,
        measurements={
            "radius": radius,
            "max_angle_deg": math.degrees(angle),
            "distance_angle_by_input_count": {
                "8": list(others["8"]),
                "12": [dist, angle],
                "16": list(others["16"]),
            },
        },
    )
    # the picture: the band about its centre circle (the striction curve of the
    # Möbius band wanders far inside it): input segments centred on the circle,
    # the refined strip about the points of the refined rulings nearest the
    # centre-circle point of their matched parameter
    spec = SURFACES["mobius_band"]
    circle = spec.points_directions(np.linspace(0.0, 2.0 * np.pi, 200), radius=radius)[0]
    half = 0.4 * radius
    p0 = res.lines.point
    centre = p0 + np.einsum("ni,ni->n", b - p0, x[:, :3])[:, None] * x[:, :3]
    scene = _picture(record["title"], lines, spec.points_directions(u, radius=radius)[0],
                     res.surface(), centre, half, 2, mesh_centre=centre,
                     curves=[(circle, "black", "centre circle"),
                             (s, "crimson", "refined striction curve")])
    return _Example(record, scene)


# --------------------------------------------------------------------------
# examples 5 and 6: the picture of a DH refinement
# --------------------------------------------------------------------------


def _dh_picture(
    title: str, lines: Lines, res: RefineResult, origins: FloatArray, half: float, every: int
) -> _Scene:
    """The picture of a DH refinement (examples 5 and 6).

    The input ``lines`` about their striction points, the refined strip and every
    ``every``-th refined ruling about the refined striction points, each ``half`` [m]
    to either side, and the refined DH frames' ``origins`` (M, 3) [m, world] as a curve.
    """
    s0 = RuledSurface(lines).striction_points()
    surf = res.surface()
    curves = [(origins, "crimson", "DH frame origins")]
    return _picture(title, lines, s0, surf, surf.striction_points(), half, every, curves=curves)


# --------------------------------------------------------------------------
# example 5: hyperboloid of revolution, DH algorithm
# --------------------------------------------------------------------------


def _example_hyperboloid() -> _Example:
    a, c = 0.6, 1.0
    u = np.linspace(0.0, np.pi, 8)
    lines = hyperboloid(u, a=a, c=c)
    res = refine(lines, algorithm="dh", scheme="four_point", steps=4)
    origin = res.striction
    assert origin is not None
    v = np.array([-1.0, 0.0, 1.0])
    pts = origin[:, None, :] + v[None, :, None] * res.lines.direction[:, None, :]
    resid = float(np.abs(hyperboloid_residual(pts, a=a, c=c)).max())
    checks = [
        _check(
            "max |quadric residual| at 3 points per refined ruling (v = -1, 0, 1 m) (m)",
            resid,
            "<",
            1e-9,
        ),
        *_manifold_checks(res.lines.plucker),
    ]
    record = _record(
        "hyperboloid",
        "Example 5: hyperboloid of revolution, DH algorithm (four_point, 4 steps)",
        res,
        len(lines),
        checks,
        measurements={"a": a, "c": c, "u_range": [0.0, float(np.pi)]},
    )
    return _Example(record, _dh_picture(record["title"], lines, res, origin, 1.0, 4))


# --------------------------------------------------------------------------
# example 6: helical ruled surface, DH algorithm
# --------------------------------------------------------------------------


def _example_helical_surface() -> _Example:
    pitch = 0.15
    point, direction = np.array([1.0, 0.0, 0.0]), np.array([0.3, 0.6, 0.8])
    dphi = 0.5
    steps = 3
    phi = dphi * np.arange(6)
    lines = helical_surface(phi, point=point, direction=direction, pitch=pitch)
    res = refine(lines, algorithm="dh", scheme="four_point", steps=steps)
    x = res.lines.plucker
    first = lines.plucker[0]
    # the helical parameter of each refined ruling from the azimuth of its direction
    az = np.unwrap(np.arctan2(x[:, 1], x[:, 0]))
    ph = az - math.atan2(first[1], first[0])
    ph -= 2.0 * np.pi * np.round(ph[0] / (2.0 * np.pi))
    exact = plucker_transform(helical_motion(ph, pitch), first)
    line_err = float(np.abs(exact - x).max())
    uniform = dphi * np.arange(len(x)) / 2**steps
    param_err = float(np.abs(ph - uniform).max())
    frames = res.frames
    assert frames is not None
    frame_err = float(np.abs(helical_motion(ph, pitch) @ frames[0] - frames).max())
    checks = [
        _check(
            "max |Plücker difference| refined ruling vs H(phi) ruling_0 (m)", line_err, "<", 1e-9
        ),
        _check(
            "max |phi_j - j dphi / 2^steps| (refined parameters uniform) (rad)",
            param_err,
            "<",
            1e-9,
        ),
        _check("max |T_j - H(phi_j) T_0| of the refined DH frames", frame_err, "<", 1e-9),
    ]
    record = _record(
        "helical_surface",
        "Example 6: helical ruled surface, DH algorithm (four_point, 3 steps)",
        res,
        len(lines),
        checks,
        measurements={
            "pitch": pitch,
            "point": point.tolist(),
            "direction": direction.tolist(),
            "dphi": dphi,
        },
    )
    return _Example(record, _dh_picture(record["title"], lines, res, frames[:, :3, 3], 0.8, 2))


_EXAMPLES: tuple[Callable[[], _Example], ...] = (
    _example_cylindroid,
    _example_helical_developable,
    _example_four_lines,
    _example_mobius,
    _example_hyperboloid,
    _example_helical_surface,
)
