"""The plan's verdict: every measurement of a planned cut as a :class:`Check`.

Gating (the plan is feasible only when all hold; ``docs/verdict.md``):

* ``reach`` — every ruling of the path has a continuous joint solution clear of
  the stock and table (the redundancy search);
* ``verified`` — the trajectory was played in MuJoCo;
* ``collisions`` — no contact between arm, bow, wire (outside the cut), stock and
  table, in MuJoCo and in the planner's own bow model;
* ``wire_deviation`` — the simulated wire (from the simulated joints) within
  ``[cut] wire_tolerance`` of the target rulings inside the stock;
  ``planned_wire_deviation`` — the same for the planned joints;
* ``feed_max`` / ``feed_min`` — the feed of the wire inside the stock within
  ``[cut] feed_tolerance`` of the set feed (above and below);
* ``joint_position`` / ``joint_speed`` / ``joint_acceleration`` — ratios to the
  robot's limits (finite differences of the samples) at most 1; ``joint_torque``
  — the simulated joint torques (MuJoCo, with the bow's mass) at most the limits;
* ``singularity`` — the singularity measure during the cut at least the margin.

Information only: TCP tracking error, feed within 1 %, kerf, duration.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..robot.verdict import Check, Verdict

__all__ = ["Measurements", "collision_sentence", "plan_verdict"]


@dataclass(frozen=True)
class Measurements:
    """What the planner measured (None: not measured).  Units: mm, mm/s, ratios."""

    reach_ok: bool
    reach_detail: str
    rulings: int
    simulated: bool
    collisions: tuple[str, ...]
    wire_deviation_mm: float | None
    planned_wire_deviation_mm: float | None
    feed_set_mm_s: float
    feed_max_mm_s: float | None
    feed_min_mm_s: float | None
    feed_within_1pct: float | None
    position_ratio: float | None
    speed_ratio: float | None
    acc_ratio: float | None
    torque_ratio: float | None
    singularity_min: float | None
    tracking_error_mm: float | None
    kerf_mm: float
    duration_s: float | None


def plan_verdict(
    m: Measurements, *, wire_tolerance_mm: float, feed_tolerance: float, singularity_margin: float
) -> Verdict:
    """The checks of a plan (see the module doc) from its measurements."""
    F = m.feed_set_mm_s
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
        Check.at_most("wire_deviation", "simulated wire deviation from the rulings",
                      m.wire_deviation_mm, wire_tolerance_mm, "mm",
                      "the simulated wire leaves the target rulings"),
        Check.at_most("planned_wire_deviation", "planned wire deviation from the rulings",
                      m.planned_wire_deviation_mm, wire_tolerance_mm, "mm",
                      "the planned wire leaves the target rulings"),
        Check.at_most("feed_max", "highest feed inside the stock", m.feed_max_mm_s,
                      F * (1 + feed_tolerance), "mm/s",
                      f"the wire moves faster than {F:g} mm/s + {100 * feed_tolerance:g} %"),
        Check.at_least("feed_min", "lowest feed inside the stock", m.feed_min_mm_s,
                       F * (1 - feed_tolerance), "mm/s",
                       f"the joints cannot hold {F:g} mm/s - {100 * feed_tolerance:g} %: the "
                       "wire slows down inside the stock (a wider kerf there)"),
        Check.at_most("joint_position", "joint position / limit", m.position_ratio, 1.0,
                      detail="a joint leaves its position range"),
        Check.at_most("joint_speed", "joint speed / limit", m.speed_ratio, 1.0,
                      detail="a joint is faster than its limit"),
        Check.at_most("joint_acceleration", "joint acceleration / limit", m.acc_ratio, 1.0,
                      detail="a joint accelerates beyond its limit"),
        Check.at_most("joint_torque", "simulated joint torque / limit", m.torque_ratio, 1.0,
                      detail="a joint needs more torque than it has (payload, speed)"),
        Check.at_least("singularity", "singularity measure during the cut", m.singularity_min,
                       singularity_margin, detail="the arm comes too close to a singularity"),
        Check.info("tracking_error", "simulated TCP tracking error", m.tracking_error_mm, "mm"),
        Check.info("feed_within_1pct", "share of the cut within 1 % of the feed",
                   m.feed_within_1pct),
        Check.info("kerf", "kerf (not compensated)", m.kerf_mm, "mm"),
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


def ranges_text(mask: np.ndarray, unit: str = "rulings") -> str:
    """``"rulings 3-17, 40-41"`` for the True runs of a boolean mask."""
    m = np.asarray(mask, dtype=np.int8)
    d = np.diff(np.r_[0, m, 0])
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1) - 1
    parts = [f"{a}" if a == b else f"{a}-{b}" for a, b in zip(starts, stops, strict=True)]
    return f"{unit} " + ", ".join(parts[:8]) + (" ..." if len(parts) > 8 else "")
