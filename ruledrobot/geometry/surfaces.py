"""Built-in parametric ruled surfaces: exact rulings for tests, examples and job files.

Every surface is a one-parameter family of oriented lines: ruling ``u`` passes
through the base point ``b(u)`` along the unit direction ``l(u)``, so the
surface point is ``x(u, v) = b(u) + v l(u)`` (metres; ``u`` in radians for the
angular families, metres for the hyperbolic paraboloid).  All coordinates are
world coordinates; the surfaces are placed with their axis along ``z``.

=========================  ==========================================================
name                       ruling ``u`` (parameters, defaults)
=========================  ==========================================================
``cylindroid``             Plücker conoid ``z (x^2 + y^2) = 2 c x y``: through
                           ``(0, 0, c sin 2u)`` along ``(cos u, sin u, 0)``
                           (``c=0.5``).  Ruling ``u + pi`` is ruling ``u`` reversed.
``hyperbolic_paraboloid``  ``z = x y / c``, the family ``x = u``: through
                           ``(u, 0, 0)`` along ``(0, 1, u/c)`` (``c=1``).
``hyperboloid``            ``(x^2 + y^2)/a^2 - z^2/c^2 = 1``: through
                           ``(a cos u, a sin u, 0)`` along ``(-a sin u, a cos u, c)``
                           (``a=1, c=1``).
``helicoid``               ``x sin(z/p) = y cos(z/p)``: through ``(0, 0, p u)``
                           along ``(cos u, sin u, 0)`` (``pitch p=0.2`` m/rad).
``helical_surface``        the line through ``point`` along ``direction`` moved by
                           the helical motion ``H(u)`` = rotation ``u`` about ``z``
                           plus translation ``pitch u`` along ``z``
                           (``point=(1,0,0), direction=(0,1,1), pitch=0.2``).
``helical_developable``    tangents of the helix ``(r cos u, r sin u, h u)``: through
                           it along ``(-r sin u, r cos u, h)``
                           (``radius r=1, pitch h=0.3`` m/rad); its striction curve
                           (curve of regression) is the helix.
``conoid``                 right conoid (generalised Plücker conoid) with the ``z``
                           axis as directrix: through ``(0, 0, height sin(waves u))``
                           along ``(cos u, sin u, 0)`` (``height=0.5, waves=3``);
                           ``waves=2`` is the cylindroid with ``c = height``.
``mobius_band``            Möbius band: through the centre circle point
                           ``(R cos u, R sin u, 0)`` along
                           ``(cos(u/2) cos u, cos(u/2) sin u, sin(u/2))``
                           (``radius R=1``).  Ruling ``u + 2 pi`` is ruling ``u``
                           reversed.
=========================  ==========================================================

Use the samplers (``cylindroid(u, c=...)`` ... -> :class:`Lines`), the generic
:func:`ruling` (exact Plücker rows for any parameter array shape), or the
registry :data:`SURFACES` / :func:`sample_surface` to ask for a surface by name
with keyword parameters (what a job file does).  Exact membership tests exist
where the surface is algebraic/implicit: :func:`cylindroid_residual`,
:func:`hyperbolic_paraboloid_residual`, :func:`hyperboloid_residual`,
:func:`helicoid_residual`; each returns the first-order (Sampson) distance
``F / |grad F|`` in metres.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ._arrays import norm
from .checks import FloatArray, as_float_array, as_point
from .lines import Lines, plucker_from_point_direction
from .surface_residuals import (
    _finite,
    _nonzero,
    _positive,
    cylindroid_residual,
    helicoid_residual,
    hyperbolic_paraboloid_residual,
    hyperboloid_residual,
)

__all__ = [
    "SURFACES",
    "SurfaceSample",
    "SurfaceSpec",
    "conoid",
    "cylindroid",
    "cylindroid_residual",
    "helical_developable",
    "helical_motion",
    "helical_surface",
    "helicoid",
    "helicoid_residual",
    "hyperbolic_paraboloid",
    "hyperbolic_paraboloid_residual",
    "hyperboloid",
    "hyperboloid_residual",
    "mobius_band",
    "ruling",
    "sample_surface",
    "surface_point",
]

Closure = Literal["open", "closed", "flip"]
PointsDirections = tuple[FloatArray, FloatArray]


# --------------------------------------------------------------------------
# parameter checking
# --------------------------------------------------------------------------


def _param_u(u: ArrayLike) -> FloatArray:
    return as_float_array(u, "u")


def _vector3(value: Any, name: str) -> FloatArray:
    return as_point(value, name, what="x, y, z")


def _direction3(value: Any, name: str) -> FloatArray:
    arr = _vector3(value, name)
    if not np.any(arr != 0.0):
        raise ValueError(f"{name}: expected a non-zero direction vector, got {value!r}")
    return arr


def _positive_int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer, float)):
        raise ValueError(f"{name}: expected a positive integer, got {value!r}")
    if float(value) != int(value) or int(value) < 1:
        raise ValueError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


# --------------------------------------------------------------------------
# the families: (u, params) -> base points (..., 3), directions (..., 3)
# --------------------------------------------------------------------------


def _stack(x: FloatArray, y: FloatArray, z: FloatArray) -> FloatArray:
    x, y, z = np.broadcast_arrays(x, y, z)
    return np.stack([x, y, z], axis=-1)


def _cylindroid_pd(u: FloatArray, c: float) -> PointsDirections:
    zero = np.zeros_like(u)
    return _stack(zero, zero, c * np.sin(2.0 * u)), _stack(np.cos(u), np.sin(u), zero)


def _hyperbolic_paraboloid_pd(u: FloatArray, c: float) -> PointsDirections:
    zero = np.zeros_like(u)
    return _stack(u, zero, zero), _stack(zero, np.ones_like(u), u / c)


def _hyperboloid_pd(u: FloatArray, a: float, c: float) -> PointsDirections:
    cu, su = np.cos(u), np.sin(u)
    return _stack(a * cu, a * su, np.zeros_like(u)), _stack(-a * su, a * cu, np.full_like(u, c))


def _helicoid_pd(u: FloatArray, pitch: float) -> PointsDirections:
    zero = np.zeros_like(u)
    return _stack(zero, zero, pitch * u), _stack(np.cos(u), np.sin(u), zero)


def _helical_surface_pd(
    u: FloatArray, point: FloatArray, direction: FloatArray, pitch: float
) -> PointsDirections:
    T = helical_motion(u, pitch)
    R, t = T[..., :3, :3], T[..., :3, 3]
    return R @ point + t, R @ direction


def _helical_developable_pd(u: FloatArray, radius: float, pitch: float) -> PointsDirections:
    cu, su = np.cos(u), np.sin(u)
    return (
        _stack(radius * cu, radius * su, pitch * u),
        _stack(-radius * su, radius * cu, np.full_like(u, pitch)),
    )


def _conoid_pd(u: FloatArray, height: float, waves: int) -> PointsDirections:
    zero = np.zeros_like(u)
    return _stack(zero, zero, height * np.sin(waves * u)), _stack(np.cos(u), np.sin(u), zero)


def _mobius_pd(u: FloatArray, radius: float) -> PointsDirections:
    cu, su, ch = np.cos(u), np.sin(u), np.cos(0.5 * u)
    return (
        _stack(radius * cu, radius * su, np.zeros_like(u)),
        _stack(ch * cu, ch * su, np.sin(0.5 * u)),
    )


# --------------------------------------------------------------------------
# registry
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class SurfaceSpec:
    """One built-in ruled surface.

    * ``name``: registry key; ``description``: the parametrisation in words.
    * ``defaults``: keyword parameters and their default values (metres/radians).
    * ``domain``: default parameter interval ``(start, stop)`` for sampling.
    * ``closure``: topology over the default domain when sampled without its
      end point: ``"open"``, ``"closed"`` (periodic, period ``stop - start``) or
      ``"flip"`` (ruling ``stop`` is ruling ``start`` reversed).
    * ``residual``: exact membership test ``(points, **params) -> (...)`` metres,
      or None.
    """

    name: str
    description: str
    defaults: Mapping[str, Any]
    domain: tuple[float, float]
    closure: Closure
    _family: Callable[..., PointsDirections] = field(repr=False)
    _checks: Mapping[str, Callable[[Any, str], Any]] = field(repr=False)
    residual: Callable[..., FloatArray] | None = field(default=None, repr=False)

    @property
    def period(self) -> float | None:
        """Parameter period for closed/flip surfaces; None for open ones.

        ``u + period`` is the same ruling, reversed for ``"flip"``.
        """
        return None if self.closure == "open" else self.domain[1] - self.domain[0]

    def params(self, **params: Any) -> dict[str, Any]:
        """The full, checked parameter set: defaults updated with ``params``.

        Unknown names or bad values raise ValueError naming the parameter and
        listing the accepted ones.
        """
        unknown = sorted(set(params) - set(self.defaults))
        if unknown:
            ok = ", ".join(f"{k}={v!r}" for k, v in self.defaults.items())
            raise ValueError(
                f"surface {self.name!r}: unknown parameter(s) {unknown}; accepted: {ok}"
            )
        merged = {**self.defaults, **params}
        return {
            k: self._checks[k](v, f"surface {self.name!r} parameter {k}") for k, v in merged.items()
        }

    def points_directions(self, u: ArrayLike, **params: Any) -> PointsDirections:
        """Return base points ``b(u)`` and unit directions ``l(u)``, each (..., 3).

        For parameters ``u`` of any shape (...).
        """
        uu = _param_u(u)
        b, d = self._family(uu, **self.params(**params))
        return b, d / norm(d)[..., None]

    def plucker(self, u: ArrayLike, **params: Any) -> FloatArray:
        """Exact rulings as Plücker rows (..., 6) for parameters ``u`` (...)."""
        b, d = self.points_directions(u, **params)
        return plucker_from_point_direction(b, d)

    def __call__(self, u: ArrayLike, **params: Any) -> Lines:
        """The rulings at parameters ``u`` (N,) (a scalar gives one line) as :class:`Lines`."""
        uu = _param_u(u)
        if uu.ndim > 1:
            raise ValueError(f"u: expected a scalar or a 1-D array of parameters, got {uu.shape}")
        return Lines(self.plucker(uu.reshape(-1), **params))


_Check = Callable[[Any, str], Any]
"""A parameter's check: ``(value, name) -> checked value``; ValueError naming ``name``."""

_TURN = (0.0, 2.0 * np.pi)


def _surface(
    name: str,
    description: str,
    family: Callable[..., PointsDirections],
    params: Mapping[str, tuple[Any, _Check]],
    *,
    closure: Closure = "open",
    domain: tuple[float, float] = _TURN,
    residual: Callable[..., FloatArray] | None = None,
) -> SurfaceSpec:
    """A :class:`SurfaceSpec` whose ``params`` give each parameter once, as ``name:
    (default, check)``; the domain is one turn ``[0, 2 pi)`` unless given."""
    defaults = {k: default for k, (default, _) in params.items()}
    checks = {k: check for k, (_, check) in params.items()}
    return SurfaceSpec(name, description, defaults, domain, closure, family, checks, residual)


_SPECS: dict[str, SurfaceSpec] = {
    s.name: s
    for s in (
        _surface(
            "cylindroid",
            "Plücker conoid z (x^2+y^2) = 2 c x y: ruling u through (0, 0, c sin 2u) along "
            "(cos u, sin u, 0); ruling u + pi is ruling u reversed",
            _cylindroid_pd,
            {"c": (0.5, _nonzero)},
            closure="flip",
            domain=(0.0, np.pi),
            residual=cylindroid_residual,
        ),
        _surface(
            "hyperbolic_paraboloid",
            "z = x y / c, rulings x = u: through (u, 0, 0) along (0, 1, u/c)",
            _hyperbolic_paraboloid_pd,
            {"c": (1.0, _nonzero)},
            domain=(-1.0, 1.0),
            residual=hyperbolic_paraboloid_residual,
        ),
        _surface(
            "hyperboloid",
            "(x^2+y^2)/a^2 - z^2/c^2 = 1: ruling u through (a cos u, a sin u, 0) along "
            "(-a sin u, a cos u, c)",
            _hyperboloid_pd,
            {"a": (1.0, _positive), "c": (1.0, _positive)},
            closure="closed",
            residual=hyperboloid_residual,
        ),
        _surface(
            "helicoid",
            "ruling u through (0, 0, pitch u) along (cos u, sin u, 0)",
            _helicoid_pd,
            {"pitch": (0.2, _nonzero)},
            residual=helicoid_residual,
        ),
        _surface(
            "helical_surface",
            "the line (point, direction) moved by the helical motion: rotation u about z "
            "and translation pitch u along z",
            _helical_surface_pd,
            {
                "point": ((1.0, 0.0, 0.0), _vector3),
                "direction": ((0.0, 1.0, 1.0), _direction3),
                "pitch": (0.2, _finite),
            },
        ),
        _surface(
            "helical_developable",
            "tangents of the helix (r cos u, r sin u, h u): through it along "
            "(-r sin u, r cos u, h); r = radius, h = pitch (m/rad)",
            _helical_developable_pd,
            {"radius": (1.0, _positive), "pitch": (0.3, _finite)},
        ),
        _surface(
            "conoid",
            "right conoid: ruling u through (0, 0, height sin(waves u)) along (cos u, sin u, 0)",
            _conoid_pd,
            {"height": (0.5, _finite), "waves": (3, _positive_int)},
            closure="closed",
        ),
        _surface(
            "mobius_band",
            "ruling u through (R cos u, R sin u, 0) along "
            "(cos(u/2) cos u, cos(u/2) sin u, sin(u/2)); ruling u + 2 pi is ruling u reversed",
            _mobius_pd,
            {"radius": (1.0, _positive)},
            closure="flip",
        ),
    )
}

SURFACES: Mapping[str, SurfaceSpec] = MappingProxyType(_SPECS)
"""Registry: surface name -> :class:`SurfaceSpec` (callable ``spec(u, **params) -> Lines``)."""


def _spec(name: str) -> SurfaceSpec:
    if name not in SURFACES:
        raise ValueError(
            f"surface: unknown surface {name!r}; expected one of {', '.join(SURFACES)}"
        )
    return SURFACES[name]


def ruling(name: str, u: ArrayLike, **params: Any) -> FloatArray:
    """Exact Plücker rows (..., 6) of surface ``name`` at parameters ``u`` (any shape)."""
    return _spec(name).plucker(u, **params)


def surface_point(name: str, u: ArrayLike, v: ArrayLike, **params: Any) -> FloatArray:
    """Surface points ``b(u) + v l(u)`` (..., 3) for broadcastable ``u``, ``v`` (m)."""
    b, d = _spec(name).points_directions(u, **params)
    vv = as_float_array(v, "v")
    return b + vv[..., None] * d


# --------------------------------------------------------------------------
# named samplers
# --------------------------------------------------------------------------


def cylindroid(u: ArrayLike, c: float = 0.5) -> Lines:
    """Cylindroid (Plücker conoid) rulings at ``u`` (N,) rad.

    Through ``(0, 0, c sin 2u)`` along ``(cos u, sin u, 0)``. The rulings through the double
    line ``|z| <= c`` of the z axis; ruling ``u + pi`` is ruling ``u`` reversed (closed with a
    flip)."""
    return SURFACES["cylindroid"](u, c=c)


def hyperbolic_paraboloid(u: ArrayLike, c: float = 1.0) -> Lines:
    """Rulings ``x = u`` (N,) m of ``z = x y / c``: through ``(u, 0, 0)`` along ``(0, 1, u/c)``."""
    return SURFACES["hyperbolic_paraboloid"](u, c=c)


def hyperboloid(u: ArrayLike, a: float = 1.0, c: float = 1.0) -> Lines:
    """Return one ruling family of the hyperboloid of revolution at ``u`` (N,) [rad].

    ``(x^2+y^2)/a^2 - z^2/c^2 = 1``: through ``(a cos u, a sin u, 0)`` along ``(-a sin u, a
    cos u, c)``.
    """
    return SURFACES["hyperboloid"](u, a=a, c=c)


def helicoid(u: ArrayLike, pitch: float = 0.2) -> Lines:
    """Right helicoid rulings at ``u`` (N,) rad.

    Through ``(0, 0, pitch u)`` along ``(cos u, sin u, 0)``; ``pitch`` in m/rad."""
    return SURFACES["helicoid"](u, pitch=pitch)


def helical_surface(
    u: ArrayLike,
    point: ArrayLike = (1.0, 0.0, 0.0),
    direction: ArrayLike = (0.0, 1.0, 1.0),
    pitch: float = 0.2,
) -> Lines:
    """General helical ruled surface.

    The line through ``point`` (3,) along ``direction`` (3,) moved by :func:`helical_motion`
    ``(u, pitch)`` for each ``u`` (N,) rad."""
    return SURFACES["helical_surface"](u, point=point, direction=direction, pitch=pitch)


def helical_developable(u: ArrayLike, radius: float = 1.0, pitch: float = 0.3) -> Lines:
    """Return the tangent lines of the helix ``(r cos u, r sin u, h u)`` at ``u`` (N,) [rad].

    Through the helix point along ``(-r sin u, r cos u, h)``; ``r = radius`` m, ``h =
    pitch`` m/rad.
    """
    return SURFACES["helical_developable"](u, radius=radius, pitch=pitch)


def conoid(u: ArrayLike, height: float = 0.5, waves: int = 3) -> Lines:
    """Right conoid at ``u`` (N,) rad.

    Through ``(0, 0, height sin(waves u))`` along ``(cos u, sin u, 0)``; directrix the z axis,
    director plane z = 0."""
    return SURFACES["conoid"](u, height=height, waves=waves)


def mobius_band(u: ArrayLike, radius: float = 1.0) -> Lines:
    """Möbius band rulings at ``u`` (N,) rad.

    Through ``(R cos u, R sin u, 0)`` along ``(cos(u/2) cos u, cos(u/2) sin u, sin(u/2))``;
    ruling ``u + 2 pi`` is ruling ``u`` reversed, so ``u = 2 pi k / N`` (k < N) is a sequence
    closed with a flip."""
    return SURFACES["mobius_band"](u, radius=radius)


def helical_motion(phi: ArrayLike, pitch: float) -> FloatArray:
    """Helical motions (..., 4, 4).

    Rotation by ``phi`` (...) rad about the z axis and translation ``pitch * phi`` (m) along
    it. A one-parameter subgroup of SE(3)."""
    phi = as_float_array(phi, "phi")
    pitch = _finite(pitch, "pitch")
    c, s = np.cos(phi), np.sin(phi)
    T = np.zeros((*phi.shape, 4, 4))
    T[..., 0, 0], T[..., 0, 1], T[..., 1, 0], T[..., 1, 1] = c, -s, s, c
    T[..., 2, 2] = T[..., 3, 3] = 1.0
    T[..., 2, 3] = pitch * phi
    return T


# --------------------------------------------------------------------------
# sampling by name
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class SurfaceSample:
    """Rulings sampled from a built-in surface.

    ``lines`` (N), their parameters ``u`` (N,), the topology ``closed``/``flip``
    to pass on to :class:`~ruledrobot.geometry.ruled.RuledSurface`, and the
    surface ``name`` with its full parameter set ``params``.
    """

    name: str
    lines: Lines
    u: FloatArray
    closed: bool
    flip: bool
    params: dict[str, Any]


def sample_surface(
    name: str,
    n: int = 8,
    start: float | None = None,
    stop: float | None = None,
    closed: bool | None = None,
    **params: Any,
) -> SurfaceSample:
    """``n`` rulings of the surface ``name`` at evenly spaced parameters.

    * ``closed=None``: closed exactly when the surface is periodic (see
      :attr:`SurfaceSpec.closure`) and neither ``start`` nor ``stop`` is given;
    * closed: ``u_k = start + period k / n`` (k < n), ``start`` defaults to the
      domain start; ``stop`` must be omitted or equal ``start + period``;
    * open: ``n`` parameters from ``start`` to ``stop`` inclusive (defaults: the domain).

    Unknown surfaces or parameters, ``n < 2`` (``n < 3`` closed) or a closed
    request on an open surface raise ValueError.
    """
    spec = _spec(name)
    full = spec.params(**params)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n: expected an integer number of rulings >= 2, got {n!r}")
    if closed is None:
        closed = spec.closure != "open" and start is None and stop is None
    u0 = spec.domain[0] if start is None else _finite(start, "start")
    if closed:
        period = spec.period
        if period is None:
            raise ValueError(
                f"closed: surface {name!r} is not periodic; sample it open (closed=False)"
            )
        if n < 3:
            raise ValueError(f"n: a closed sample needs at least 3 rulings, got {n}")
        if stop is not None and not np.isclose(_finite(stop, "stop"), u0 + period):
            raise ValueError(
                f"stop: a closed sample of {name!r} spans one period {period:.6g}; "
                f"expected stop = start + period = {u0 + period:.6g} or none, got {stop!r}"
            )
        u = u0 + period * np.arange(n) / n
    else:
        u1 = spec.domain[1] if stop is None else _finite(stop, "stop")
        if u1 == u0:
            raise ValueError(f"stop: equals start ({u0!r}); expected a non-empty interval")
        u = np.linspace(u0, u1, n)
    lines = spec(u, **full)
    return SurfaceSample(
        name, lines, u, bool(closed), bool(closed and spec.closure == "flip"), full
    )
