"""What every reader returns and every writer takes: rulings with their segments.

* :class:`Rulings` — the lines (metres, in the frame of the file), whether the
  sequence is closed, and, where the file fixes them, the two end points of
  each ruling (``ends`` (N, 2, 3): tower points of a G-code move, root and tip
  points of a wing panel, the two profiles of a DXF pair) and the pair of
  parallel planes they lie on (:class:`Planes`).
* :class:`Planes` — two parallel planes ``z = 0`` and ``z = distance`` of a frame
  ``pose`` (4, 4): the towers of a foam cutter (the *cutter frame*: x along the
  X/U carriages, y along Y/V, z from the XY tower to the UV tower), the root
  and tip faces of a wing panel.
* :func:`plane_ends` cuts infinite rulings into segments on two planes;
  :func:`fit_planes` chooses planes for rulings that came without any.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...geometry._arrays import FloatArray
from ...geometry.lines import Lines

__all__ = ["Planes", "Rulings", "fit_planes", "plane_ends", "rulings_from_ends"]


@dataclass(frozen=True)
class Planes:
    """Planes ``z = 0`` and ``z = distance`` of the frame ``pose``, and what they are.

    ``distance`` m, signed, non-zero; ``pose`` (4, 4) given in the rulings' frame; ``name``
    says what they are: ``"towers"`` (a G-code file's), ``"faces"`` (a wing panel's root and
    tip), ``"profiles"`` (the planes of two flat CAD profiles), ``"planes"``.
    """

    pose: FloatArray = field(repr=False)
    distance: float
    name: str = "planes"

    def __post_init__(self) -> None:
        T = np.array(self.pose, dtype=np.float64)
        if T.shape != (4, 4) or not np.all(np.isfinite(T)):
            raise ValueError(f"planes: pose must be a finite 4x4 matrix, got shape {T.shape}")
        if not np.isfinite(self.distance) or self.distance == 0.0:
            raise ValueError(f"planes: distance must be finite and non-zero, got {self.distance}")
        T.setflags(write=False)
        object.__setattr__(self, "pose", T)
        object.__setattr__(self, "distance", float(self.distance))


@dataclass(frozen=True)
class Rulings:
    """Rulings read from a file (see the module doc).

    ``lines`` (N); ``closed``: the last ruling is followed by the first;
    ``ends`` (N, 2, 3) m or None; ``planes`` the planes ``ends`` lie on, or None;
    ``feed`` (N-1,) m/s: the speed of the faster wire end on each move where a
    G-code file says it (NaN where it does not), else None; ``source`` names the
    file; ``notes`` are facts a user should hear (skipped moves, guessed units).
    """

    lines: Lines
    closed: bool = False
    ends: FloatArray | None = field(default=None, repr=False)
    planes: Planes | None = None
    feed: FloatArray | None = field(default=None, repr=False)
    source: str = ""
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        n = len(self.lines)
        if self.ends is not None:
            e = np.array(self.ends, dtype=np.float64)
            if e.shape != (n, 2, 3):
                raise ValueError(f"rulings: ends must have shape ({n}, 2, 3), got {e.shape}")
            e.setflags(write=False)
            object.__setattr__(self, "ends", e)
        if self.feed is not None:
            f = np.array(self.feed, dtype=np.float64).reshape(-1)
            f.setflags(write=False)
            object.__setattr__(self, "feed", f)

    def __len__(self) -> int:
        return len(self.lines)

    def path_lines(self) -> Lines:
        """The lines as an open path.

        A closed sequence gets its first ruling again at the end, so that a cut along the path
        goes all the way round."""
        if not self.closed:
            return self.lines
        return Lines(np.concatenate([self.lines.plucker, self.lines.plucker[:1]]))


def rulings_from_ends(a: ArrayLike, b: ArrayLike, where: str) -> Lines:
    """Lines through ``a`` (N, 3) towards ``b`` (N, 3).

    ValueError naming the first ruling whose two ends coincide."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    scale = max(1.0, float(np.abs(np.concatenate([a, b])).max(initial=0.0)))
    bad = np.linalg.norm(b - a, axis=1) <= 1e-12 * scale
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"{where}: ruling {i}: its two ends coincide at {a[i].tolist()} m; "
                         "expected distinct ends")  # fmt: skip
    return Lines.from_two_points(a, b)


def plane_ends(lines: Lines, planes: Planes, where: str = "rulings") -> FloatArray:
    """Where each line meets the planes ``z = 0`` and ``z = distance`` of ``planes``.

    (N, 2, 3) m in the lines' frame. A line within 1e-6 rad of parallel to the planes has no
    such points: ValueError naming it."""
    T = planes.pose
    R, t = T[:3, :3], T[:3, 3]
    l = lines.direction @ R  # directions in the plane frame
    p = (lines.point - t) @ R  # points in the plane frame
    lz = l[:, 2]
    bad = np.abs(lz) < 1e-6
    if bad.any():
        i = int(np.argmax(bad))
        angle = np.degrees(np.arccos(min(1.0, abs(float(lz[i])))))
        raise ValueError(f"{where}: ruling {i} is parallel to the planes (at {angle:.4f} deg to "
                         "their normal): it meets neither; expected rulings that cross both "
                         "planes (towers)")  # fmt: skip
    z = np.array([0.0, planes.distance])
    s = (z[None, :] - p[:, 2:3]) / lz[:, None]  # (N, 2) line parameters
    local = p[:, None, :] + s[..., None] * l[:, None, :]
    local[..., 2] = z  # exactly on the planes
    return local @ R.T + t


def fit_planes(lines: Lines, distance: float) -> Planes:
    """Planes for rulings that came without any.

    Z along the mean ruling direction (signs aligned with the first ruling), x along the
    largest spread of the rulings in the planes, the two planes ``distance`` apart and centred
    on the rulings' points nearest their centroid, the origin placed so that every end has ``x,
    y >= 0`` (machine coordinates of a foam cutter start at zero)."""
    d = lines.direction
    d = d * np.where(d @ d[0] < 0, -1.0, 1.0)[:, None]
    z = d.mean(axis=0)
    z /= np.linalg.norm(z)
    foot0 = lines.point
    c = foot0.mean(axis=0)
    foot = foot0 + ((c - foot0) * d).sum(axis=1, keepdims=True) * d
    spread = foot - foot.mean(axis=0)
    spread -= (spread @ z)[:, None] * z
    _, _, vt = np.linalg.svd(spread, full_matrices=False) if len(lines) > 1 else (0, 0, np.eye(3))
    x = vt[0] - (vt[0] @ z) * z
    if np.linalg.norm(x) < 1e-9:
        x = np.cross(z, [1.0, 0.0, 0.0] if abs(z[0]) < 0.9 else [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    T = np.eye(4)
    T[:3, :3] = np.stack([x, y, z], axis=1)
    T[:3, 3] = foot.mean(axis=0) - 0.5 * distance * z
    ends = plane_ends(lines, Planes(T, distance), "fitting planes")
    local = (ends.reshape(-1, 3) - T[:3, 3]) @ T[:3, :3]
    T[:3, 3] += T[:3, :3] @ np.r_[local[:, :2].min(axis=0), 0.0]
    return Planes(T, distance)
