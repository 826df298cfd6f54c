"""Where a run enters the trajectory and how it gets there (pure computation, no I/O).

:func:`plan_entry` decides, from the arm's actual joints and the requested
start sample ``N`` (``--resume N``; 0 for a fresh run), one of:

* ``"continue"`` — the arm is at (within ``tolerance`` of) the planned pose of
  a sample near ``N`` (within ``window`` seconds of it): the run goes on from
  that sample (a moveJ of at most ``tolerance`` first, so that the first servo
  target is where the arm is);
* ``"replay"`` — the arm is elsewhere and ``N`` is inside the stock: never a
  moveJ across the stock; the arm moves to the *entry* of that in-stock run
  (the start of the lead-in before it, else the last sample before the wire
  entered the stock) and replays the kerf's own path from there through ``N``
  and on: the wire passes through the kerf it already cut;
* ``"approach"`` — the arm is elsewhere and ``N`` is outside the stock: a
  moveJ to ``N`` (the approach move of a fresh run).

It refuses (a failing check) when the arm is at the planned pose of an
in-stock sample that is not near ``N``: the wire is in the stock there, and a
moveJ would drag it through uncut material; and when the in-stock run of ``N``
has no sample outside the block before it to enter from.

Whether the wire is in the block at a sample comes from the one model of the wire
against the block (:func:`inside_mask`: :meth:`Trajectory.wire_in_stock` when the
metadata names its cut, else the sidecar's ``in_stock``).
"""

from __future__ import annotations

import math
import os
import re
import weakref
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..robot.motion.trajectory import Trajectory
from ..robot.verdict import Check
from .settings import APPROACH_ACCELERATION, APPROACH_SPEED

__all__ = [
    "Entry",
    "StopPlace",
    "inside_mask",
    "moveJ_time",
    "plan_entry",
    "recording_path_for",
    "resample",
    "stop_place",
]


def moveJ_time(distance: float, speed: float, acceleration: float) -> float:
    """Duration of a trapezoidal (or triangular) move of the leading joint [s]."""
    d = abs(float(distance))
    if d <= 0.0:
        return 0.0
    if d >= speed * speed / acceleration:
        return d / speed + speed / acceleration
    return 2.0 * math.sqrt(d / acceleration)


@dataclass(frozen=True)
class Entry:
    """How the run enters the trajectory.

    ``kind``: ``"continue"``, ``"replay"`` or ``"approach"``; ``requested``: the
    sample asked for; ``sample``: the first sample streamed; ``distance``: the
    joint distance of the leading joint from the actual pose to ``sample``
    [rad], ``joint``: that joint (1-based); ``approach_time``: the moveJ's
    estimated duration [s]; ``replay_time``: the time of the trajectory from
    ``sample`` to ``requested`` (the kerf replayed) [s]; ``note``: in words;
    ``check``: the pre-motion check of the entry (fails when refused).
    """

    kind: str
    requested: int
    sample: int
    distance: float
    joint: int
    approach_time: float
    replay_time: float
    note: str
    check: Check

    @property
    def ok(self) -> bool:
        """Whether the entry's check holds (the entry is not refused)."""
        return self.check.ok


_INSIDE: weakref.WeakKeyDictionary[Trajectory, np.ndarray] = weakref.WeakKeyDictionary()


def inside_mask(traj: Trajectory) -> np.ndarray:
    """(M,) bool, read-only.

    The wire is in the block at sample k — from the one model of the wire against the block
    (:meth:`Trajectory.wire_in_stock`) when the metadata names its cut (``meta.cut``), else
    from the sidecar's ``in_stock`` ranges. Computed once per trajectory (a trajectory is
    immutable; ~1 s for a long cut)."""
    mask = _INSIDE.get(traj)
    if mask is None:
        wis = traj.wire_in_stock()
        mask = traj.inside_stock() if wis is None else np.array(wis.inside, dtype=bool)
        mask.flags.writeable = False
        _INSIDE[traj] = mask
    return mask


def _in_stock_run(inside: np.ndarray, k: int) -> tuple[int, int] | None:
    if not inside[k]:
        return None
    out = np.flatnonzero(~inside)
    before, after = out[out < k], out[out > k]
    return (int(before[-1]) + 1 if before.size else 0,
            int(after[0]) if after.size else inside.size)  # fmt: skip


def entry_sample(traj: Trajectory, a: int, inside: np.ndarray | None = None) -> int:
    """The sample a replay of the in-stock run starting at ``a`` starts from.

    The start of the latest lead-in phase that begins before ``a`` with the wire outside the
    block from there to ``a`` (the model's and the phases' edges need not coincide), else ``a -
    1`` (the last sample before the wire entered the block), at least 0. ``inside``:
    :func:`inside_mask` of ``traj`` (computed when not given)."""
    inside = inside_mask(traj) if inside is None else inside
    best = None
    for p in traj.meta.phases:
        if p.name == "lead_in" and p.start < a and not inside[p.start:a].any():
            best = p.start if best is None else max(best, p.start)
    return best if best is not None else max(a - 1, 0)


def _nearest_stretch(idx: np.ndarray, dist: np.ndarray, requested: int) -> int:
    """Of the sorted sample indices ``idx``, cut into runs of consecutive samples, the run
    nearest ``requested`` (in samples); in it, the sample of least ``dist``."""
    breaks = np.flatnonzero(np.diff(idx) > 1) + 1
    runs = np.split(idx, breaks)
    gap = [0 if r[0] <= requested <= r[-1] else min(abs(r[0] - requested),
                                                    abs(r[-1] - requested)) for r in runs]
    run = runs[int(np.argmin(gap))]
    return int(run[np.argmin(dist[run])])


def plan_entry(
    traj: Trajectory,
    q_actual: np.ndarray,
    requested: int,
    *,
    tolerance: float = 0.005,
    window: float = 1.0,
    approach_speed: float = APPROACH_SPEED,
    approach_acceleration: float = APPROACH_ACCELERATION,
) -> Entry:
    """Decide how to enter ``traj`` at sample ``requested`` from the pose ``q_actual``."""
    q = np.asarray(traj.q, dtype=float)
    qa = np.asarray(q_actual, dtype=float)
    n = q.shape[0]
    dist = np.max(np.abs(q - qa), axis=1)  # joint distance to every sample
    t = np.asarray(traj.t, dtype=float)
    lo = int(np.searchsorted(t, t[requested] - window, side="left"))
    hi = int(np.searchsorted(t, t[requested] + window, side="right"))
    hi = min(hi, n - 1)  # the last sample cannot start a run
    near = lo + int(np.argmin(dist[lo:hi])) if hi > lo else requested
    close = lo + np.flatnonzero(dist[lo:hi] <= tolerance)
    if close.size:  # the nearest sample of the stretch of samples the arm is at that lies
        # nearest the requested one: a path that comes back through its own poses (there
        # and back, a pass turning round in its kerf) has a later stretch as near, and
        # continuing there would skip everything in between (found: a stop at 207 of a
        # there-and-back resumed at 393)
        near = int(_nearest_stretch(close, dist, requested))

    def move_to(k: int) -> tuple[float, int, float]:
        d = np.abs(q[k] - qa)
        j = int(np.argmax(d))
        return float(d[j]), j + 1, moveJ_time(float(d[j]), approach_speed, approach_acceleration)

    def entry(kind: str, k: int, note: str, check: Check) -> Entry:
        d, j, tm = move_to(k)
        replay = float(t[requested] - t[k]) if k < requested else 0.0
        return Entry(kind, requested, k, d, j, tm, replay, note, check)

    name = "entry"
    label = "entry into the trajectory"
    safe = "no move across the stock"
    if hi > lo and dist[near] <= tolerance:
        note = (
            f"the arm is at sample {near} (within {dist[near]:.4f} rad of its planned pose): "
            f"continue from there"
        )
        if near != requested:
            note += f" (requested {requested})"
        value = f"continue at {near}"
        return entry("continue", near, note, Check(name, label, value, safe, "", "", True))
    inside = inside_mask(traj)
    if inside.any():
        at = np.flatnonzero(inside & (dist <= tolerance))
        if at.size:
            m = int(_nearest_stretch(at, dist, requested))  # as above
            detail = (
                f"the arm is at the planned pose of sample {m}, where the wire is inside "
                f"the stock, not near sample {requested}: a move from there would drag the "
                f"wire through uncut stock; resume with --resume {m}"
            )
            chk = Check(
                name,
                label,
                f"wire in the stock at {m}",
                safe,
                "",
                "",
                False,
                True,
                detail,
            )
            return entry("refused", m, detail, chk)
    run = _in_stock_run(inside, requested)
    if run is not None and run[0] == 0:
        detail = (
            f"the wire is in the block at sample {requested} and has been since the first "
            f"sample (in-stock run 0..{run[1] - 1}): there is no sample outside the block to "
            "re-enter the kerf from, and a move to it would drag the wire through uncut "
            "stock; move the arm to the first sample by hand and run again"
        )
        chk = Check(name, label, f"wire in the stock at {requested}", safe, "", "", False,
                    True, detail)  # fmt: skip
        return entry("refused", requested, detail, chk)
    if run is not None:
        k0 = entry_sample(traj, run[0], inside)
        note = (
            f"the arm is not at the cut and sample {requested} is inside the stock (in-stock "
            f"run {run[0]}..{run[1] - 1}): move to sample {k0} before the wire enters the "
            f"stock and replay the kerf's own path from there through {requested} and on"
        )
        value = f"replay from {k0}"
        return entry("replay", k0, note, Check(name, label, value, safe, "", "", True))
    if requested == 0:
        note = "moveJ to the first sample (the approach move)"
    else:
        note = (
            f"the arm is not near sample {requested}, which is outside the stock: moveJ to "
            "it and continue"
        )
    if traj.meta.cut is None and not traj.meta.in_stock:
        note += " (the trajectory names no in-stock samples)"
    value = f"approach {requested}"
    return entry("approach", requested, note, Check(name, label, value, safe, "", "", True))


@dataclass(frozen=True)
class StopPlace:
    """Where a run stopped: input sample, its time, its phase, the wire in the stock."""

    sample: int
    time: float
    phase: str
    in_stock: bool

    def describe(self) -> str:
        """The place in words: sample, time [s], phase and whether the wire is in the stock."""
        where = "inside the stock" if self.in_stock else "outside the stock"
        return f"sample {self.sample} (t = {self.time:.3f} s), phase {self.phase}, wire {where}"


def stop_place(traj: Trajectory, k: int, inside: np.ndarray | None = None) -> StopPlace:
    """Where sample ``k`` is.

    ``inside``: :func:`inside_mask` of ``traj`` (computed when not given)."""
    k = int(min(max(k, 0), traj.n - 1))
    inside = inside_mask(traj) if inside is None else inside
    return StopPlace(k, float(traj.t[k]), traj.phase_at(k), bool(inside[k]))


_RUN_RE = re.compile(r"\.run-(\d{3,})$")


def recording_path_for(path: str | os.PathLike[str]) -> Path:
    """``cut.csv`` -> the first free ``cut.run-001.csv``, ``cut.run-002.csv``, ...

    beside it (free: neither the CSV nor its sidecar exists).  The CSV is created empty at once
    (exclusively), so two runs never choose the same name."""
    p = Path(path)
    stem = _RUN_RE.sub("", p.stem)
    k = 1
    while True:
        cand = p.with_name(f"{stem}.run-{k:03d}.csv")
        if not cand.with_suffix(".json").exists():
            try:
                fd = os.open(cand, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pass
            else:
                os.close(fd)
                return cand
        k += 1


def resample(t: np.ndarray, q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Samples at a uniform period ``dt`` from ``t[0]`` (linear interpolation), end included."""
    T = float(t[-1] - t[0])
    n = math.floor(T / dt + 1e-9)
    tg = t[0] + dt * np.arange(n + 1)
    if tg[-1] < t[-1] - 1e-12:
        tg = np.append(tg, t[0] + dt * (n + 1))
    qg = np.empty((tg.size, q.shape[1]))
    for j in range(q.shape[1]):
        qg[:, j] = np.interp(tg, t, q[:, j])
    return tg, qg
