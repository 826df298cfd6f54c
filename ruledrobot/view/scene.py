"""A plan folder as a scene description: what the browser shows, computed without a browser.

:func:`build_scene` turns a :class:`~ruledrobot.view.folder.PlanFolder` into a
:class:`PlanScene`: the geoms of the simulation's own MuJoCo model of the cell
(:class:`ruledrobot.sim.Scene` of the job, compiled as ``play`` compiles it),
their world poses at each frame from MuJoCo's kinematics, the wire (MuJoCo's
``wire_start`` / ``wire_end`` sites), the refined rulings and meshes of the
plan, the figures at each frame (phase, feed, joint speeds against their
limits, singularity measure), collisions and near misses with where and
when, and the table of checks.  No viewer library is imported here; the
server and the static export draw the same description.

Frames: everything is in MuJoCo's **world** frame, where the robot base sits
at the job's ``[robot] base``; the plan's files (rulings, ``surface.stl``, the
stock) are in the robot base frame and are moved there.  Units: m, s, rad.

Frames of the timeline are trajectory samples (no interpolation): every
``round(1 / (fps * period))``-th sample and the last one.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..geometry._arrays import FloatArray
from ..geometry.box import Box
from ..geometry.mesh import Mesh
from ..robot.arm.model import RobotModel
from ..robot.motion.rates import finite_difference_rates
from ..robot.motion.trajectory import KinematicsRef, Trajectory, model_for
from ..robot.verdict import Check
from ..robot.wire.in_stock import chord_fractions, flange_wire_ends, wire_in_stock
from ..sim._mujoco import mujoco
from ..sim.scene import Scene, default_camera
from .clearance import Event, contacts_along, locate, near_misses
from .folder import PlanFolder, read_plan_folder
from .geoms import GeomMesh, geom_meshes, geom_poses

__all__ = ["NEAR_MISS", "PlanScene", "Timeline", "build_scene"]

#: Default distance (m) under which two parts count as a near miss.
NEAR_MISS = 0.02
#: Step (s) of the clearance search along the motion (finer than the display frames).
CLEARANCE_STEP = 0.01
#: The browser's first view: the video's camera moved this fraction of the way to its target.
CAMERA_ZOOM = 0.7


@dataclass(frozen=True, eq=False)
class Timeline:
    """The motion at the display frames (K of them), all in the world frame.

    ``t`` (K,) s; ``sample`` (K,) trajectory sample index; ``q`` (K, J) rad;
    ``geom_pos`` (K, G, 3) m and ``geom_quat`` (K, G, 4) ``[w, x, y, z]``: MuJoCo's
    ``geom_xpos`` / ``geom_xmat`` of the scene's geoms (order of
    :attr:`PlanScene.geoms`); ``wire`` (K, 2, 3) the wire ends (MuJoCo's sites);
    ``chord`` (K, 2, 3) the part of the wire inside the stock (NaN outside);
    ``phase`` (K,) names; ``feed`` (K,) m/s (NaN outside the stock);
    ``speed_ratio`` (K, J) |joint speed| / limit; ``singularity`` (K,) the
    singularity measure (0 at a singularity); with a heat model (the trajectory's
    ``heat_power``): ``heat_power`` (K,) W/m the set-point and ``wire_power`` (K,) W/m the
    wire's power after the lag, and with a ``[material]`` ``kerf`` (K, 2) m the kerf
    predicted at the chord's ends (wire start side, end side) by
    ``Trajectory.face_errors`` (the verdict's model), the widest over the samples since
    the frame before (NaN: none on the part's face; inf: a burn); else None.
    """

    t: FloatArray
    sample: np.ndarray
    q: FloatArray = field(repr=False)
    geom_pos: FloatArray = field(repr=False)
    geom_quat: FloatArray = field(repr=False)
    wire: FloatArray = field(repr=False)
    chord: FloatArray = field(repr=False)
    phase: np.ndarray = field(repr=False)
    feed: FloatArray = field(repr=False)
    speed_ratio: FloatArray = field(repr=False)
    singularity: FloatArray = field(repr=False)
    kerf: FloatArray | None = field(default=None, repr=False)
    heat_power: FloatArray | None = field(default=None, repr=False)
    wire_power: FloatArray | None = field(default=None, repr=False)

    @property
    def duration(self) -> float:
        """Time from the first to the last display frame [s]."""
        return float(self.t[-1] - self.t[0])

    def frame_at(self, time: float) -> int:
        """The index of the last frame at or before ``time`` (s), clamped."""
        return int(np.clip(np.searchsorted(self.t, time + 1e-9, side="right") - 1, 0,
                           self.t.size - 1))  # fmt: skip


@dataclass(frozen=True, eq=False)
class PlanScene:
    """Everything the viewer draws of one plan folder (see the module doc).

    ``geoms`` the visible MuJoCo geoms; ``rest_pos`` (G, 3), ``rest_quat`` (G, 4)
    their poses at the first sample (or at the model's ``home`` keyframe when the
    folder holds no motion); ``stock`` the block (world); ``rulings`` (N, 2, 3)
    the refined rulings clipped to the stock; ``meshes`` name -> Mesh (world):
    ``surface``, ``part``, ``removed`` when present; ``timeline`` or None;
    ``events`` collisions and near misses; ``checks`` the verdict's table;
    ``limits``: ``feed_set``, ``feed_min``, ``feed_max`` (m/s), ``kerf_set`` (m: the
    first cut's kerf), ``singularity``
    (the smallest measure allowed), ``near_miss`` (m); ``camera``
    ``(position, target)`` (3,), (3,) world; ``notes`` what the viewer wants
    the user to know (no motion, files worked around).
    """

    folder: PlanFolder = field(repr=False)
    title: str
    verdict: str
    ok: bool
    geoms: tuple[GeomMesh, ...] = field(repr=False)
    rest_pos: FloatArray = field(repr=False)
    rest_quat: FloatArray = field(repr=False)
    stock: Box = field(repr=False)
    rulings: FloatArray = field(repr=False)
    meshes: dict[str, Mesh] = field(repr=False)
    timeline: Timeline | None = field(repr=False)
    events: tuple[Event, ...] = field(repr=False)
    checks: tuple[Check, ...] = field(repr=False)
    limits: dict[str, float] = field(repr=False)
    camera: tuple[FloatArray, FloatArray] = field(repr=False)
    notes: tuple[str, ...] = ()
    robot: RobotModel | None = field(default=None, repr=False)
    mjcf: str = field(default="", repr=False)

    @property
    def moving(self) -> np.ndarray:
        """Indices (into :attr:`geoms`) of the geoms that move with the arm."""
        return np.array([i for i, g in enumerate(self.geoms) if not g.static], dtype=int)


def _robot(folder: PlanFolder, notes: list[str]) -> RobotModel:
    """The arm as the simulation built it: the job's model, calibration and base; the
    trajectory's kinematics when the job's calibration could not be read."""
    robot = folder.job.cell_robot()
    traj = folder.trajectory
    if traj is not None and KinematicsRef.of(robot).checksum != traj.meta.kinematics.checksum:
        robot = dataclasses.replace(model_for(traj.meta), tool=np.eye(4)).with_base(robot.base)
    return robot


def _limits(folder: PlanFolder, near_miss: float) -> dict[str, float]:
    by_name = {c.name: c for c in folder.checks}
    report = folder.report

    def limit(name: str, default: float, scale: float = 1.0) -> float:
        c = by_name.get(name)
        return float(c.limit) * scale if c is not None and isinstance(c.limit, (int, float)) \
            else default

    feed_set = float(report.get("feed_speed_mm_s") or np.nan) * 1e-3
    return {
        "feed_set": feed_set,
        "kerf_set": float(report.get("kerf_mm") or np.nan) * 1e-3,
        "feed_max": limit("feed_max", np.nan, 1e-3),
        "feed_min": limit("feed_min", np.nan, 1e-3),
        "singularity": limit("singularity", 0.02),
        "near_miss": float(near_miss),
    }


def _kerf_heat(traj: Trajectory, k: np.ndarray) -> dict[str, FloatArray | None]:
    """The timeline's ``kerf``, ``heat_power``, ``wire_power`` at samples ``k`` (K,)
    (:class:`Timeline`): the verdict's model on the trajectory, each cut's face joined."""
    if traj.heat_power is None:
        return {}
    kerf = None
    if traj.meta.cut is not None and traj.meta.cut.material is not None:
        faces = traj.face_errors()
        if faces:
            kerf = np.full((traj.n, 2), np.nan)
            for fe in faces.values():
                kerf = np.where(np.isnan(fe.kerf), kerf, fe.kerf)
            # per frame the widest since the frame before: a burn between frames shows
            kerf = np.fmax.reduceat(kerf, np.r_[0, k[:-1] + 1], axis=0)
    return {"kerf": kerf, "heat_power": np.asarray(traj.heat_power)[k],
            "wire_power": traj.wire_power()[k]}


def _frames(n: int, period: float, fps: float) -> np.ndarray:
    stride = max(1, round(1.0 / (fps * period)))
    return np.unique(np.r_[np.arange(0, n, stride), n - 1])


def _phase_labels(folder: PlanFolder) -> np.ndarray:
    traj = folder.trajectory
    assert traj is not None
    labels = np.full(traj.n, "move", dtype=object)
    for p in traj.meta.phases:
        labels[p.start : p.stop] = p.name
    return labels


def _report_events(folder: PlanFolder) -> list[dict[str, Any]]:
    """Collisions the plan reported (MuJoCo's and the planner's bow model), as dicts."""
    out = []
    for c in folder.report.get("collisions") or ():
        if isinstance(c, dict):
            out.append(c)
    if not out and folder.simulation is not None:
        out = [c for c in folder.simulation.get("collisions") or () if isinstance(c, dict)]
    return out


def build_scene(
    folder: PlanFolder | str | os.PathLike[str],
    *,
    fps: float = 20.0,
    near_miss: float = NEAR_MISS,
) -> PlanScene:
    """The scene of a plan folder (see the module doc).

    ``fps`` display frames per second of trajectory time; ``near_miss`` the
    distance (m) under which two parts are marked as a near miss (the clearance
    search runs every :data:`CLEARANCE_STEP` s of the motion).
    """
    if not isinstance(folder, PlanFolder):
        folder = read_plan_folder(folder)
    if not fps > 0:
        raise ValueError(f"fps: expected a positive frame rate, got {fps}")
    if not near_miss >= 0:
        raise ValueError(f"near_miss: expected a distance >= 0 m, got {near_miss}")
    notes = list(folder.notes)
    job = folder.job
    robot = _robot(folder, notes)
    sim_scene = Scene.from_job(job, robot=robot)
    mj = mujoco()
    xml = sim_scene.mjcf()
    model = mj.MjModel.from_xml_string(xml)
    geoms = geom_meshes(mj, model)
    ids = np.array([g.geom_id for g in geoms], dtype=int)
    base = np.asarray(robot.base)
    R, p = base[:3, :3], base[:3, 3]
    stock = job.stock.moved(base)

    rulings = np.zeros((0, 2, 3))
    if folder.rulings is not None:
        lines = folder.rulings.transform(base)
        o, d = lines.point, lines.direction
        t_in, t_out, hit = stock.clip_lines(o, d)
        rulings = np.stack([o + t_in[:, None] * d, o + t_out[:, None] * d], axis=1)[hit]
    meshes = {name: Mesh(m.vertices @ R.T + p, m.faces) for name, m in folder.meshes.items()}

    traj = folder.trajectory
    timeline = None
    events: list[Event] = []
    if traj is None:
        q_rest = np.asarray(model.key_qpos[0][: robot.n_joints]) if model.nkey else np.zeros(6)
        reason = "; ".join(c.name for c in folder.checks if c.gating and not c.ok) or "unknown"
        notes.insert(0, f"no trajectory in this folder: the plan fails ({reason}), so there is "
                        "no motion to play; the arm is drawn at its home pose")  # fmt: skip
    else:
        q_rest = traj.q[0]
        k = _frames(traj.n, traj.meta.control_period, fps)
        labels = _phase_labels(folder)
        pos, quat = geom_poses(mj, model, traj.q[k], ids)
        wire = _wire_sites(mj, model, traj.q[k])
        lo, hi = chord_fractions(wire, stock)
        inside = ~np.isnan(lo)
        chord = np.where(inside[:, None, None], wire[:, :1] + np.stack([lo, hi], 1)[:, :, None]
                         * (wire[:, 1:] - wire[:, :1]), np.nan)  # fmt: skip
        flange = dataclasses.replace(robot, tool=np.eye(4)).fk(traj.q)
        tool = sim_scene.tool
        assert tool is not None
        all_wire = flange_wire_ends(flange, tool)
        feed = wire_in_stock(traj.t, all_wire, stock).feed[k]
        qd, _ = finite_difference_rates(traj.t, traj.q)
        vmax = np.asarray(robot.max_velocity, dtype=np.float64)
        speed = np.abs(qd[np.minimum(k, qd.shape[0] - 1)]) / vmax
        timeline = Timeline(traj.t[k], k, traj.q[k], pos, quat, wire, chord, labels[k], feed,
                            speed, robot.singularity_measure(traj.q[k]),
                            **_kerf_heat(traj, k))  # fmt: skip
        # where the motion comes close: MuJoCo's collision detection with a margin
        kc = _frames(traj.n, traj.meta.control_period, 1.0 / CLEARANCE_STEP)
        contacts = contacts_along(mj, model, traj.q[kc], max(near_miss, 1e-6))
        events += near_misses(contacts, traj.t[kc], labels[kc], near_miss)
    events += _reported(folder, mj, model, traj, labels if traj is not None else None)
    rest_pos, rest_quat = geom_poses(mj, model, q_rest[None], ids)
    cam_pos, cam_target = default_camera(robot.with_base(np.eye(4)), job.stock)
    # closer than the video's, aimed nearer the stock: the cut is what the user looks at
    aim = cam_target + 0.5 * (job.stock.centre - cam_target)
    cam_pos = aim + CAMERA_ZOOM * (cam_pos - cam_target)
    cam_target = aim
    camera = (R @ cam_pos + p, R @ cam_target + p)
    title = f"{folder.path.name} — {robot.name}, {len(rulings)} rulings in the stock"
    return PlanScene(folder, title, folder.summary, folder.feasible, geoms, rest_pos[0],
                     rest_quat[0], stock, rulings, meshes, timeline,
                     tuple(sorted(events, key=lambda e: (e.kind != "collision", e.time))),
                     folder.checks, _limits(folder, near_miss), camera, tuple(notes), robot,
                     xml)  # fmt: skip


def _wire_sites(mj: Any, model: Any, q: FloatArray) -> FloatArray:
    """Wire ends (K, 2, 3) world m: MuJoCo's ``wire_start`` / ``wire_end`` sites at ``q``."""
    s0 = mj.mj_name2id(model, mj.mjtObj.mjOBJ_SITE, "wire_start")
    s1 = mj.mj_name2id(model, mj.mjtObj.mjOBJ_SITE, "wire_end")
    data = mj.MjData(model)
    out = np.empty((q.shape[0], 2, 3))
    for k in range(q.shape[0]):
        data.qpos[: q.shape[1]] = q[k]
        mj.mj_kinematics(model, data)
        out[k, 0], out[k, 1] = data.site_xpos[s0], data.site_xpos[s1]
    return out


def _reported(folder: PlanFolder, mj: Any, model: Any, traj: Any, labels: Any) -> list[Event]:
    """The plan's own collision reports as events, located on the motion when there is one."""
    out = []
    for c in _report_events(folder):
        g1, g2 = c.get("geom1"), c.get("geom2")
        start = float(c.get("start_s", c.get("first_t", 0.0)) or 0.0)
        end = float(c.get("end_s", start) or start)
        depth = c.get("max_depth_mm")
        what = f"{g1} – {g2}" if g1 and g2 else str(c.get("what", "collision"))
        phase = str(c.get("phase", ""))
        position = None
        time = start
        if traj is not None and g1 and g2:
            a, b = np.searchsorted(traj.t, [start - 1e-9, end + 1e-9])
            idx = np.arange(a, max(b, a + 1))
            found = contacts_along(mj, model, traj.q[np.clip(idx, 0, traj.n - 1)], 0.0)
            hit = locate(found, g1, g2)
            if hit is not None:
                j, _, position = hit
                time = float(traj.t[min(idx[j], traj.n - 1)])
                phase = phase or str(labels[min(idx[j], traj.n - 1)])
        out.append(Event("collision", what, start, end, time, phase or "?",
                         -float(depth) if isinstance(depth, (int, float)) else 0.0, position,
                         "plan report"))  # fmt: skip
    return out
