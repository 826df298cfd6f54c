"""The cut planner: job -> refined rulings -> wire motion -> timed joint trajectory -> files.

``plan(job, out_dir)`` writes into ``out_dir``:

* ``trajectory.csv`` — one row per controller period: ``t,q1..q6`` and the TCP
  (the wire frame, see ``docs/wirecut.md``) as a UR pose vector;
* ``refined.json`` — the refined rulings of the cut and their frames;
* ``surface.stl`` — the cut surface inside the stock (for CAD);
* ``report.json`` — the numbers below; ``plots.png`` — surface and wire
  positions, joint trajectories against limits, feed speed.

Time law: approach (a joint move to the lead-in pose from 0.1 m further out —
away from the stock centre — or from ``[robot] home``), the cut at the feed speed (lead-in, chords,
lead-out; :func:`ruledrobot.wirecut.timing.time_path`), retract.  Every number
in the report is measured on the *sampled* joints through forward kinematics.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..geometry import se3
from ..geometry._arrays import FloatArray
from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..io.lines import save_lines
from ..io.trajectory import write_trajectory
from ..robot import load, wrap_angle
from .job import Job
from .measure import feed_speeds, wire_points
from .path import CutPath, chord_ends_in_flange, cut_path
from .redundancy import bow_segments
from .timing import TimedPath, concatenate, joint_move, time_path, trajectory_limits_report
from .toolpath import speed_factor, wire_frame

__all__ = ["LIFT", "PlanResult", "plan"]

LIFT = 0.1  # m: approach from / retract to this far beyond the lead-in/out pose


@dataclass(frozen=True)
class PlanResult:
    """What :func:`plan` produced: the report, the written files, the trajectory."""

    feasible: bool
    report: dict
    files: dict[str, Path] = field(default_factory=dict)
    trajectory: TimedPath | None = field(default=None, repr=False)
    path: CutPath | None = field(default=None, repr=False)


def _wrap_near(q: FloatArray, ref: FloatArray) -> FloatArray:
    """The 2 pi representatives of ``q`` nearest ``ref``."""
    return ref + wrap_angle(q - ref)


def _backed_off(model, q: FloatArray, away: FloatArray, dist: float) -> FloatArray | None:
    """Joints nearest ``q`` whose flange is ``dist`` further along ``away`` (unit, base
    frame); None if unreachable or out of limits."""
    P = model.fk(q)
    P[:3, 3] += dist * away
    sols = model.ik(P)
    sols = sols[~np.isnan(sols).any(axis=1)]
    if not len(sols):
        return None
    sols = _wrap_near(sols, q)
    best = sols[np.argmin(np.abs(sols - q).max(axis=1))]
    return best if model.within_limits(best) else None


def _fill_nearest(values: FloatArray, valid: np.ndarray) -> FloatArray:
    """Rows of ``values`` where ``valid`` is False replaced by the nearest valid row."""
    idx = np.flatnonzero(valid)
    pos = np.clip(np.searchsorted(idx, np.arange(len(values))), 0, len(idx) - 1)
    left = idx[np.clip(pos - 1, 0, len(idx) - 1)]
    right = idx[pos]
    k = np.arange(len(values))
    nearest = np.where(np.abs(k - left) <= np.abs(right - k), left, right)
    return values[nearest]


def _interp_rows(x: FloatArray, xp: FloatArray, fp: FloatArray) -> FloatArray:
    flat = fp.reshape(len(xp), -1)
    out = np.stack([np.interp(x, xp, flat[:, k]) for k in range(flat.shape[1])], axis=1)
    return out.reshape(len(x), *fp.shape[1:])


def plan(
    job: Job,
    out_dir: str | Path,
    progress: Callable[[str], None] | None = None,
    simulate: bool = True,
    video: bool = False,
) -> PlanResult:
    """Plan ``job`` and write its files into ``out_dir`` (see the module doc).

    ``simulate``: play the trajectory in MuJoCo (the job's cell: arm, bow, stock,
    table) and report, from the *simulated* joints, the wire's deviation from the
    target rulings inside the stock, the TCP tracking error and the collisions
    (the playback report goes to ``simulation/``).  ``video``: also render
    ``video.mp4`` (needs an OpenGL backend: EGL or OSMesa).

    An infeasible job still gets ``report.json`` (``feasible: false`` and the
    reasons) and returns ``PlanResult(feasible=False)``; nothing else is written.
    """
    say = progress or (lambda msg: None)
    out = Path(out_dir)
    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    model = load(job.robot.model).with_base(job.robot.base)
    dt = float(model.control_period)
    vel = model.max_velocity * job.robot.speed_scale
    acc = model.max_acceleration if job.robot.acceleration is None else job.robot.acceleration

    say("refining the rulings and choosing the wire motion")
    cp = cut_path(job, model)
    timings["path_s"] = time.perf_counter() - t0
    m = cp.motion
    report: dict = {
        "feasible": bool(cp.feasible),
        "robot": job.robot.model,
        "input_rulings": cp.input_rulings,
        "refinement_steps": cp.steps,
        "path_rulings": len(cp.frames),
        "rulings_in_stock": int(m.hit.sum()),
        "reasons": list(m.reasons),
        "unreachable": [r for r in m.reasons if not cp.feasible],
    }
    if not cp.feasible:
        files = {"report": atomic_write_text(out / "report.json", json.dumps(report, indent=1))}
        return PlanResult(False, report, files, None, cp)

    say("timing the cut")
    t1 = time.perf_counter()
    s = np.arange(len(cp.frames), dtype=np.float64)
    ends = chord_ends_in_flange(cp)
    sf = speed_factor(m.flange, s, ends, m.hit)
    cut = time_path(s, m.q, sf, job.cut.feed_speed, vel, acc, dt)
    parts: list[TimedPath] = []
    start, end = m.q[0], m.q[-1]
    mids = (m.flange @ wire_frame(job.tool))[[0, -1], :3, 3]
    away = mids - job.stock.centre
    away /= np.linalg.norm(away, axis=1, keepdims=True)
    above_start = _backed_off(model, start, away[0], LIFT)
    above_end = _backed_off(model, end, away[1], LIFT)
    slow = job.cut.approach_speed
    if job.robot.home is not None:
        home = _wrap_near(job.robot.home, start)
        first = home if above_start is None else above_start
        parts.append(joint_move(home, first, vel, acc, dt, slow))
    if above_start is not None:
        parts.append(joint_move(above_start, start, vel, acc, dt, slow))
    n_before = len(parts)
    parts.append(cut)
    if above_end is not None:
        parts.append(joint_move(end, above_end, vel, acc, dt, slow))
    if job.robot.home is not None:
        last = end if above_end is None else above_end
        parts.append(joint_move(last, _wrap_near(job.robot.home, last), vel, acc, dt, slow))
    traj = concatenate(parts, dt) if len(parts) > 1 else cut
    timings["timing_s"] = time.perf_counter() - t1

    say("measuring and writing the results")
    t2 = time.perf_counter()
    in_cut = traj.segment == n_before
    W = wire_frame(job.tool)
    flange = model.fk(traj.q)
    s_t = np.clip(traj.s_of_t - traj.s_of_t[in_cut][0], 0.0, s[-1])
    i0 = np.clip(np.floor(s_t).astype(int), 0, len(s) - 2)
    # inside the stock: both neighbouring rulings cross it
    hit_t = in_cut & m.hit[i0] & m.hit[i0 + 1]
    ends_t = _interp_rows(s_t, s, _fill_nearest(ends, m.hit))
    feed = feed_speeds(traj.t, flange, ends_t, hit_t)
    ratios = trajectory_limits_report(traj.t, traj.q, model.max_velocity, model.max_acceleration)
    # bow clearance along the whole sampled motion (approach and retract too)
    segs = bow_segments(job.tool)
    world = wire_points(flange, segs.reshape(1, 6, 3).repeat(len(flange), 0)).reshape(-1, 3, 2, 3)
    bow_hits = job.stock.segment_hits(world[:, :, 0], world[:, :, 1]).any(axis=1) & ~in_cut
    collisions = []
    if bow_hits.any():
        k = np.flatnonzero(bow_hits)
        collisions.append(
            {
                "what": "bow vs stock outside the cut",
                "first_t": float(traj.t[k[0]]),
                "samples": int(k.size),
            }
        )
    # planned wire deviation: distance of the sampled wire's chord ends from the target
    # ruling at the same path parameter — the z axis of the refined frame motion there
    # (the screw geodesic between the neighbouring refined frames)
    target = se3.geodesic(cp.frames[i0], cp.frames[i0 + 1], s_t - i0)
    G = flange @ W
    ends_w = wire_points(flange, ends_t)
    off = ends_w - target[:, None, :3, 3]
    dev = np.linalg.norm(np.cross(off, target[:, None, :3, 2]), axis=-1).max(axis=1)
    sim_files: dict[str, Path] = {}
    if simulate:
        say("verifying in MuJoCo")
        t3 = time.perf_counter()
        from ..sim import Scene, play

        scene = Scene.from_job(job, robot=model)
        pb = play(scene, traj.t, traj.q, traj.qd)
        sim = pb.report()
        w_sim = wire_points(model.fk(pb.q), ends_t)
        off_sim = w_sim - target[:, None, :3, 3]
        dev_sim = np.linalg.norm(np.cross(off_sim, target[:, None, :3, 2]), axis=-1).max(axis=1)
        report["max_wire_deviation_mm"] = float(dev_sim[hit_t].max() * 1e3) if hit_t.any() else 0.0
        report["max_tcp_tracking_error_mm"] = sim["tcp_position_error_mm"]["max"]
        report["simulation_realtime_factor"] = sim.get("realtime_factor")
        collisions.extend(c.as_dict() for c in pb.collisions)
        sim_files = {f"simulation_{k}": v for k, v in pb.write(out / "simulation").items()}
        if video:
            from ..sim import render_video

            sim_files["video"] = render_video(scene, out / "video.mp4", traj.t, pb.q)
        timings["simulation_s"] = time.perf_counter() - t3
    cut_feed = feed[hit_t]
    interior = hit_t & ~traj.feed_limited
    report.setdefault("max_wire_deviation_mm", None)
    report.setdefault("max_tcp_tracking_error_mm", None)
    report.update(
        {
            "duration_s": float(traj.t[-1]),
            "cut_duration_s": float(traj.t[in_cut][-1] - traj.t[in_cut][0]),
            "samples": len(traj.t),
            "control_period_s": dt,
            "feed_speed_mm_s": job.cut.feed_speed * 1e3,
            "max_feed_speed_mm_s": float(cut_feed.max() * 1e3) if cut_feed.size else 0.0,
            "feed_within_1pct_fraction": float(
                np.mean(np.abs(feed[interior] / job.cut.feed_speed - 1.0) <= 0.01)
            )
            if interior.any()
            else 0.0,
            "max_joint_speed_ratio": ratios["max_speed_ratio"],
            "max_joint_accel_ratio": ratios["max_acc_ratio"],
            "min_singularity_measure": float(model.singularity_measure(traj.q[in_cut]).min()),
            "max_planned_wire_deviation_mm": float(dev[hit_t].max() * 1e3) if hit_t.any() else 0.0,
            "collisions": collisions,
            "roll_deg": float(np.degrees(m.roll[0])),
            "constant_roll": bool(np.ptp(m.roll) < 1e-12),
            "slide_m": float(m.slide[0]),
            "wire_reversed": bool(m.reverse),
            "kerf_mm": job.cut.kerf * 1e3,
        }
    )
    files: dict[str, Path] = {}
    files["trajectory"] = write_trajectory(
        out / "trajectory.csv",
        traj.t,
        traj.q,
        G,
        comments=[
            f"robot: {job.robot.model}",
            f"period: {dt} s",
            "tcp: wire frame (midpoint of the wire, z along it)",
        ],
    )
    from ..geometry.lines import Lines
    from ..geometry.mesh import box_clipped_mesh
    from ..io.mesh import write_stl

    z, o = cp.frames[:, :3, 2], cp.frames[:, :3, 3]
    lines = Lines(np.concatenate([z, np.cross(o, z)], axis=1))
    files["refined"] = save_lines(out / "refined.json", lines, frames=cp.frames)
    mesh = box_clipped_mesh(lines, job.stock.centre, job.stock.size, job.stock.rotation)
    if len(mesh.faces):
        files["surface"] = write_stl(out / "surface.stl", mesh.vertices, mesh.faces)
    files["plots"] = _plots(out / "plots.png", job, cp, traj, feed, hit_t, model, flange, W)
    files.update(sim_files)
    timings["write_s"] = time.perf_counter() - t2 - timings.get("simulation_s", 0.0)
    timings["total_s"] = time.perf_counter() - t0
    report["timings"] = timings
    files["report"] = atomic_write_text(out / "report.json", json.dumps(report, indent=1) + "\n")
    return PlanResult(True, report, files, traj, cp)


def _plots(
    path: Path,
    job: Job,
    cp: CutPath,
    traj: TimedPath,
    feed: FloatArray,
    hit_t: np.ndarray,
    model,
    flange: FloatArray,
    W: FloatArray,
) -> Path:
    """One PNG: surface with wire positions, joints against limits, feed speed."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(13, 8.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(2, 2, (1, 3), projection="3d")
    m = cp.motion
    h = m.hit
    c0, c1 = m.chord[:, 0], m.chord[:, 1]
    F = cp.frames
    a = F[h, :3, 3] + c0[h, None] * F[h, :3, 2]
    b = F[h, :3, 3] + c1[h, None] * F[h, :3, 2]
    for p, q in zip(a[::2], b[::2], strict=True):
        ax.plot(*np.c_[p, q], color="tab:blue", lw=0.6)
    G = m.flange @ W
    half = 0.5 * job.tool.wire_length
    ends = np.stack([G[:, :3, 3] - half * G[:, :3, 2], G[:, :3, 3] + half * G[:, :3, 2]], 1)
    for e in ends[:: max(1, len(ends) // 12)]:
        ax.plot(*e.T, color="tab:orange", lw=1.5)
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * 0.5
    pts = job.stock.centre + (corners * job.stock.size) @ job.stock.rotation.T
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(corners[i] != corners[j]) == 1:
                ax.plot(*pts[[i, j]].T, color="0.4", lw=0.8)
    ax.set_title("cut surface in the stock (blue), planned wire positions (orange)")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    ax2 = fig.add_subplot(2, 2, 2)
    for j in range(6):
        ax2.plot(traj.t, traj.q[:, j], label=f"q{j + 1}")
    ax2.set_title("joint positions (rad); limits ±2π")
    ax2.set_xlabel("t (s)")
    ax2.legend(ncol=6, fontsize=7)
    ax3 = fig.add_subplot(2, 2, 4)
    ax3.plot(traj.t[hit_t], feed[hit_t] * 1e3, ".", ms=1, label="measured (FK of samples)")
    ax3.axhline(job.cut.feed_speed * 1e3, color="k", lw=0.8, label="set feed")
    ax3.set_title("feed speed of the wire inside the stock (mm/s)")
    ax3.set_xlabel("t (s)")
    ax3.legend(fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return atomic_write_bytes(path, buf.getvalue())
