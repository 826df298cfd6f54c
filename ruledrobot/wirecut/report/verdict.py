"""The plan's verdict: every measurement of a planned cut as a :class:`Check`.

Gating (the plan is feasible only when all hold; ``docs/verdict.md``):

* ``reach`` — every ruling of the path has a continuous joint solution clear of
  the stock and table (the redundancy search);
* ``verified`` — the trajectory was played in MuJoCo;
* ``collisions`` — no contact between arm, bow, wire (outside the cut), stock and
  table, in MuJoCo and in the planner's own bow model;
* ``transits`` — every transit between passes (and the approach and retract) found a
  route clear of the cell's whole collision model (:mod:`..motion.transit`); one that
  did not is named with the passes it connects and the bodies in the direct move's way,
  and the plan then has no motion at all (no move through them is kept);
* ``timing`` (only when it fails, the plan then has no motion) — the time law found no
  usable trajectory for a pass: it would last longer than ``MAX_SAMPLES`` periods (hours
  for a loop) or its path speed collapses; named with the pass, the rulings where the
  time goes and the joint limit (or the feed) that binds there (:func:`timing_check`);
* ``wire_deviation`` — the simulated wire (from the simulated joints) within
  ``[cut] wire_tolerance`` of the target rulings inside the stock;
  ``planned_wire_deviation`` — the same for the planned joints;
* ``feed_max`` / ``feed_min`` — the feed of the wire inside the stock within
  ``[cut] feed_tolerance`` of the set feed (above and below); the lowest feed leaves
  out the slow-down and speed-up where the wire stops at a corner of its path
  (:mod:`..motion.corners`: a turn of more than 30 degrees, which no machine passes at the
  feed), counted in ``corner_stops``;
* ``kept_surface`` (kerf compensated cuts) — the kept part's surface within
  ``[cut] wire_tolerance`` of the target, from the kerf offsets (:mod:`..cut.kerf`);
* ``face_error`` (cuts that name the part's side, ``keep``) — the predicted cut face
  (the wire's chord ends moved by half the kerf predicted there, from their speeds and
  the wire's power) within ``[cut] tolerance`` of the part's surface, over the samples on
  the face (:mod:`ruledrobot.robot.wire.face`); a stop with the heat on is a burn.  Such
  a cut's ``feed_max`` / ``feed_min`` are information (the time law's target): the face
  decides (these are per cut, named ``wire_deviation:NAME`` ... when a job has several);
* ``joint_position`` / ``joint_speed`` / ``joint_acceleration`` — ratios to the
  robot's limits (finite differences of the samples) at most 1; ``joint_torque``
  — the simulated joint torques (MuJoCo, with the bow's mass) at most the limits;
* ``singularity`` — the singularity measure during the cut at least the margin.

Information only: TCP tracking error, feed within 1 %, kerf, corner stops, the wire's bow
and the corner dwell it asks for (``wire_lag``; or what to give to predict it), duration.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ...robot.motion.rates import RATIO_MAX
from ...robot.verdict import Check, Verdict
from ...robot.wire.cut import feed_checks

__all__ = ["CutMeasurements", "Measurements", "collision_sentence", "plan_verdict",
           "timing_check", "transits_check"]


@dataclass(frozen=True)
class CutMeasurements:
    """What was measured on one cut (all its passes; None: not measured).

    Units: mm, mm/s, ratios; the tolerances are the cut's own."""

    name: str
    feed_set_mm_s: float
    feed_max_mm_s: float | None
    feed_min_mm_s: float | None
    feed_within_1pct: float | None
    wire_deviation_mm: float | None
    planned_wire_deviation_mm: float | None
    kerf_mm: float
    compensated: bool
    kept_surface_error_mm: float | None
    wire_tolerance_mm: float
    feed_tolerance: float
    corner_stops: int = 0
    #: what holds the wire below the feed where it is slowest, measured (None: it is not)
    feed_min_limit: str | None = None
    #: the predicted face's largest distance from the part (None: no face judged, the cut
    #: names no part side; inf: a burn), its tolerance, and where, in words
    face_error_mm: float | None = None
    tolerance_mm: float = 0.1
    face_detail: str = ""
    #: the predicted kerf's range on the face at the wire's start and end side, in words
    predicted_kerf: str | None = None
    #: the wire's bow at the feed on the longest chord / the corner dwell it asks for, in
    #: words (None: not predicted)
    wire_lag: str | None = None
    #: the compensation follows the kerf ``[material]`` predicts per point, not ``kerf_mm``
    per_point: bool = False
    #: the predicted face's largest distance from the part as servoj follows the plan
    #: (None: not judged: no face, or a burn, which ``face_error`` reports), and where
    followed_face_mm: float | None = None
    followed_detail: str = ""


@dataclass(frozen=True)
class Measurements:
    """What the planner measured on the whole job (None: not measured).

    Units: mm, mm/s, ratios.  ``cuts``: per cut; a single cut's checks keep their plain names."""

    reach_ok: bool
    reach_detail: str
    rulings: int
    simulated: bool
    collisions: tuple[str, ...]
    position_ratio: float | None
    speed_ratio: float | None
    acc_ratio: float | None
    torque_ratio: float | None
    singularity_min: float | None
    tracking_error_mm: float | None
    duration_s: float | None
    cuts: tuple[CutMeasurements, ...] = ()
    #: the transits no clear route was found for, in words (:func:`transits_check`)
    transits: tuple[str, ...] = ()
    #: what to give to predict the wire's bow (None: every cut's is predicted)
    wire_lag_needs: str | None = None


def _cut_checks(c: CutMeasurements, single: bool) -> list[Check]:
    key = "" if single else f":{c.name}"
    of = "" if single else f" ({c.name})"
    F = c.feed_set_mm_s
    tol = c.feed_tolerance
    checks = [
        Check.at_most("wire_deviation" + key, "simulated wire deviation from the rulings" + of,
                      c.wire_deviation_mm, c.wire_tolerance_mm, "mm",
                      "the simulated wire leaves the target rulings"),
        Check.at_most("planned_wire_deviation" + key,
                      "planned wire deviation from the rulings" + of,
                      c.planned_wire_deviation_mm, c.wire_tolerance_mm, "mm",
                      "the planned wire leaves the target rulings"),
        *feed_checks(key, c.feed_max_mm_s, c.feed_min_mm_s, F, tol, (
            "highest feed inside the stock" + of, "lowest feed inside the stock" + of), (
            f"the wire moves faster than {F:g} mm/s + {100 * tol:g} %",
            f"the wire slows below {F:g} mm/s - {100 * tol:g} % inside the stock "
            f"(a wider kerf there): {c.feed_min_limit or 'see the plots'}")),
    ]  # fmt: skip
    if c.compensated:
        checks.append(Check.at_most(
            "kept_surface" + key, "kept surface from the target, kerf compensated" + of,
            c.kept_surface_error_mm, c.wire_tolerance_mm, "mm",
            "a straight wire's kerf offset cannot follow the surface's twist"))  # fmt: skip
    if c.face_error_mm is not None:
        checks.append(Check.at_most(
            "face_error" + key, "predicted cut face from the part's surface" + of,
            c.face_error_mm, c.tolerance_mm, "mm", c.face_detail))  # fmt: skip
        # the face decides; the feed window is the time law's target, shown
        checks = [dataclasses.replace(ch, gating=False) if ch.name.startswith("feed_") else ch
                  for ch in checks]  # fmt: skip
    if c.followed_face_mm is not None:
        checks.append(Check.at_most(
            "face_followed" + key, "the same as servoj follows the plan" + of,
            c.followed_face_mm, c.tolerance_mm, "mm", c.followed_detail))  # fmt: skip
    return checks


def _cut_info(c: CutMeasurements, single: bool) -> list[Check]:
    key = "" if single else f":{c.name}"
    of = "" if single else f" ({c.name})"
    kerf = ("kerf asked (compensated per point: the predicted kerf)" if c.per_point
            else "kerf (compensated)" if c.compensated else "kerf (not compensated)")
    info = [
        Check.info("feed_within_1pct" + key, "share of the cut within 1 % of the feed" + of,
                   c.feed_within_1pct),
        Check.info("kerf" + key, kerf + of, c.kerf_mm, "mm"),
    ]  # fmt: skip
    if c.predicted_kerf is not None:
        info.append(Check.info("predicted_kerf" + key, "predicted kerf on the face, wire start "
                               "side / end side" + of, c.predicted_kerf))  # fmt: skip
    if c.wire_lag is not None:
        info.append(Check.info("wire_lag" + key, "wire bow behind its ends at the feed "
                               "(longest chord) / corner dwell it asks for" + of, c.wire_lag))
    if c.corner_stops:
        info.append(Check.info(
            "corner_stops" + key, "corners where the wire stops (not in the lowest feed)" + of,
            c.corner_stops, "", "the kerf is wider where the wire stops"))  # fmt: skip
    return info


def transits_check(failures: tuple[str, ...]) -> Check:
    """Return the ``transits`` check: how many transits found no route clear of the cell.

    At most 0; the detail names each, the passes it connects and what is in the way.
    """
    return Check("transits", "transits without a clear route (arm, bow, wire, stock, table)",
                 len(failures), 0, relation="<=", ok=not failures,
                 detail="\n".join(failures))  # fmt: skip


def timing_check(failures: tuple[str, ...]) -> Check:
    """Return the ``timing`` check: how many passes the time law found no trajectory for.

    How many passes the time law found no usable trajectory for (at most 0): an absurd
    duration (hours for a loop), a path speed that collapses; the detail names each pass,
    the rulings where the time goes and the limit that binds there.
    """
    return Check("timing", "motions without a usable time law (hours long, stalled)",
                 len(failures), 0, relation="<=", ok=not failures,
                 detail="\n".join(failures))  # fmt: skip


def plan_verdict(m: Measurements, *, singularity_margin: float) -> Verdict:
    """The checks of a plan (see the module doc) from its measurements."""
    single = len(m.cuts) <= 1
    cut_checks = [ch for c in m.cuts for ch in _cut_checks(c, single)]
    checks = [
        Check("reach", "every ruling reachable, clear of stock and table",
              "yes" if m.reach_ok else "no", "yes", relation="==", ok=m.reach_ok,
              detail=m.reach_detail),
        Check("verified", "trajectory played in MuJoCo", "yes" if m.simulated else "no",
              "yes", relation="==", ok=m.simulated,
              detail="" if m.simulated else "the plan was not verified in MuJoCo"),
        Check("collisions", "collisions (arm, bow, wire, stock, table)",
              None if not m.reach_ok else len(m.collisions), 0, relation="<=",
              ok=m.reach_ok and not m.collisions, detail="\n".join(m.collisions[:8])
              + (f"\nand {len(m.collisions) - 8} more" if len(m.collisions) > 8 else "")),
        transits_check(m.transits),
        *cut_checks,
        Check.at_most("joint_position", "joint position / limit", m.position_ratio, 1.0,
                      detail="a joint leaves its position range"),
        Check.at_most("joint_speed", "joint speed / limit", m.speed_ratio, RATIO_MAX,
                      detail="a joint is faster than its limit"),
        Check.at_most("joint_acceleration", "joint acceleration / limit", m.acc_ratio, RATIO_MAX,
                      detail="a joint accelerates beyond its limit"),
        Check.at_most("joint_torque", "simulated joint torque / limit", m.torque_ratio, RATIO_MAX,
                      detail="a joint needs more torque than it has (payload, speed)"),
        Check.at_least("singularity", "singularity measure during the cut", m.singularity_min,
                       singularity_margin, detail="the arm comes too close to a singularity"),
        Check.info("tracking_error", "simulated TCP tracking error", m.tracking_error_mm, "mm"),
        *[ch for c in m.cuts for ch in _cut_info(c, single)],
        *([] if m.wire_lag_needs is None else
          [Check.info("wire_lag", "wire bow and corner dwell: not predicted",
                      m.wire_lag_needs)]),
        Check.info("duration", "duration of the whole trajectory", m.duration_s, "s"),
    ]  # fmt: skip
    return Verdict(tuple(checks))


def collision_sentence(c: dict, phase: str) -> str:
    """A playback collision (``Collision.as_dict()``) in words."""
    a, b = _name(c["geom1"], c["body1"]), _name(c["geom2"], c["body2"])
    if c["body1"] in ("world", ""):  # the robot's part first: "link6 hits the stock"
        a, b = b, a
    t0, t1 = c["start_s"], c["end_s"]
    when = f"at t = {t0:.2f} s" if t1 - t0 < 1e-6 else f"from t = {t0:.2f} s to {t1:.2f} s"
    return f"{a} hits {b}, {c['max_depth_mm']:.1f} mm deep, {when} ({phase})"


def _name(geom: str, body: str) -> str:
    if body in ("world", ""):
        return f"the {geom}" if geom in ("stock", "table", "floor") else geom
    if geom.startswith(body):
        return geom
    return f"{geom} of {body}"
