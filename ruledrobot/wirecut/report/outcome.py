"""A plan's outcome: the report (``report.json``) and the verdict, from the plan and its
verification in MuJoCo (``docs/verdict.md``).

The report holds the whole job (duration, ratios, collisions, the largest figures
over all cuts) and a section per cut (``report["cuts"]``): its passes, rulings,
feed, wire deviation, kerf and the kept surface's error, the chosen roll and slide.
"""

from __future__ import annotations

import numpy as np

from ...robot.motion.servo import servo_time_constant
from ...robot.verdict import Check, Verdict
from ...robot.wire.cut import feed_measures
from ...robot.wire.face import FaceError
from ...robot.wire.lag import corner_dwell, wire_bow
from ..cut.heat_power import burn_advice
from ..motion.feed_limit import feed_limit_reason
from ..plan import SINGULARITY_MARGIN, Plan, job_reference
from ..reach.explain import reach_reasons
from ..verify import Verification
from .verdict import (
    CutMeasurements,
    Measurements,
    plan_verdict,
    timing_check,
    transits_check,
)

__all__ = ["REPORT_FORMAT", "plan_outcome"]

REPORT_FORMAT = "ruledrobot.plan-report/1"
#: what the report says when the wire's bow cannot be predicted (docs/kerf.md, "Wire lag")
LAG_NEEDS = ("give [material] drag (N/m per m/s) and [tool] wire_tension (N) to predict "
             "the wire's bow and the corner dwell it asks for")  # fmt: skip


def _mm(x: float | None) -> float | None:
    return None if x is None else float(x) * 1e3


def _keep_text(keep) -> str | list[float] | None:
    if keep is None or isinstance(keep, str):
        return keep
    return [float(v) for v in keep]


def _cut_sections(plan: Plan, ver: Verification | None) -> tuple[list[dict], list[CutMeasurements]]:
    mo, me = plan.motion, plan.measured
    sections, measures = [], []
    cut_meta = plan.trajectory.meta.cut
    feeds = {f.name: f for f in feed_measures(mo.wire, cut_meta)}
    faces = me.faces  # computed once with the plan
    for cut in plan.job.cuts:
        ks = [k for k, cp in enumerate(plan.passes) if cp.cut is cut]
        passes = [plan.passes[k] for k in ks]
        rows = np.isin(mo.pass_of, ks) & mo.surface
        interior = rows & ~mo.timed.feed_limited
        slits = np.isin(mo.pass_of, ks) & mo.in_stock & ~mo.surface
        stops = rows & (False if mo.corner_stop is None else mo.corner_stop)
        fm = feeds.get(cut.name)
        n_stops = int(np.count_nonzero(stops & ~np.r_[False, stops[:-1]]))
        dev_p = float(me.deviation[rows].max()) if rows.any() else 0.0
        dev_s = None if ver is None else (float(ver.deviation[rows].max()) if rows.any() else 0.0)
        err = max((float(np.max(cp.kerf_error)) for cp in passes
                   if cp.kerf_error is not None and cp.kerf_error.size), default=0.0)  # fmt: skip
        compensated = any(cp.compensated for cp in passes)
        in_pass = np.isin(mo.pass_of, ks)
        t_cut = mo.timed.t[in_pass]
        m0 = passes[0].motion
        fe = faces.get(cut.name)
        ff = me.faces_followed.get(cut.name)
        # the followed face's finite part: a wire standing still hot is face_error's to
        # judge on the plan (the servo's creep into a stop moves where its burn test fires)
        ff_mm = None if fe is None or fe.burn or ff is None else _finite_face_mm(ff)
        lag = _wire_lag(plan, cut, float(mo.wire.chord_length[rows].max(initial=0.0)))
        cm = CutMeasurements(
            name=cut.name, feed_set_mm_s=cut.feed_speed * 1e3,
            feed_max_mm_s=_mm(None if fm is None or np.isnan(fm.highest) else fm.highest),
            feed_min_mm_s=_mm(None if fm is None or np.isnan(fm.lowest) else fm.lowest),
            feed_min_limit=None if fm is None or fm.min_ok else feed_limit_reason(plan, fm),
            corner_stops=n_stops,
            feed_within_1pct=float(np.mean(np.abs(me.feed[interior] / cut.feed_speed - 1.0)
                                           <= 0.01)) if interior.any() else None,
            wire_deviation_mm=_mm(dev_s), planned_wire_deviation_mm=_mm(dev_p),
            kerf_mm=cut.kerf * 1e3, compensated=compensated,
            per_point=compensated and plan.job.material is not None,
            kept_surface_error_mm=err * 1e3 if compensated else None,
            wire_tolerance_mm=cut.wire_tolerance * 1e3, feed_tolerance=cut.feed_tolerance,
            face_error_mm=None if fe is None else _face_mm(fe), tolerance_mm=cut.tolerance * 1e3,
            face_detail="" if fe is None else _face_detail(fe, mo, plan.job),
            followed_face_mm=None if ff_mm is None else ff_mm[0],
            followed_detail="" if ff_mm is None else _followed_detail(
                ff_mm, ff.tolerance * 1e3, float(mo.timed.t[ff_mm[1]]), mo.labels[ff_mm[1]]),
            predicted_kerf=None if fe is None else _kerf_words(fe),
            wire_lag=None if lag["bow_mm"] is None else
            f"{lag['bow_mm']:.3g} mm / {lag['corner_dwell_s']:.3g} s",
        )  # fmt: skip
        measures.append(cm)
        sections.append({
            "name": cut.name,
            "closed": any(cp.closed for cp in passes),
            "passes": len(passes),
            "input_rulings": passes[0].input_rulings,
            "refinement_steps": passes[0].steps,
            "path_rulings": int(sum(len(cp.frames) for cp in passes)),
            "rulings_in_stock": int(sum(int(cp.motion.hit.sum()) for cp in passes)),
            "cut_duration_s": float(t_cut[-1] - t_cut[0]) if t_cut.size else 0.0,
            "feed_speed_mm_s": cm.feed_set_mm_s,
            "max_feed_speed_mm_s": cm.feed_max_mm_s,
            "min_feed_speed_mm_s": cm.feed_min_mm_s,
            "corner_stops": n_stops,
            "feed_within_1pct_fraction": cm.feed_within_1pct,
            "max_planned_wire_deviation_mm": cm.planned_wire_deviation_mm,
            "max_wire_deviation_mm": cm.wire_deviation_mm,
            "kerf_mm": cm.kerf_mm,
            "kerf_compensated": compensated,
            "keep": _keep_text(cut.keep),
            "max_kept_surface_error_mm": cm.kept_surface_error_mm,
            "max_face_error_mm": None if fe is None or fe.burn else cm.face_error_mm,
            "max_followed_face_error_mm": cm.followed_face_mm,
            "face_burn": None if fe is None else fe.burn,
            "face_tolerance_mm": cm.tolerance_mm,
            "predicted_kerf_mm": None if fe is None else _kerf_range(fe),
            "wire_lag": lag,
            "roll_deg": float(np.degrees(m0.roll[0])),
            "constant_roll": bool(np.ptp(m0.roll) < 1e-12),
            "slide_m": float(m0.slide[0]),
            "wire_reversed": bool(m0.reverse),
            "notes": [n for cp in passes for n in cp.notes],
            "slit_feed_mm_s": [float(me.feed[slits].min() * 1e3),
                               float(me.feed[slits].max() * 1e3)] if slits.any() else None,
        })
    return sections, measures


def _wire_lag(plan: Plan, cut, chord: float) -> dict:
    """The wire's lag on one cut, information (docs/kerf.md, "Wire lag"): its bow behind its
    ends at the cut's feed on its longest chord in the block ``chord`` [m]
    (:func:`~ruledrobot.robot.wire.lag.wire_bow`) and the corner dwell that asks for
    (:func:`~ruledrobot.robot.wire.lag.corner_dwell`); ``bow_mm`` None and ``needs`` saying
    what to give without ``[material] drag`` and ``[tool] wire_tension``."""
    job = plan.job
    drag = None if job.material is None else job.material.drag
    tension, length = job.tool.wire_tension, job.tool.wire_length
    out = {"information": True, "speed_mm_s": cut.feed_speed * 1e3, "chord_mm": chord * 1e3,
           "wire_length_mm": length * 1e3, "drag_n_s_m2": drag, "wire_tension_n": tension}
    if drag is None or tension is None:
        return out | {"bow_mm": None, "corner_dwell_s": None, "needs": LAG_NEEDS}
    bow = float(wire_bow(cut.feed_speed, chord, length, tension, drag))
    return out | {"bow_mm": bow * 1e3,
                  "corner_dwell_s": float(corner_dwell(bow, cut.feed_speed))}  # fmt: skip


def _face_mm(fe: FaceError) -> float | None:
    """The worst face error in mm (inf: a burn; None: the wire never on the face)."""
    return None if np.isnan(fe.worst) else float(fe.worst) * 1e3


def _face_detail(fe: FaceError, mo, job) -> str:
    """Where the face is worst, in words: a burn's time, where the wire stands and what to
    change (:func:`~..cut.heat_power.burn_advice`), or the error's time and phase."""
    if np.isnan(fe.worst):
        return "the wire never cut the part's face"
    if fe.burn:
        at_corner = mo.corner_stop is not None and bool(mo.corner_stop[fe.at])
        where = "at a corner stop in the foam" if at_corner else "in the foam"
        return (f"burn at t = {fe.t:.3f} s: the wire stops {where} with the heat above its "
                f"threshold; {burn_advice(job.tool.heat, job.material)}")  # fmt: skip
    return (f"worst at t = {fe.t:.3f} s ({mo.labels[fe.at]}), the predicted kerf there "
            f"{fe.kerf[fe.at, 0] * 1e3:.3f} / {fe.kerf[fe.at, 1] * 1e3:.3f} mm at the wire's "
            "start / end side")  # fmt: skip


def _finite_face_mm(fe: FaceError) -> tuple[float, int] | None:
    """The largest finite face error in mm and its sample (None: none finite)."""
    e = np.where(np.isfinite(fe.error), fe.error, -np.inf)
    if not np.isfinite(e).any():
        return None
    j = int(np.argmax(e))
    return float(e[j]) * 1e3, j


def _followed_detail(worst: tuple[float, int], tolerance_mm: float, t: float, label: str) -> str:
    """Where the face as servoj follows is worst, and what to change when it fails."""
    words = f"worst at t = {t:.3f} s ({label})"
    if worst[0] <= tolerance_mm:
        return words
    return (words + f": the controller's servo lags the plan by about {servo_time_constant():g}"
            " s and cuts inside tight turns by about (speed x lag)^2 / 2 x radius: lower the "
            "cut's feed_speed (half the feed, about a quarter of the error)")


def _kerf_range(fe: FaceError) -> dict[str, list[float] | None]:
    """The predicted kerf's range [min, max] in mm at each chord end on the face.

    A burn's unbounded kerf is ``null`` (strict JSON has no infinity; ``face_burn`` says it).
    """
    r = fe.kerf_range() * 1e3

    def mm(x: float) -> float | None:
        return float(x) if np.isfinite(x) else None

    return {side: None if np.isnan(r[i]).any() else [mm(r[i, 0]), mm(r[i, 1])]
            for i, side in enumerate(("wire_start_side", "wire_end_side"))}  # fmt: skip


def _kerf_words(fe: FaceError) -> str | None:
    """``"0.80-0.81 / 0.80-0.93 mm"``: the kerf's range at each chord end (None: none)."""
    r = fe.kerf_range() * 1e3
    if np.isnan(r).any():
        return None
    return " / ".join(f"{a:.3f}-{b:.3f}" for a, b in r) + " mm"


def _unreachable(plan: Plan) -> tuple[dict, Verdict]:
    """A plan without motion: some pass is infeasible (``reach`` fails), or every pass is
    feasible and the time law found no usable trajectory for one (``reach`` holds,
    ``timing`` fails) or a transit found no clear route (``transits`` fails)."""
    reasons = tuple(plan.reasons) + reach_reasons(plan)  # how far, which rule, where to move
    ok = (bool(plan.transit_failures) or bool(plan.timing_failures)) and all(
        cp.feasible for cp in plan.passes)  # fmt: skip
    checks = [Check("reach", "every ruling reachable, clear of stock and table",
                    "yes" if ok else "no", "yes", relation="==", ok=ok,
                    detail="" if ok else "; ".join(reasons))]  # fmt: skip
    if ok and plan.timing_failures:  # the time law: before any transit is looked for
        checks.append(timing_check(plan.timing_failures))
        reasons += plan.timing_failures
    elif ok:
        failures = tuple(f.sentence() for f in plan.transit_failures)
        checks.append(transits_check(failures))
        reasons += failures
    verdict = Verdict(tuple(checks))
    cp = plan.passes[0]
    report = {
        "format": REPORT_FORMAT,
        "robot": plan.job.robot.model,
        "job": job_reference(plan),
        "input_rulings": cp.input_rulings,
        "refinement_steps": cp.steps,
        "path_rulings": int(sum(len(p.frames) for p in plan.passes)),
        "rulings_in_stock": int(sum(int(p.motion.hit.sum()) for p in plan.passes)),
        "reasons": list(reasons),
        "notes": list(plan.notes),
        "feasible": False,
        "verdict": verdict.as_dict(),
        "timings": dict(plan.timings),
    }
    return report, verdict


def plan_outcome(plan: Plan, ver: Verification | None) -> tuple[dict, Verdict]:
    """The report and the verdict of ``plan``.

    ``ver`` None: not verified in MuJoCo (the ``verified`` check fails)."""
    if plan.motion is None:
        return _unreachable(plan)
    job, mo, me = plan.job, plan.motion, plan.measured
    sections, cut_measures = _cut_sections(plan, ver)
    sim = ver.report if ver is not None else None
    collisions = list(me.collisions) + (list(ver.collisions) if ver is not None else [])
    sentences = tuple(me.sentences) + (tuple(ver.sentences) if ver is not None else ())
    meas = Measurements(
        reach_ok=True, reach_detail="", rulings=int(sum(len(cp.frames) for cp in plan.passes)),
        simulated=ver is not None, collisions=sentences,
        position_ratio=me.position_ratio, speed_ratio=me.ratios["max_speed_ratio"],
        acc_ratio=me.ratios["max_acc_ratio"],
        torque_ratio=None if sim is None else sim["joint_torque"]["max_ratio"],
        singularity_min=me.singularity_min,
        tracking_error_mm=None if sim is None else sim["tcp_position_error_mm"]["max"],
        duration_s=float(mo.timed.t[-1]), cuts=tuple(cut_measures),
        wire_lag_needs=None if any(c.wire_lag for c in cut_measures) else LAG_NEEDS,
    )  # fmt: skip
    verdict = plan_verdict(meas, singularity_margin=SINGULARITY_MARGIN)
    if not mo.surface.any():
        missing = Check("in_stock", "the wire passes through the stock", "no", "yes",
                        relation="==", ok=False,
                        detail="no sample has the wire inside the stock")  # fmt: skip
        verdict = Verdict((*verdict.checks, missing))
    first = sections[0]
    cutting = mo.pass_of >= 0
    t_cut = mo.timed.t[cutting]

    def worst(key: str, fn=max):
        vals = [s[key] for s in sections if s[key] is not None]
        return fn(vals) if vals else None

    report = {
        "format": REPORT_FORMAT,
        "robot": job.robot.model,
        "job": job_reference(plan),
        "input_rulings": first["input_rulings"],
        "refinement_steps": first["refinement_steps"],
        "path_rulings": meas.rulings,
        "rulings_in_stock": int(sum(s["rulings_in_stock"] for s in sections)),
        "reasons": list(plan.reasons),
        "notes": list(plan.notes),
        "feasible": verdict.ok,
        "verdict": verdict.as_dict(),
        "duration_s": float(mo.timed.t[-1]),
        "cut_duration_s": float(t_cut[-1] - t_cut[0]) if t_cut.size else 0.0,
        "samples": int(mo.timed.t.size),
        "control_period_s": float(plan.model.control_period),
        "feed_speed_mm_s": first["feed_speed_mm_s"],
        "max_feed_speed_mm_s": worst("max_feed_speed_mm_s"),
        "min_feed_speed_mm_s": worst("min_feed_speed_mm_s", min),
        "feed_within_1pct_fraction": worst("feed_within_1pct_fraction", min),
        "max_joint_position_ratio": me.position_ratio,
        "max_joint_speed_ratio": me.ratios["max_speed_ratio"],
        "max_joint_accel_ratio": me.ratios["max_acc_ratio"],
        "max_joint_torque_ratio": meas.torque_ratio,
        "min_singularity_measure": me.singularity_min,
        "max_planned_wire_deviation_mm": worst("max_planned_wire_deviation_mm"),
        "max_wire_deviation_mm": worst("max_wire_deviation_mm"),
        "max_tcp_tracking_error_mm": meas.tracking_error_mm,
        "collisions": collisions,
        "roll_deg": first["roll_deg"],
        "constant_roll": first["constant_roll"],
        "slide_m": first["slide_m"],
        "wire_reversed": first["wire_reversed"],
        "kerf_mm": first["kerf_mm"],
        "heat": None if job.tool.heat is None else {
            "output": job.tool.heat.output, "preheat_s": job.tool.heat.preheat,
            "windows_s": [[float(mo.timed.t[a]), float(mo.timed.t[b - 1])]
                          for a, b in plan.trajectory.meta.heat.windows],
        },
        "cuts": sections,
        "timings": dict(plan.timings),
    }
    if sim is not None:
        report["simulation_realtime_factor"] = sim.get("realtime_factor")
        report["timings"]["simulation_s"] = ver.seconds
    return report, verdict
