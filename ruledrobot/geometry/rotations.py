"""The angle of a rotation and the angle between two rotations: one formula.

For a rotation matrix ``R`` by the angle ``theta`` about the unit axis ``u``
(Rodrigues: ``R = I + sin(theta) [u]_x + (1 - cos(theta)) [u]_x^2``)::

    trace(R) - 1     = 2 cos(theta)
    vee(R - R^T)     = 2 sin(theta) u        (vee: the axial vector of a skew matrix)

so ``theta = atan2(|vee(R - R^T)| / 2, (trace(R) - 1) / 2)`` in ``[0, pi]``.  Both parts
carry their own information: near 0 the sine part gives the angle to a relative
rounding error (``arccos((trace - 1) / 2)`` loses half the digits there: an angle
below about 1e-8 rad reads as 0), near pi the cosine part pins the quadrant and the
sine part still resolves ``pi - theta`` to an absolute ~1e-16 rad (``arccos`` loses
half the digits there too).  The same value as the norm of the rotation vector
(:func:`ruledrobot.geometry.se3.rotvec_from_matrix`) without the quaternion's square
roots and branches.  The distance between two rotations ``A``, ``B`` is the angle of
``A^T B`` (the geodesic distance on SO(3), bi-invariant).

Every consumer (a trajectory's TCP error, the playback's orientation error, the path
program's decimation, a calibration's flange rotation) calls these; the guard in
``tests/architecture/test_one_home.py`` fails on a second spelling.
Units: rad.  Shapes: leading batch axes broadcast.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .checks import FloatArray

__all__ = ["angle_between", "rotation_angle"]


def _rotations(R: ArrayLike, name: str) -> FloatArray:
    """Rotation parts (..., 3, 3) of rotation matrices (..., 3, 3) or poses (..., 4, 4)."""
    R = np.asarray(R, dtype=np.float64)
    if R.ndim < 2 or R.shape[-2:] not in ((3, 3), (4, 4)):
        raise ValueError(f"{name}: expected rotation matrices (..., 3, 3) or poses "
                         f"(..., 4, 4), got shape {R.shape}")  # fmt: skip
    return R[..., :3, :3]


def rotation_angle(R: ArrayLike) -> FloatArray:
    """Rotation angles (...,) in [0, pi] rad of rotation matrices (..., 3, 3).

    ``atan2(|vee(R - R^T)| / 2, (trace(R) - 1) / 2)`` (module doc: accurate near 0 and
    near pi).  Poses (..., 4, 4) are read by their rotation part.
    """
    R = _rotations(R, "R")
    s = 0.5 * np.sqrt((R[..., 2, 1] - R[..., 1, 2]) ** 2 + (R[..., 0, 2] - R[..., 2, 0]) ** 2
                      + (R[..., 1, 0] - R[..., 0, 1]) ** 2)  # fmt: skip
    c = 0.5 * (R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1.0)
    return np.arctan2(s, c)


def angle_between(A: ArrayLike, B: ArrayLike) -> FloatArray:
    """Angles (...,) in [0, pi] rad of the rotations taking ``A`` to ``B`` (..., 3, 3).

    The rotation angle of ``A^T B`` (:func:`rotation_angle`): the geodesic distance on
    SO(3), the same in any world frame and symmetric in ``A``, ``B``.  Batch axes
    broadcast; poses (..., 4, 4) are read by their rotation part.
    """
    A, B = _rotations(A, "A"), _rotations(B, "B")
    return rotation_angle(np.einsum("...ji,...jk->...ik", A, B))
