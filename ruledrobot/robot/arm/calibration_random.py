"""Seeded random factory calibrations of realistic size, and the DH table of given joint axes.

:func:`random_calibration` perturbs a nominal arm's joint axes the way real
calibrations arise and reads the DH table off them with :func:`dh_from_axes`
(used by tests, the benchmarks and ``ruledrobot ursim --calibration random:SEED``).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from ...geometry.angles import wrap_angle
from .._checks import FloatArray
from .calibration import Calibration, CalibrationError, _nominal_model, zero_frames
from .ur_tables import NominalDH

__all__ = ["dh_from_axes", "random_calibration"]


class _Named(Protocol):
    name: str


def _signed_angle(u: FloatArray, v: FloatArray, axis: FloatArray) -> float:
    """Angle turning ``u`` into ``v`` about ``axis`` (unit vectors, u and v normal to axis)."""
    return math.atan2(float(np.cross(u, v) @ axis), float(u @ v))


def dh_from_axes(
    points: ArrayLike,
    directions: ArrayLike,
    flange: ArrayLike,
    reference_x: ArrayLike | None = None,
) -> FloatArray:
    """The standard-DH table of a 6R arm given its joint axes at ``q = 0``.

    Parameters
    ----------
    points, directions : (6, 3) a point and the unit direction of each joint axis in
        the base frame; axis 1 must be the base z axis through the origin.
    flange : (4, 4) the flange frame at ``q = 0``; its z axis must lie on axis 6.
    reference_x : optional (6, 3) x axes of frames 1..6 the result should follow
        (a common normal has two directions; the one nearer the reference is taken,
        so that a perturbed UR keeps the signs of its nominal ``a`` and ``alpha``).

    Returns
    -------
    (6, 4) per joint ``[theta_offset, a, d, alpha]``.  Frame ``i`` sits at the foot on
    axis ``i + 1`` of the common normal of axes ``i`` and ``i + 1``; for parallel
    axes the foot of the previous frame's origin (so ``d_i = 0``).  Nearly parallel
    axes give the far-away common normal, hence the large ``d`` of real calibrations.
    """
    P = np.asarray(points, dtype=np.float64).reshape(6, 3)
    U = np.asarray(directions, dtype=np.float64).reshape(6, 3)
    F = np.asarray(flange, dtype=np.float64).reshape(4, 4)
    U = U / np.linalg.norm(U, axis=1, keepdims=True)
    o = np.zeros(3)
    x = np.array([1.0, 0.0, 0.0])
    z = U[0]
    if (
        np.linalg.norm(z - np.array([0.0, 0.0, 1.0])) > 1e-12
        or np.linalg.norm(np.cross(P[0], z)) > 1e-12
    ):
        raise ValueError("directions[0]: axis 1 must be the base z axis through the origin")
    out = np.zeros((6, 4))
    for i in range(5):
        v, p = U[i + 1], P[i + 1]
        n = np.cross(z, v)
        nn = float(np.linalg.norm(n))
        w = o - p
        if nn < 1e-14:  # parallel: foot of the previous origin
            t1 = 0.0
            foot2 = p + (w @ v) * v
            xi = foot2 - o
            length = float(np.linalg.norm(xi))
            xi = xi / length if length > 1e-15 else (x if reference_x is None else
                                                       np.asarray(reference_x)[i])  # fmt: skip
        else:
            b = float(z @ v)
            dz, ev = float(z @ w), float(v @ w)
            den = nn * nn
            t1 = (b * ev - dz) / den
            t2 = (ev - b * dz) / den
            foot2 = p + t2 * v
            xi = n / nn
        if reference_x is not None and xi @ np.asarray(reference_x, dtype=np.float64)[i] < 0.0:
            xi = -xi
        foot1 = o + t1 * z
        out[i] = (_signed_angle(x, xi, z), float((foot2 - foot1) @ xi), t1, _signed_angle(z, v, xi))
        o, x, z = foot2, xi, v
    # joint 6: the flange z lies on axis 6
    zf, of, xf = F[:3, 2], F[:3, 3], F[:3, 0]
    if np.linalg.norm(np.cross(z, zf)) > 1e-9 or np.linalg.norm(np.cross(of - o, z)) > 1e-9:
        raise ValueError("flange: its z axis must lie on axis 6")
    out[5] = (_signed_angle(x, xf, z), 0.0, float((of - o) @ z), 0.0)
    return out


def _small_rotation(rng: np.random.Generator, axis: FloatArray, sigma: float) -> FloatArray:
    """A rotation matrix by a random vector normal to ``axis`` (each component ~ N(0, sigma))."""
    w = rng.normal(0.0, sigma, 3)
    w -= (w @ axis) * axis
    angle = float(np.linalg.norm(w))
    if angle == 0.0:
        return np.eye(3)
    k = w / angle
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def random_calibration(
    model: str | _Named = "ur5e", seed: int = 0, *, scale: float = 1.0
) -> Calibration:
    """A seeded, realistic factory calibration of ``model`` (for tests and demos).

    Built the way a real one arises: the nominal joint axes at ``q = 0`` are tilted
    (each by a random rotation of about ``1.5e-3 * scale`` rad per component, normal to
    it) and moved (about ``0.3 mm * scale`` per component), the flange is moved along
    axis 6 and turned about it, each joint zero is offset by about ``3e-5 * scale`` rad,
    and the DH table is then read off the perturbed axes (:func:`dh_from_axes`).  As in
    real calibrations, the nearly parallel axes 2-4 get large, nearly cancelling
    ``d2..d4`` and ``theta2..4``.  Axis 1 stays the base z axis.  A draw the checks
    refuse (at ``scale`` 1 rarely: ``d`` beyond 10 km when two axes come out parallel
    to 1e-7 rad) is drawn again, up to 20 times; at ``scale`` 10 nearly all are
    refused and the last refusal is raised.
    """
    name = model if isinstance(model, str) else model.name
    nom = _nominal_model(name)
    rng = np.random.default_rng(seed)
    source = f"seeded random (seed {seed}" + (f", scale {scale:g})" if scale != 1.0 else ")")
    for attempt in range(_ATTEMPTS):
        try:
            return _random_attempt(nom, rng, scale, source)
        except CalibrationError:
            if attempt == _ATTEMPTS - 1:
                raise
    raise AssertionError("unreachable")  # pragma: no cover


_ATTEMPTS = 20


def _random_attempt(
    nom: NominalDH, rng: np.random.Generator, scale: float, source: str
) -> Calibration:
    F = zero_frames(nom.theta_offset, nom.a, nom.d, nom.alpha)
    points = F[:6, :3, 3].copy()
    dirs = F[:6, :3, 2].copy()
    tilt, shift = 1.5e-3 * scale, 3e-4 * scale
    for i in range(1, 6):
        dirs[i] = _small_rotation(rng, dirs[i], tilt) @ dirs[i]
        dirs[i] /= np.linalg.norm(dirs[i])
        dp = rng.normal(0.0, shift, 3)
        points[i] = points[i] + dp - (dp @ dirs[i]) * dirs[i]
    # flange: on the new axis 6, near the nominal flange origin, x turned about the axis
    z6 = dirs[5]
    of = points[5] + ((F[6, :3, 3] - points[5]) @ z6) * z6 + rng.normal(0.0, shift) * z6
    x6 = F[6, :3, 0] - (F[6, :3, 0] @ z6) * z6
    x6 /= np.linalg.norm(x6)
    turn = rng.normal(0.0, 1e-4 * scale)
    x6 = math.cos(turn) * x6 + math.sin(turn) * np.cross(z6, x6)
    flange = np.eye(4)
    flange[:3, 0], flange[:3, 1], flange[:3, 2], flange[:3, 3] = x6, np.cross(z6, x6), z6, of
    table = dh_from_axes(points, dirs, flange, reference_x=F[1:, :3, 0])
    table[:, 0] += rng.normal(0.0, 3e-5 * scale, 6)
    table[:, 0] = wrap_angle(table[:, 0])
    checksum = tuple(int(c) for c in rng.integers(0, 2**32, 6))
    return Calibration.from_dh(nom.name, table, checksum=checksum, source=source, status=2)


