"""Decimation of a sampled TCP path into linear-move waypoints (Douglas-Peucker in SE(3)).

The path is cut into straight TCP segments such that every dropped sample
lies within ``tolerance`` metres of its segment and within
``angle_tolerance`` radians of the orientation interpolated along it (slerp
at the sample's arc-length fraction).  The first and last samples are always
kept.  Used for ``movel``/``movep`` programs and for the runner's path mode.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from ..geometry.ranges import runs_of
from ..geometry.rotations import angle_between, rotation_angle
from ..geometry.se3 import pose_from_rotvec, rotvec_from_matrix
from .settings import PATH_BLEND

__all__ = ["PathStep", "decimate_points", "decimate_tcp_path", "path_steps"]


def _rot(rv: np.ndarray) -> np.ndarray:
    return pose_from_rotvec(rv)[..., :3, :3]


def _segment_errors(p: np.ndarray, R: np.ndarray, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """Position and angle errors of samples i+1..j-1 against the segment i -> j."""
    a, b = p[i], p[j]
    inner = p[i + 1 : j]
    ab = b - a
    L2 = float(ab @ ab)
    if L2 > 0.0:
        s = np.clip(((inner - a) @ ab) / L2, 0.0, 1.0)
    else:
        s = np.zeros(len(inner))
    proj = a + s[:, None] * ab
    pos = np.linalg.norm(inner - proj, axis=1)
    # orientation: slerp between the ends at the fraction s (uniform in arc when L = 0)
    if L2 == 0.0:
        s = np.arange(1, j - i) / (j - i)
    Ri, Rj = R[i], R[j]
    rel = rotvec_from_matrix(Ri.T @ Rj)
    interp = Ri @ _rot(s[:, None] * rel[None, :])  # (n, 3, 3)
    err = np.einsum("nji,njk->nik", interp, R[i + 1 : j])  # interp^T R_k
    ang = rotation_angle(err)
    return pos, ang


def decimate_tcp_path(
    tcp: np.ndarray,
    tolerance: float = 0.0005,
    angle_tolerance: float = 0.005,
    max_segment: int = 0,
) -> np.ndarray:
    """Indices of the samples to keep from TCP UR vectors (M, 6).

    ``tolerance`` [m] and ``angle_tolerance`` [rad] bound the deviation of the
    dropped samples from the straight segments; ``max_segment > 0`` also caps
    the number of samples a segment may span.  Returns sorted indices,
    first and last included.
    """
    tcp = np.asarray(tcp, dtype=float)
    if tcp.ndim != 2 or tcp.shape[1] != 6 or tcp.shape[0] < 1:
        raise ValueError(f"tcp: expected shape (M, 6) UR pose vectors, got {tcp.shape}")
    if not tolerance > 0 or not angle_tolerance > 0:
        raise ValueError("tolerance and angle_tolerance: must be positive")
    p = tcp[:, :3]
    R = _rot(tcp[:, 3:]) if tcp.shape[0] > 2 else None

    def split(i: int, j: int) -> int | None:
        pos, ang = _segment_errors(p, R, i, j)
        score = np.maximum(pos / tolerance, ang / angle_tolerance)
        k = int(np.argmax(score))
        if score[k] > 1.0:
            return i + 1 + k
        return (i + j) // 2 if max_segment > 0 and j - i > max_segment else None

    return _kept_samples(tcp.shape[0], split)


def _kept_samples(M: int, split: Callable[[int, int], int | None]) -> np.ndarray:
    """Ramer-Douglas-Peucker on sample indices: from the segment (0, M - 1), split every
    segment of 3 or more samples where ``split(i, j)`` says (None: keep it whole).
    Returns the sorted indices kept, first and last included."""
    if M <= 2:
        return np.arange(M)
    keep = np.zeros(M, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, M - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = split(i, j)
        if m is not None:
            keep[m] = True
            stack += [(i, m), (m, j)]
    return np.flatnonzero(keep)


# ---------------------------------------------------------------- path programs


#: m/s, rad/s: a plan sample interval slower than both is the TCP standing still
STILL_SPEED = 1e-5
STILL_TURN = 1e-4


@dataclass(frozen=True)
class PathStep:
    """One step of a path program, from plan sample ``start`` to plan sample ``stop``.

    ``kind``: ``"line"`` (a linear move to the TCP of sample ``stop``; ``v`` m/s of TCP
    path, rad/s of TCP rotation for a pure reorientation, as URScript's ``movel`` /
    ``movep``), ``"joint"`` (a ``movej`` to the joints of sample ``stop``; ``v`` rad/s of
    the leading joint) or ``"dwell"`` (the TCP still: a ``sleep`` of ``seconds``).
    ``seconds``: the plan's time for the step; ``r``: blend radius (m); ``heat``: the
    wire is hot during it (the program switches before the step when it changes).
    """

    kind: str
    start: int
    stop: int
    seconds: float
    v: float = 0.0
    r: float = 0.0
    heat: bool = False


def decimate_points(x: np.ndarray, tolerance: float) -> np.ndarray:
    """Return the indices of the points (M, D) to keep within ``tolerance`` of the kept path.

    Every dropped point lies within ``tolerance`` (Euclidean) of the straight segment
    between its kept neighbours, at its own fraction of the segment's samples' index (as a
    joint move passes them).
    """
    x = np.asarray(x, dtype=float)

    def split(i: int, j: int) -> int | None:
        a, b = x[i], x[j]
        ab = b - a
        L2 = float(ab @ ab)
        inner = x[i + 1 : j]
        s = np.clip(((inner - a) @ ab) / L2, 0.0, 1.0) if L2 > 0 else np.zeros(j - i - 1)
        err = np.linalg.norm(inner - (a + s[:, None] * ab), axis=1)
        k = int(np.argmax(err))
        return i + 1 + k if err[k] > tolerance else None

    return _kept_samples(x.shape[0], split)


def _speed_splits(speed: np.ndarray, i: int, j: int, change: float, floor: float) -> list[int]:
    """Samples strictly between ``i`` and ``j`` where a move must end so that the plan's
    speed over each move (``speed[k]`` of the interval k -> k+1) varies by at most
    ``change`` of its largest value, and at most ``floor``."""
    cuts = []
    lo = hi = float(speed[i])
    for k in range(i + 1, j):
        s = float(speed[k])
        nlo, nhi = min(lo, s), max(hi, s)
        if nhi - nlo > max(change * nhi, floor):
            cuts.append(k)
            lo = hi = s
        else:
            lo, hi = nlo, nhi
    return cuts


def path_steps(
    t: np.ndarray,
    tcp: np.ndarray,
    q: np.ndarray | None = None,
    *,
    boundaries: np.ndarray | tuple[int, ...] = (),
    heat: np.ndarray | None = None,
    strict: np.ndarray | None = None,
    tolerance: float = 0.0005,
    angle_tolerance: float = 0.005,
    joint_tolerance: float = 0.001,
    speed_change: float = 0.02,
    free_speed_change: float = 0.10,
    speed_floor: float = 1e-4,
    blend: float = PATH_BLEND,
    min_dwell: float = 0.05,
) -> tuple[PathStep, ...]:
    """The steps of a path program playing the plan's samples.

    TCP ``tcp`` (M, 6), joints ``q`` (M, 6) at times ``t`` (M,) — as planned: nothing of the
    plan's motion is merged.

    * every sample of ``boundaries`` (phase starts and ends, the wire entering and leaving
      the stock) and every heat switch (``heat`` (M,) bool) is a waypoint, so no move
      spans two phases;
    * a run of samples with the TCP still lasting ``min_dwell`` s or more is a dwell
      (``sleep``), never a move; a shorter rest ends a move without a blend;
    * where ``strict`` (M,) holds (the cutting phases: the wire hot, near or in the
      stock; default everywhere) the moves are linear: the TCP path decimated to
      ``tolerance`` / ``angle_tolerance`` (:func:`decimate_tcp_path`) and split again
      wherever the plan's TCP speed changes by more than ``speed_change`` (2 %) of the
      faster speed — and by more than 2 % of the piece's top speed, at least
      ``speed_floor`` m/s, so that a ramp from rest is some 50 moves, not thousands;
    * elsewhere (free air: approach, transits, retract; with ``q`` given) the moves are
      joint moves through the plan's joints decimated to ``joint_tolerance`` rad
      (:func:`decimate_points`), split where the leading joint's speed changes by more
      than ``free_speed_change``: a Cartesian line between two poses of a transit can pass
      a singularity (the part demo's second transit passes within 1e-4 of one);
    * each move's ``v`` is the plan's mean speed over it, so it takes the plan's time;
    * blends of ``blend`` m, clipped to 45 % of either neighbouring move; none into a
      dwell, a heat switch, a rest of the plan, a change between linear and joint moves,
      or the end.
    """
    t = np.asarray(t, dtype=float)
    tcp = np.asarray(tcp, dtype=float)
    M = t.size
    if tcp.shape != (M, 6) or M < 2:
        raise ValueError(f"tcp: expected ({M}, 6) UR pose vectors of at least 2 samples, "
                         f"got {tcp.shape}")  # fmt: skip
    on = np.zeros(M, dtype=bool) if heat is None else np.asarray(heat, dtype=bool)
    tight = np.ones(M, dtype=bool) if strict is None or q is None else np.asarray(strict, bool)
    p = tcp[:, :3]
    R = _rot(tcp[:, 3:])
    dt = np.diff(t)
    seg_len = np.linalg.norm(np.diff(p, axis=0), axis=1)
    speed = seg_len / dt
    turn = angle_between(R[:-1], R[1:])
    still = (speed < STILL_SPEED) & (turn / dt < STILL_TURN)
    jspeed = np.zeros(M - 1) if q is None else np.abs(np.diff(q, axis=0)).max(axis=1) / dt
    dwells = {a: b for a, b in runs_of(still) if t[b] - t[a] >= min_dwell}
    edges = np.flatnonzero(np.diff(on.astype(np.int8))) + 1
    tight_edges = np.flatnonzero(np.diff(tight.astype(np.int8))) + 1
    cuts = {0, M - 1, *(int(k) for k in boundaries if 0 < k < M - 1), *edges.tolist(),
            *tight_edges.tolist()}  # fmt: skip
    for a, b in dwells.items():
        cuts.update((a, b))
    keep: set[int] = set(cuts)
    for i, j in pairwise(sorted(cuts)):
        if dwells.get(i) == j:
            continue
        if tight[i]:
            geo = decimate_tcp_path(tcp[i : j + 1], tolerance, angle_tolerance) + i
            sp, change = speed, speed_change
        else:
            geo = decimate_points(q[i : j + 1], joint_tolerance) + i  # type: ignore[index]
            sp, change = jspeed, free_speed_change
        keep.update(int(k) for k in geo)
        floor = max(speed_floor if tight[i] else 0.0, change * float(sp[i:j].max()))
        for a, b in pairwise(geo):
            keep.update(_speed_splits(sp, int(a), int(b), change, floor))
    arc = np.r_[0.0, np.cumsum(seg_len)]
    rest = np.r_[True, still] & np.r_[still, True]  # the plan is at rest at sample k
    steps: list[PathStep] = []
    for i, j in pairwise(sorted(keep)):
        secs = float(t[j] - t[i])
        hot = bool(on[i])
        L = float(arc[j] - arc[i])
        rot = float(angle_between(R[i], R[j]))
        if dwells.get(i) == j or (L < 1e-6 and rot < 1e-6):
            steps.append(PathStep("dwell", i, j, secs, heat=hot))
        elif tight[i]:
            steps.append(PathStep("line", i, j, secs, v=(L if L >= 1e-6 else rot) / secs,
                                  heat=hot))  # fmt: skip
        else:
            dq = float(np.abs(q[j] - q[i]).max())  # type: ignore[index]
            steps.append(PathStep("joint", i, j, secs, v=dq / secs, heat=hot))
    out: list[PathStep] = []
    for n, s in enumerate(steps):
        nxt = steps[n + 1] if n + 1 < len(steps) else None
        r = 0.0
        if (nxt is not None and s.kind != "dwell" and nxt.kind == s.kind and nxt.heat == s.heat
                and not rest[s.stop]):  # fmt: skip
            la = float(arc[s.stop] - arc[s.start])
            lb = float(arc[nxt.stop] - arc[nxt.start])
            r = max(0.0, min(blend, 0.45 * la, 0.45 * lb))
        out.append(dataclasses.replace(s, r=r))
    return tuple(out)
