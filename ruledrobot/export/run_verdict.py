"""A run's verdict from what the robot did: the recording measured by the one model of the
wire against the block (:mod:`ruledrobot.robot.wire.in_stock`, :mod:`~ruledrobot.robot.wire.cut`).

After the motion the runner has the recording (the controller's actual joints) and, per
recorded sample, the plan sample the live deviation match put it at (the child tags
each sample; the samples recorded while the arm settled after a stop are matched here
the same way, nearest in joint space near the last match).  From them:

* the **actual wire**: forward kinematics of the recorded joints with the trajectory's
  own model (:func:`~ruledrobot.robot.motion.trajectory.model_for`: its kinematics, its TCP,
  no base) — the TCP is the wire's midpoint with z along the wire;
* **feed** (``feed_max:NAME``, ``feed_min:NAME``): :func:`~ruledrobot.robot.wire.cut.feed_measures`
  of the actual wire against the trajectory's cut (``meta.cut``), whose feed windows
  (plan samples) are carried over to the recorded samples matched into them; the set
  speed scales with the run's ``speed_scale``; information (the time law's target) for a
  cut whose face error is measured: the face decides, as in the plan's verdict;
* **wire deviation** (``wire_deviation``): where the actual wire is in the block, the
  distance of its chord's two ends from the planned wire (the line) at the matched
  plan sample — the largest distance of a chord point, since the distance of a point
  of one segment from a line is convex along it;
* **skipped samples in the stock** (``skipped_in_stock``): samples a servoj stream
  skipped to keep the plan's schedule (:meth:`~.run_session.Session.keep_schedule`) where
  the planned wire is in the block — information that explains a feed or wire failure,
  not a failure of its own: what the foam suffers is the feed and the wire, measured on
  the recording (a skip the servo smoothed is no defect of the part).  Only where nothing
  physical can be measured (no ``meta.cut``, nothing recorded) do the skips gate the run.
  The skipped samples in all and the longest slip are information;
* **hot dwell** (``hot_dwell``): the longest time the actual wire stayed in the block
  with the heat on (the controller's outputs, recorded with the joints) cutting slower
  than half the slowest set feed (:func:`~ruledrobot.robot.wire.cut.hot_dwell`), at most
  its plan's own (the corner stops) plus 0.1 s: a wire that waits hot in the foam burns
  it — what a stall of the PC did to a streamed cut, and what a forwarded run's controlled
  stop prevents by switching the heat off as it decelerates;
* **face error** (``face_error``, per cut that names the part's face; issue 33): the
  predicted cut face of the actual wire — its chord ends moved by half the kerf the
  model predicts from their recorded speeds and the wire's power — against the part's
  surface (:func:`~ruledrobot.robot.wire.face.face_errors`, the plan's own check) over
  the recorded samples matched onto the face, against the cut's ``tolerance``.  The
  power: the analog output the controller reported times its ``full_scale`` where the
  heat schedules it (:attr:`~ruledrobot.robot.motion.trajectory.Heat.schedules_power`),
  else the plan's ``heat_power`` at the matched sample where the recorded output was on;
  delayed by the heat's ``lag`` (:func:`~ruledrobot.robot.wire.kerf.wire_power`).  A
  stop with the heat on is a burn (inf); a resume's ramp is left out (its mark);
* **motion** (the run completed) and the **joint deviation** (the live monitor's largest).

A trajectory without ``meta.cut`` (files from before the planner wrote it) has no feed
or wire figures: they are information, "not measured", and the skipped samples, placed by
the sidecar's ``in_stock`` ranges, gate the run.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..geometry.ranges import runs_of
from ..robot.motion.trajectory import Trajectory, model_for
from ..robot.verdict import Check, Verdict
from ..robot.wire.cut import (
    DWELL_FRACTION,
    DWELL_SLACK,
    FeedMeasure,
    FeedWindow,
    WireCut,
    feed_measures,
    hot_dwell,
)
from ..robot.wire.face import FaceError, face_errors
from ..robot.wire.in_stock import WireInStock, largest_line_distance, wire_ends
from ..robot.wire.kerf import wire_power
from .heat import motion_power
from .run_plan import inside_mask
from .urscript import plan_wire_tolerance
from .verify_program import carried_faces

__all__ = [
    "DEVIATION_LIMIT",
    "MAX_LATENCY",
    "RESUME_RAMP",
    "RunMeasures",
    "align_recording",
    "measure_run",
    "recording_cut",
]

#: s: the longest ramp from rest to the feed a resume inside the block is allowed (the
#: resume mark: left out of feed_min, and added with the pre-heat to the hot dwell's limit)
RESUME_RAMP = 0.5
#: rad: the largest joint deviation of the arm from the plan a run tolerates (the run
#: stops beyond it; ``run_trajectory``'s and the verdict's default)
DEVIATION_LIMIT = 0.05
#: s: the longest the stream may fall behind its clock, or the controller go silent,
#: before the run stops (``run_trajectory``'s and the verdict's default)
MAX_LATENCY = 0.1


def align_recording(plan_q: np.ndarray, rec_q: np.ndarray, tags: np.ndarray,
                    window: int) -> np.ndarray:  # fmt: skip
    """(R,) the plan sample (row of ``plan_q``) of every recorded sample.

    Its tag where the live match made one (``tags`` >= 0), else the nearest plan sample in
    joint space from a quarter ``window`` behind the last match to ``window`` ahead of it (the
    live match's rule, :meth:`~.run_session.Session.check_deviation`); 0 before any."""
    out = np.asarray(tags, dtype=np.int64).copy()
    last, high = 0, 0
    n = plan_q.shape[0]
    for r in range(out.size):
        if out[r] < 0:
            lo = max(0, high - window // 4)
            hi = min(n, max(lo, last + window) + 1)
            d = np.max(np.abs(plan_q[lo:hi] - rec_q[r]), axis=1)
            out[r] = lo + int(np.flatnonzero(d <= d.min() + 1e-6)[-1])
        last = int(out[r])
        high = max(high, last)
    return out


def _runs_in(index: np.ndarray, start: int, stop: int) -> tuple[tuple[int, int], ...]:
    return runs_of((index >= start) & (index < stop))


def recording_cut(cut: WireCut, plan_index: np.ndarray, speed_scale: float = 1.0) -> WireCut:
    """The trajectory's cut for the recorded samples.

    Each feed window (and its held ranges) carried over to the recorded samples whose plan
    sample ``plan_index`` (R,) lies in it, the set speed times ``speed_scale``; each face
    target's ranges likewise; the material kept."""
    feeds = []
    for w in cut.feeds:
        held = tuple(r for a, b in w.held for r in _runs_in(plan_index, a, b))
        for a, b in _runs_in(plan_index, w.start, w.stop):
            feeds.append(FeedWindow(w.name, a, b, w.speed * speed_scale, w.tolerance, held,
                                    w.wire_tolerance))  # fmt: skip
    return WireCut(cut.stock, cut.wire_length, tuple(feeds), carried_faces(cut.faces, plan_index),
                   cut.material)  # fmt: skip


@dataclass(frozen=True, eq=False)
class RunMeasures:
    """What the robot did to the cut (module doc).

    ``verdict``: the run's checks; ``plan_index`` (R,): the plan sample of each recorded
    sample; ``cut``: the trajectory's cut carried over to the recorded samples (None
    without ``meta.cut``); ``in_stock``: recorded-sample ranges with the actual wire in
    the block; ``feeds``: per cut, on the recording (sample indices are recorded ones);
    ``wire_deviation`` m (NaN when not measured) at plan sample ``wire_deviation_at``;
    ``skipped_in_stock``: skipped samples with the planned wire in the block, as plan
    sample ranges ``skipped_in_stock_ranges``; ``faces``: the face error per cut on the
    recording (sample indices are recorded ones).
    """

    verdict: Verdict
    plan_index: np.ndarray = field(repr=False)
    cut: WireCut | None = field(repr=False)
    in_stock: tuple[tuple[int, int], ...] = ()
    feeds: tuple[FeedMeasure, ...] = ()
    wire_deviation: float = float("nan")
    wire_deviation_at: int = -1
    skipped: int = 0
    skipped_in_stock: int = 0
    skipped_in_stock_ranges: tuple[tuple[int, int], ...] = ()
    max_slip: float = 0.0
    faces: tuple[FaceError, ...] = field(default=(), repr=False)

    def as_dict(self) -> dict[str, Any]:
        """The measures and the verdict, JSON-ready (the recording's sidecar, ``"run"``)."""
        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        idx = self.plan_index
        return {
            "verdict": self.verdict.as_dict(),
            "wire_deviation_m": num(self.wire_deviation),
            "wire_deviation_at_sample": self.wire_deviation_at,
            "feeds": [{"name": f.name, "speed_m_s": f.speed, "tolerance": f.tolerance,
                       "highest_m_s": num(f.highest), "lowest_m_s": num(f.lowest),
                       "highest_at_sample": int(idx[f.at_highest]) if f.at_highest >= 0 else None,
                       "lowest_at_sample": int(idx[f.at_lowest]) if f.at_lowest >= 0 else None,
                       "max_ok": f.max_ok, "min_ok": f.min_ok}
                      for f in self.feeds],
            "skipped_samples": self.skipped,
            "skipped_in_stock": self.skipped_in_stock,
            "skipped_in_stock_ranges": [list(r) for r in self.skipped_in_stock_ranges],
            "max_slip_s": self.max_slip,
            "face_errors": [{"name": f.name, "max_mm": num(1e3 * f.worst), "burn": f.burn,
                             "at_sample": int(idx[f.at]) if f.at >= 0 else None,
                             "tolerance_mm": 1e3 * f.tolerance} for f in self.faces],
            "in_stock_recorded": [list(r) for r in self.in_stock],
            "plan_sample_first_last": [int(idx[0]), int(idx[-1])] if idx.size else None,
        }  # fmt: skip


def _where(traj: Trajectory, ranges: list[tuple[int, int]], most: int = 4) -> str:
    parts = [f"{a}..{b - 1} (t = {traj.t[a]:.3f} s, {traj.phase_at(a)})" for a, b in ranges[:most]]
    more = f" and {len(ranges) - most} more" if len(ranges) > most else ""
    return ", ".join(parts) + more


def _without_resume_ramp(rcut: WireCut, wis: WireInStock) -> tuple[WireCut, int]:
    """``rcut`` with the recorded samples of a resume's ramp left out of the held ranges:
    from the first sample until the wire first cuts at the lower feed bound (at most
    :data:`RESUME_RAMP` s); and the number of samples left out."""
    if not rcut.feeds:
        return rcut, 0
    lo = min(f.speed * (1.0 - f.tolerance) for f in rcut.feeds)
    t = wis.t
    within = t <= t[0] + RESUME_RAMP
    fast = np.flatnonzero(within & (np.nan_to_num(wis.feed, nan=0.0) >= lo))
    ramp = int(fast[0]) if fast.size else int(np.count_nonzero(within))
    feeds = []
    for f in rcut.feeds:
        held = tuple((max(a, ramp), b) for a, b in f.held if b > max(a, ramp))
        feeds.append(FeedWindow(f.name, f.start, f.stop, f.speed, f.tolerance, held,
                                f.wire_tolerance))  # fmt: skip
    faces = tuple(dataclasses.replace(f, ranges=tuple(
        (max(a, ramp), b) for a, b in f.ranges if b > max(a, ramp))) for f in rcut.faces)
    return dataclasses.replace(rcut, feeds=tuple(feeds), faces=faces), ramp


def _face_checks(traj: Trajectory, faces: dict[str, FaceError],
                 idx: np.ndarray) -> list[Check]:  # fmt: skip
    """``face_error`` (``face_error:NAME`` when several cuts) per cut: gating where the
    actual wire cut the face, information where it never did."""
    out = []
    of = len(faces) > 1
    for name, fe in faces.items():
        key, label = (f"face_error:{name}", f" ({name})") if of else ("face_error", "")
        label = "predicted cut face of the actual wire from the part's surface" + label
        if np.isnan(fe.worst):
            out.append(Check.info(key, label, "not measured: the actual wire never cut the "
                                  "part's face"))  # fmt: skip
            continue
        k = int(idx[fe.at])
        where = f"plan sample {k} (t = {traj.t[k]:.3f} s, {traj.phase_at(k)})"
        detail = (f"burn at {where}: the wire stood in the foam with the heat above its "
                  "threshold" if fe.burn else
                  f"{1e3 * fe.worst:.3f} mm at {where}, the predicted kerf there "
                  f"{1e3 * fe.kerf[fe.at, 0]:.3f} / {1e3 * fe.kerf[fe.at, 1]:.3f} mm at the "
                  "wire's start / end side")  # fmt: skip
        out.append(Check.at_most(key, label, 1e3 * fe.worst, 1e3 * fe.tolerance, "mm", detail))
    return out


def _dwell_check(traj: Trajectory, wis: WireInStock, hot: np.ndarray | None,
                 speed_scale: float, idx: np.ndarray,
                 entry_in_block: float | None = None) -> Check:  # fmt: skip
    """``hot_dwell``: the longest time the recorded hot wire stayed in the block cutting
    slower than half the slowest set feed, against its plan's own (corner stops) plus
    :data:`~ruledrobot.robot.wire.cut.DWELL_SLACK`."""
    label = "longest hot dwell of the actual wire in the block"
    cut, heat = traj.meta.cut, traj.meta.heat
    if heat is None or hot is None or cut is None or not cut.feeds:
        why = "the trajectory switches no heat" if heat is None else "heat not recorded"
        return Check.info("hot_dwell", label, f"not measured: {why}")
    speed = min(f.speed for f in cut.feeds) * speed_scale
    plan_wis = traj.wire_in_stock()
    assert plan_wis is not None
    planned = hot_dwell(plan_wis, heat.on(traj.n), speed / speed_scale).seconds / speed_scale
    got = hot_dwell(wis, np.asarray(hot, dtype=bool)[: wis.n], speed)
    where = (f" from plan sample {int(idx[got.start])} (t = {traj.t[int(idx[got.start])]:.3f}"
             f" s, {traj.phase_at(int(idx[got.start]))})" if got.start >= 0 else "")
    limit = planned + DWELL_SLACK
    mark = ""
    if entry_in_block is not None:
        limit += entry_in_block + RESUME_RAMP
        mark = (f"; a resume in the kerf: its pre-heat ({entry_in_block:g} s) and ramp (up to "
                f"{RESUME_RAMP:g} s) allowed: the resume mark")  # fmt: skip
    return Check.at_most("hot_dwell", label, got.seconds, limit, "s",
                         f"{got.seconds:.3f} s with the heat on below "
                         f"{1e3 * DWELL_FRACTION * speed:.1f} mm/s{where}; the plan's own "
                         f"{planned:.3f} s (corner stops){mark}")  # fmt: skip


def measure_run(
    traj: Trajectory,
    rec: Trajectory | None,
    plan_index: np.ndarray,
    *,
    status: str,
    message: str,
    skipped_ranges: list[tuple[int, int]] | tuple[tuple[int, int], ...] = (),
    max_slip: float = 0.0,
    max_latency: float = MAX_LATENCY,
    max_deviation: float = 0.0,
    deviation_limit: float = DEVIATION_LIMIT,
    speed_scale: float = 1.0,
    wire_tolerance: float | None = None,
    hot: np.ndarray | None = None,
    entry_in_block: float | None = None,
    power: np.ndarray | None = None,
) -> RunMeasures:
    """The run's verdict and measures (module doc).

    ``traj``: the plan; ``rec``: the recording (None when nothing was recorded); ``plan_index``
    (R,): the plan sample of each recorded sample (:func:`align_recording` mapped to input
    samples); ``skipped_ranges``: the skipped samples as half-open plan-sample ranges;
    ``wire_tolerance`` (m): the wire deviation's limit, default the plan's
    (:func:`~.urscript.plan_wire_tolerance`: the strictest of its cuts'); ``hot`` (R,): the
    heat on at each recorded sample, as the controller's outputs said (None: not recorded), for
    the hot dwell; ``entry_in_block``: the pre-heat [s] of a run that entered the trajectory
    from rest with the wire in the block (a resume that continues in the kerf), None otherwise
    — its **resume mark** is allowed: the ramp from rest to the feed (at most
    :data:`RESUME_RAMP` s) is left out of ``feed_min`` and the pre-heat added to the hot
    dwell's limit, both said in the checks' details (and the ramp left out of the face
    error); ``power`` (R,): the recorded analog output times its full scale [W/m]
    (:func:`~.heat.heat_power_from_outputs`; None: not recorded), for the face error."""
    wire_tolerance = plan_wire_tolerance(traj, wire_tolerance)
    checks = [
        Check("motion", "the motion ran to the end", status, "completed", "", "==",
              status == "completed", True,
              "" if status == "completed" else f"{status}: {message}"),
        Check.at_most("joint_deviation", "joint deviation actual vs plan (live monitor)",
                      max_deviation, deviation_limit, "rad",
                      f"{max_deviation:.4f} rad from the plan"),
    ]  # fmt: skip
    inside = inside_mask(traj)
    skip = np.zeros(traj.n, dtype=bool)
    for a, b in skipped_ranges:
        skip[int(a):int(b)] = True
    skipped = int(skip.sum())
    bad = skip & inside
    bad_runs = list(runs_of(bad))
    n_bad = int(bad.sum())
    cut = traj.meta.cut
    idx = np.asarray(plan_index, dtype=np.int64)
    measured = cut is not None and rec is not None and rec.n >= 2
    label = "samples skipped with the wire in the block"
    where = (f"the stream fell behind its schedule (up to {1e3 * max_slip:.0f} ms) and skipped "
             f"{n_bad} samples with the wire in the foam: samples {_where(traj, bad_runs)}"
             if n_bad else "")  # fmt: skip
    if measured:  # the feed and the wire on the recording decide: the skips explain them
        checks.append(Check.info("skipped_in_stock", label, n_bad, "", where))
    else:  # nothing physical can be measured: the skips are the only evidence there is
        checks.append(Check.at_most("skipped_in_stock", label, n_bad, 0, "", where))
    checks.append(Check.info("skipped", "samples skipped to keep the schedule (all)", skipped))
    checks.append(Check.info("slip", f"longest slip behind the schedule (stop beyond "
                             f"{1e3 * max_latency:.0f} ms)", 1e3 * max_slip, "ms"))  # fmt: skip
    if cut is None or rec is None or rec.n < 2:
        why = "the trajectory names no cut (meta.cut)" if cut is None else "nothing recorded"
        checks.append(Check.info("wire_deviation", "actual wire from the planned wire in the "
                                 "block", f"not measured: {why}"))  # fmt: skip
        checks.append(Check.info("feed", "feed of the actual wire in the block",
                                 f"not measured: {why}"))  # fmt: skip
        return RunMeasures(Verdict(tuple(checks)), idx, None, skipped=skipped,
                           skipped_in_stock=n_bad, skipped_in_stock_ranges=tuple(bad_runs),
                           max_slip=max_slip)  # fmt: skip
    robot = model_for(traj.meta).with_base(np.eye(4))
    rcut = recording_cut(cut, idx, speed_scale)
    wis = rcut.measure(rec.t, robot.fk(rec.q))
    ramp = 0
    if entry_in_block is not None:  # the resume mark: the ramp from rest to the feed
        rcut, ramp = _without_resume_ramp(rcut, wis)
    # the actual chord's ends from the planned wire (a line) at the matched plan sample
    plan_ends = wire_ends(traj.tcp_poses()[idx], cut.wire_length)
    a, b = plan_ends[:, 0], plan_ends[:, 1]
    dev = largest_line_distance(wis.chord_points(), a, b - a)  # (R,), 0 outside
    if wis.inside.any():
        r = int(np.argmax(dev))
        wdev, wat = float(dev[r]), int(idx[r])
        checks.append(Check.at_most(
            "wire_deviation", "actual wire from the planned wire in the block", 1e3 * wdev,
            1e3 * wire_tolerance, "mm",
            f"{1e3 * wdev:.3f} mm at plan sample {wat} (t = {traj.t[wat]:.3f} s, "
            f"{traj.phase_at(wat)})"))  # fmt: skip
    else:
        wdev, wat = float("nan"), -1
        checks.append(Check.info("wire_deviation", "actual wire from the planned wire in the "
                                 "block", "the actual wire never entered the block"))  # fmt: skip
    checks.append(_dwell_check(traj, wis, hot, speed_scale, idx, entry_in_block))
    if entry_in_block is not None:
        checks.append(Check.info(
            "resume_mark", "a resume in the kerf: the mark it leaves (allowed)",
            float(wis.t[min(ramp, wis.n - 1)] - wis.t[0]), "s",
            f"the run entered at plan sample {int(idx[0])} from rest with the wire in the "
            f"block: its ramp to the feed ({ramp} recorded samples, at most {RESUME_RAMP:g} s) "
            f"is left out of feed_min, its pre-heat ({entry_in_block:g} s) and ramp are added "
            "to the hot dwell's limit"))  # fmt: skip
    p = motion_power(traj, idx, power, hot)
    lag = 0.0 if traj.meta.heat is None else traj.meta.heat.lag
    faces = face_errors(wis, None if p is None else wire_power(wis.t, p, lag), rcut.material,
                        rcut.faces)  # fmt: skip
    checks.extend(_face_checks(traj, faces, idx))
    feeds = feed_measures(wis, rcut)
    mark = (f"; a resume in the kerf: its ramp from rest ({ramp} recorded samples, "
            f"{float(wis.t[min(ramp, wis.n - 1)] - wis.t[0]):.3f} s) left out: the resume mark"
            if ramp else "")  # fmt: skip
    of = len(feeds) > 1
    for f in feeds:
        key, name = (f":{f.name}", f" ({f.name})") if of else ("", "")
        scaled = f" at speed scale {speed_scale:g}" if speed_scale != 1.0 else ""
        at_hi = int(idx[f.at_highest]) if f.at_highest >= 0 else -1
        at_lo = int(idx[f.at_lowest]) if f.at_lowest >= 0 else -1
        pair = f.checks(key, (
            f"highest feed of the actual wire in the block{name}{scaled}",
            f"lowest feed of the actual wire in the block{name}{scaled}"), (
            f"{1e3 * f.highest:.2f} mm/s at plan sample {at_hi} against "
            f"{1e3 * f.speed:.2f} mm/s +{100 * f.tolerance:g} %: the wire drags",
            f"{1e3 * f.lowest:.2f} mm/s at plan sample {at_lo} against "
            f"{1e3 * f.speed:.2f} mm/s -{100 * f.tolerance:g} %: a wider kerf "
            f"there{mark}"))  # fmt: skip
        face = faces.get(f.name)
        if face is not None and not np.isnan(face.worst):  # the face decides (as the plan's)
            pair = tuple(dataclasses.replace(c, gating=False) for c in pair)
        checks.extend(pair)
    return RunMeasures(Verdict(tuple(checks)), idx, rcut, wis.runs(), feeds, wdev, wat,
                       skipped, n_bad, tuple(bad_runs), max_slip,
                       tuple(faces.values()))  # fmt: skip
