"""How far a pose lies inside or outside a UR arm's reach, in metres.

The analytic IK (:mod:`.analytic`) reduces the arm to a planar two-link problem:
for each shoulder and wrist branch, the origin of DH frame 3 must lie at a distance
``D`` from the shoulder point with ``|a2| - |a3| <= D <= |a2| + |a3|`` (the elbow's
annulus), and the wrist point ``p5`` must lie outside the cylinder ``r = d4`` about
the base axis.  The distances to these bounds are lengths a user can act on: "the
wrist is 87 mm beyond the stretched arm" means the pose (or the block) has to come
about 87 mm closer to the shoulder.

* :func:`reach_margin` of a joint solution: how far (m) its elbow target lies
  inside the annulus (0 at the stretched or folded elbow).
* :func:`reach_excess` of a pose: per IK branch, how far (m) the pose misses the
  reach (> 0) or lies inside it (<= 0, minus the margin), defined where the IK has
  no solution as well.  Equal to ``-reach_margin`` of the branch's solution where
  one exists.

Calibrated arms use their nominal table (their reach differs by millimetres).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._checks import FloatArray
from .analytic import WRIST_EPS, URGeometry

if TYPE_CHECKING:
    from ..arm.model import RobotModel

__all__ = ["REACH_DIRECTIONS", "elbow_distance", "reach_excess", "reach_margin"]

#: what a positive excess means, per code of :func:`reach_excess` ``kind``
REACH_DIRECTIONS = {0: "within reach", 1: "too far from the shoulder",
                    2: "too close to the shoulder", 3: "inside the shoulder cylinder"}


def _annulus(g: URGeometry) -> tuple[float, float]:
    return abs(abs(g.a2) - abs(g.a3)), abs(g.a2) + abs(g.a3)


def elbow_distance(model: RobotModel, q: ArrayLike) -> FloatArray:
    """Return the distance (m) from the shoulder to the origin of DH frame 3 in the arm plane.

    ``sqrt(a2^2 + a3^2 + 2 a2 a3 cos q3)``, of joint positions ``q`` (..., 6).
    """
    g = model.nominal.ur_geometry
    q3 = np.asarray(q, dtype=np.float64)[..., 2] + float(model.nominal.theta_offset[2])
    d2 = g.a2 * g.a2 + g.a3 * g.a3 + 2.0 * g.a2 * g.a3 * np.cos(q3)
    return np.sqrt(np.maximum(d2, 0.0))


def reach_margin(model: RobotModel, q: ArrayLike) -> FloatArray:
    """Return how far (m) the elbow target of ``q`` lies inside the elbow's annulus.

    Joint positions ``q`` (..., 6): ``min(|a2| + |a3| - D, D - ||a2| - |a3||)`` (0 stretched
    or folded).
    """
    lo, hi = _annulus(model.nominal.ur_geometry)
    D = elbow_distance(model, q)
    return np.minimum(hi - D, D - lo)


def reach_excess(
    model: RobotModel, T: ArrayLike, check: bool = True
) -> tuple[FloatArray, np.ndarray]:
    """Per IK branch, how far (m) TCP poses ``T`` (..., 4, 4, world frame) miss the arm's reach.

    ``(excess, kind)``, both (..., 8) in the branch order of ``model.ik``.

    ``excess > 0``: the pose is out of reach on that branch by that distance (the
    elbow target beyond the stretched arm, inside the folded one, or the wrist point
    inside the shoulder cylinder); ``<= 0``: it reaches, ``-excess`` is the
    :func:`reach_margin`.  ``kind`` (int8): 0 within reach, 1 too far, 2 too close,
    3 inside the shoulder cylinder (:data:`REACH_DIRECTIONS`).  The elbow branches of a
    (shoulder, wrist) pair share their values.  At an exactly singular wrist q6 = 0 is
    taken (as :meth:`RobotModel.ik` does by default).
    """
    nom = model.nominal
    g = nom.ur_geometry
    if g is None:
        raise ValueError(f"reach_excess: {model.name} is not a UR-structure arm")
    Tf = model.flange_poses(T, check=check)
    shape = Tf.shape[:-2]
    F = Tf.reshape(-1, 4, 4)
    lo, hi = _annulus(g)
    x6, y6, z6, p = (F[:, :3, k] for k in range(4))
    p5 = p - g.d6 * z6
    r2 = p5[:, 0] ** 2 + p5[:, 1] ** 2
    rho = np.sqrt(np.maximum(r2 - g.d4 * g.d4, 0.0))
    inside = r2 < g.d4 * g.d4
    norm = np.sqrt(np.maximum(r2 * (rho * rho + g.d4 * g.d4), 1e-300))
    out = np.empty((F.shape[0], 8))
    kind = np.empty((F.shape[0], 8), dtype=np.int8)
    cyl = np.abs(g.d4) - np.sqrt(r2)
    for si, sgn1 in enumerate((1.0, -1.0)):
        c1 = -(p5[:, 1] * g.d4 + sgn1 * p5[:, 0] * rho) / norm
        s1 = (p5[:, 0] * g.d4 - sgn1 * p5[:, 1] * rho) / norm
        Px = p5[:, 0] * c1 + p5[:, 1] * s1
        Py = p5[:, 2] - g.d1
        ax = x6[:, 0] * s1 - x6[:, 1] * c1
        by = y6[:, 0] * s1 - y6[:, 1] * c1
        w = np.sqrt(ax * ax + by * by)
        sing = w < WRIST_EPS
        ws = np.where(sing, 1.0, w)
        s6, c6 = np.where(sing, 0.0, -by / ws), np.where(sing, 1.0, ax / ws)
        z4 = -(s6[:, None] * x6 + c6[:, None] * y6)
        ux = z4[:, 0] * c1 + z4[:, 1] * s1
        uy = z4[:, 2]
        for wi, sgn5 in enumerate((1.0, -1.0)):
            D = np.hypot(Px - g.d5 * sgn5 * ux, Py - g.d5 * sgn5 * uy)
            e = np.maximum(D - hi, lo - D)
            k = np.where(e > 0.0, np.where(D > hi, 1, 2), 0).astype(np.int8)
            e = np.where(inside, np.maximum(cyl, 0.0), e)
            k = np.where(inside, np.int8(3), k)
            for ei in range(2):
                b = 4 * si + 2 * wi + ei
                out[:, b] = e
                kind[:, b] = k
    return out.reshape(*shape, 8), kind.reshape(*shape, 8)
