"""Sharp corners of a compensated path: the wire at the corner point of the offset profile.

Where the path turns sharply (a polygon's corner, kept by the refinement, where the wire
stops: :mod:`..motion.corners`) the surface has two tangent planes at a chord end ``P``
of the corner ruling: the face behind (rulings ``i - 1, i``), unit normal ``a`` into the
waste, and the face ahead (``i, i + 1``), ``b`` (:func:`.kerf.face_normals`, sampled
over the corner point's reach: :func:`face_rulings_at_corners`).  A wire end moved to
``P + d`` lies ``d . a`` from the face behind and ``d . b`` from the face ahead; the
kerf leaves both where they should be when ``d . a = h_a`` and ``d . b = h_b`` (``h``
the half kerfs of the two faces there: the neighbouring rulings' at that end).  In the
plane of ``a`` and ``b`` (normal
to the ruling), with ``c = a . b``::

    d = alpha a + beta b,   alpha = (h_a - c h_b) / (1 - c^2),   beta = (h_b - c h_a) / (1 - c^2)

With ``h_a = h_b = h``: ``d = h (a + b) / (1 + c)``, of length ``h / cos(theta / 2)``
along the bisector (``theta`` the angle between the normals: the path's turn there) --
the corner point of the offset profile, the intersection of the two offset faces, for a
convex corner (the waste outside the angle: the point lies past the corner) and a
concave one (the waste inside: it lies short of it) alike.  The bisector's offset ``h``
falls short by ``h (1 / cos(theta / 2) - 1)`` (0.17 mm at 90 degrees, 0.8 mm kerf).

**Concave corners.** There the two offset faces meet before the corner: a neighbour whose
moved end lies past the corner point along the travel on its face (nearer the corner than
``h tan(theta / 2)``) would carry the wire past it, into the face ahead.  Such ends
(the run of them next to the corner, with any short of it by less than half a step) are
spread evenly along the line from the nearest end short of the point to the point, in
order, so the wire neither overruns nor doubles back nor stands (a convex corner's point
lies ahead of every end on both faces: nothing moves).  Where the path's end or another
corner comes first, the run is left as it is (``face_error`` judges).

**Mitre limit.** A turn near 180 degrees (a thin wedge) puts the point far out: ``|d|``
is held to :data:`MITRE_LIMIT` half kerfs (turns up to 175.4 degrees are exact; a
sharper wedge's tip is rounded, and ``face_error`` judges it).

A chord end is a corner where its two normals differ by more than
:data:`~..motion.corners.CORNER_ANGLE` (the turn at which the wire stops); elsewhere the
normals of a refined surface differ by a fraction of a degree and the offset along the
central normal stands.  Units: m; the frame of the rulings.
"""

from __future__ import annotations

import numpy as np

from ...geometry.checks import FloatArray
from ..motion.corners import CORNER_ANGLE

__all__ = ["MITRE_LIMIT", "corner_ends", "corner_error", "face_rulings_at_corners", "mitre",
           "neighbours"]

#: the largest offset of a corner's wire end from the corner, in half kerfs
#: (``1 / cos(theta / 2)`` reaches 25 at a turn of 175.4 degrees)
MITRE_LIMIT = 25.0


def mitre(a: FloatArray, b: FloatArray, h_a: FloatArray, h_b: FloatArray) -> FloatArray:
    """The offsets from a corner to the offset profile's corner point (module doc).

    ``d`` (..., 3) [m] with ``d . a = h_a`` and ``d . b = h_b`` in the plane of the unit
    normals ``a``, ``b`` (..., 3) (module doc), held to :data:`MITRE_LIMIT` ``max(h_a,
    h_b)``; half kerfs ``h_a``, ``h_b`` (...,) [m]."""
    c = np.einsum("...i,...i->...", a, b)
    s2 = np.maximum(1.0 - c * c, 1e-300)
    alpha, beta = (h_a - c * h_b) / s2, (h_b - c * h_a) / s2
    d = alpha[..., None] * a + beta[..., None] * b
    size = np.linalg.norm(d, axis=-1)
    top = MITRE_LIMIT * np.maximum(h_a, h_b)
    return d * np.where(size > top, top / np.maximum(size, 1e-300), 1.0)[..., None]


def neighbours(M: int, closed: bool) -> tuple[np.ndarray, np.ndarray]:
    """Return the index before and after each ruling.

    (M,), (M,): periodic when ``closed``, else the ruling itself at the ends."""
    i = np.arange(M)
    if closed:
        return np.roll(i, 1), np.roll(i, -1)
    return np.maximum(i - 1, 0), np.minimum(i + 1, M - 1)


def face_rulings_at_corners(
    o: FloatArray, z: FloatArray, te: FloatArray, back: FloatArray, ahead: FloatArray,
    half: FloatArray, closed: bool, hit: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The rulings (M, 2), (M, 2) that sample the faces behind and ahead of each ruling.

    For :func:`.kerf.face_normals`: the neighbours (twice), except at a sharp corner
    (``back``, ``ahead`` (M, 2, 3) the neighbours' face normals at the chord ends ``te``
    (M, 2) [m along ``z``]).  There, on each side, the nearest rulings whose points at the
    corner's chord parameters lie at least ``L / 2`` and ``L`` from the corner's chord ends,
    ``L = h tan(theta / 2)`` (the distance along each face from the corner to the foot of
    the offset corner point; ``h`` the largest half kerf ``half`` (M, 2) [m] there and
    beside it, ``tan`` held to :data:`MITRE_LIMIT`), stopping at another corner
    (included: the face ends there), before a ruling off the stock (``hit`` (M,) False) or
    at the path's end.  Why: a refined path's rulings lie within a fraction of a
    micrometre of its surface, and next to a corner they are micrometres apart, so their
    differences turn by degrees where the faces do not, while the corner point moves by
    ``h sin(theta / 2) / cos^2(theta / 2)`` per radian of ``theta`` (12 mm at 160 degrees,
    0.4 mm half kerf: a trailing edge's point 0.36 mm off).  Sampled over ``L`` the
    rulings' error ``e`` tilts the face by about ``8 e / L`` and the corner point's faces
    by about ``8 e``.  Frames' origins ``o``, directions ``z`` (M, 3)."""
    M = len(o)
    before, after = (np.repeat(j[:, None], 2, axis=1) for j in neighbours(M, closed))
    corner = _is_corner(back, ahead) & hit[:, None]
    rows = np.flatnonzero(corner.any(axis=1))
    if not rows.size:
        return before, after
    c = np.clip(np.einsum("...i,...i->...", back, ahead), -1.0 + 1e-12, 1.0)
    i0, i1 = before[:, 0], after[:, 0]
    h = np.fmax(np.fmax(half[i0], half[i1]), half)
    reach = h * np.minimum(np.sqrt((1.0 - c) / (1.0 + c)), MITRE_LIMIT)  # (M, 2)
    wall = corner.any(axis=1)
    for i in rows:  # a few corners
        P = o[i] + te[i, :, None] * z[i]  # (2, 3)
        for step, side in ((-1, before), (1, after)):
            j = _run(i, step, M, closed, ~hit, wall)  # another corner ends the face
            if not j.size:
                continue
            Q = o[j, None, :] + te[i][None, :, None] * z[j, None, :]  # (J, 2, 3)
            s = np.linalg.norm(Q - P, axis=-1)
            for col, share in ((0, 0.5), (1, 1.0)):
                far = (s >= share * reach[i]).all(axis=1)
                side[i, col] = j[int(np.argmax(far))] if far.any() else j[-1]
    return before, after


def _is_corner(back: FloatArray, ahead: FloatArray) -> np.ndarray:
    """Where the normals behind and ahead (..., 3) differ by more than the corner angle."""
    ok = (np.linalg.norm(back, axis=-1) > 0.5) & (np.linalg.norm(ahead, axis=-1) > 0.5)
    return ok & (np.einsum("...i,...i->...", back, ahead) < np.cos(CORNER_ANGLE))


def corner_ends(
    target: FloatArray, moved: FloatArray, z: FloatArray, back: FloatArray,
    ahead: FloatArray, half: FloatArray, sign: float, closed: bool, hit: np.ndarray,
) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """The moved chord ends with sharp corners at the offset profile's corner points.

    (Module doc.)

    ``target`` (M, 2, 3) [m] the target rulings' chord ends; ``moved`` (M, 2, 3) the ends
    moved off the corners' way (along the central normals); ``z`` (M, 3) the rulings'
    directions; ``back``, ``ahead`` (M, 2, 3) the unit normals of the faces behind and
    ahead at the ends, into the waste (``sign`` times the sweep's ``z x tangent``);
    ``half`` (M, 2) [m] the half kerfs at the ends; ``hit`` (M,) the rulings crossing the
    stock.  Returns the ends (M, 2, 3), the rulings whose ends changed (M,) and the
    corner ends (M, 2)."""
    M = target.shape[0]
    out = np.array(moved, dtype=np.float64)
    before, after = neighbours(M, closed)
    corner = _is_corner(back, ahead) & hit[:, None] & hit[before, None] & hit[after, None]
    changed = corner.any(axis=1)
    if not changed.any():
        return out, changed, corner
    h_a = np.where(np.isfinite(half[before]), half[before], half)
    h_b = np.where(np.isfinite(half[after]), half[after], half)
    ii, ee = np.nonzero(corner)
    X = target[ii, ee] + mitre(back[ii, ee], ahead[ii, ee], h_a[ii, ee], h_b[ii, ee])
    # the travel on each face, normal to the ruling: (sign n) x z points along the sweep
    travel_in = sign * np.cross(back[ii, ee], z[ii])
    travel_out = sign * np.cross(ahead[ii, ee], z[ii])
    base = out.copy()
    reach = np.linalg.norm(X - target[ii, ee], axis=1)
    for k in range(ii.size):  # a few corners: mend the (short) stretches beside them
        i, e = int(ii[k]), int(ee[k])
        out[i, e] = X[k]
        for step, T in ((-1, -travel_in[k]), (1, travel_out[k])):
            rows = _beside(target[:, e], i, step, closed, corner[:, e] | ~hit, reach[k])
            if rows.size:
                mended = _monotone(base[rows, e], target[rows, e], X[k], T, target[i, e])
                changed[rows] |= (mended != base[rows, e]).any(axis=1)
                out[rows, e] = mended
    return out, changed, corner


def _run(i: int, step: int, M: int, closed: bool, stop: np.ndarray,
         wall: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """The rulings next to ``i`` on one side (``step`` -1 behind, +1 ahead), nearest first,
    up to the first where ``stop`` (M,) holds (or back at ``i``, or the path's end), or to
    the first where ``wall`` (M,) holds, included."""
    j = i + step * np.arange(1, M)
    j = np.mod(j, M) if closed else j[(j >= 0) & (j < M)]
    bad = stop[j] | (j == i)
    j = j[: int(np.argmax(bad)) if bad.any() else j.size]
    at_wall = np.zeros(j.size, dtype=bool) if wall is None else wall[j]
    return j[: int(np.argmax(at_wall)) + 1] if at_wall.any() else j


def _beside(target: FloatArray, i: int, step: int, closed: bool, stop: np.ndarray,
            reach: float) -> np.ndarray:  # fmt: skip
    """The rulings next to corner ``i`` on one side (``step`` -1 behind, +1 ahead), nearest
    first, up to the first whose target end lies more than twice the corner point's
    distance ``reach`` [m] from the corner's and three more (or to another corner, a
    ruling off the stock or the path's end)."""
    j = _run(i, step, target.shape[0], closed, stop)
    far = np.linalg.norm(target[j] - target[i], axis=1) > 2.0 * reach
    return j[: int(np.argmax(far)) + 4 if far.any() else j.size]


def _monotone(ends: FloatArray, target: FloatArray, X: FloatArray, T: FloatArray,
              corner: FloatArray) -> FloatArray:  # fmt: skip
    """The moved ends ``ends`` (K, 3) of the rulings beside a corner, nearest first, mended
    so that they go away from the corner point ``X`` (3,) along ``T`` (3,) in order: an end
    not ahead of every nearer one (and ``X``) by half its target step, or not behind
    every farther one, is moved onto the line between the kept ends on either side of
    it, spaced by index (``target`` (K, 3) their target ends, ``corner`` the corner's)."""
    s = (ends - X) @ T
    prev = np.vstack([corner[None, :], target[:-1]])
    half_gap = 0.5 * np.linalg.norm(target - prev, axis=1)
    before = np.maximum.accumulate(np.r_[0.0, s[:-1]])
    after = np.minimum.accumulate(np.r_[s[1:], np.inf][::-1])[::-1]
    good = (s > before + half_gap) & (s < after)
    if good.all() or not good.any():
        return ends
    pos = np.flatnonzero(good) + 1.0  # the kept ends' places, X at place 0
    anchors = np.vstack([X[None, :], ends[good]])
    place = np.arange(1, len(ends) + 1, dtype=np.float64)
    out = np.array(ends)
    fill = ~good & (place < pos[-1])  # past the last kept end: left as they are
    knots = np.r_[0.0, pos]
    for c in range(3):
        out[fill, c] = np.interp(place[fill], knots, anchors[:, c])
    return out


def corner_error(
    wire: FloatArray, target: FloatArray, back: FloatArray, ahead: FloatArray,
    half: FloatArray, closed: bool,
) -> FloatArray:
    """The kept surface's largest error (M,) [m] at corner rulings.

    The wire's points
    ``wire`` (M, K, 3) against the two faces' tangent planes at the target points
    ``target`` (M, K, 3), normals ``back``, ``ahead`` (M, K, 3) into the waste, each
    half a kerf off: the neighbours' ``half`` (M, K) [m] on its side."""
    before, after = neighbours(target.shape[0], closed)
    d = wire - target
    e_in = np.abs(np.einsum("mki,mki->mk", d, back) - half[before])
    e_out = np.abs(np.einsum("mki,mki->mk", d, ahead) - half[after])
    return np.maximum(e_in, e_out).max(axis=1)
