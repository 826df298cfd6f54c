"""What a playback recorded (:class:`PlaybackResult`): its report, verdict, plots and files.
"""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry import se3
from ..geometry.checks import FloatArray
from ..geometry.rotations import angle_between
from ..io.atomic import atomic_write_json
from ..robot.arm.model import RobotModel
from ..robot.motion.rates import RATIO_MAX
from ..robot.verdict import Check, Verdict
from .contacts import Collision
from .mjcf import ServoGains
from .scene import Scene

__all__ = ["REPORT_FORMAT", "PlaybackResult"]


REPORT_FORMAT = "ruledrobot.playback/1"


@dataclass(frozen=True, eq=False)
class PlaybackResult:
    """What :func:`play` recorded, at the physics step (M samples, J joints).

    Attributes
    ----------
    robot : the arm (its ``base`` and ``tool`` define the world and TCP frames).
    t : (M,) sample times [s]: the physics grid ``t[0] + k dt`` of the input times.
    q_ref, qd_ref : (M, J) the reference [rad, rad/s] (resampled to the step).
    q, qd : (M, J) the simulated joint positions and velocities.
    torque : (M, J) joint torques [N m] (servo + feed-forward + gravity
        compensation, after the torque limit).
    tcp_ref, tcp : (M, 4, 4) reference and simulated TCP poses in the world.
    wire : (M, 2, 3) simulated wire ends (start, end) in the robot base frame, or
        None without a bow (for the wire's deviation from the target rulings).
    wire_inside : (M,) length of wire inside the stock [m], or None.
    collisions : contact events.
    timestep : physics step [s]; feedforward : the servo's feed-forward.
    gains : the servo gains used.
    wall_time : seconds :func:`play` took; physics_time : seconds of it spent
        stepping the dynamics.
    """

    robot: RobotModel
    t: FloatArray
    q_ref: FloatArray = field(repr=False)
    qd_ref: FloatArray = field(repr=False)
    q: FloatArray = field(repr=False)
    qd: FloatArray = field(repr=False)
    torque: FloatArray = field(repr=False)
    tcp_ref: FloatArray = field(repr=False)
    tcp: FloatArray = field(repr=False)
    wire: FloatArray | None = field(repr=False)
    wire_inside: FloatArray | None = field(repr=False)
    collisions: tuple[Collision, ...]
    timestep: float
    feedforward: str
    gains: ServoGains = field(repr=False)
    wall_time: float
    physics_time: float
    scene: Scene | None = field(default=None, repr=False)

    # ------------------------------------------------------------------ metrics

    @property
    def duration(self) -> float:
        """Simulated time [s]."""
        return float(self.t[-1] - self.t[0]) if self.t.size > 1 else 0.0

    @property
    def realtime_factor(self) -> float:
        """Simulated seconds per wall-clock second of the whole :func:`play` call."""
        return self.duration / self.wall_time if self.wall_time > 0 else math.inf

    def joint_error(self) -> FloatArray:
        """(M, J) ``q - q_ref`` [rad]."""
        return self.q - self.q_ref

    def tcp_position_error(self) -> FloatArray:
        """(M,) distance between simulated and reference TCP [m]."""
        return np.linalg.norm(self.tcp[:, :3, 3] - self.tcp_ref[:, :3, 3], axis=-1)

    def tcp_orientation_error(self) -> FloatArray:
        """(M,) rotation angle between simulated and reference TCP frames [rad]."""
        return angle_between(self.tcp_ref, self.tcp)

    def verdict(self) -> Verdict:
        """The playback's checks.

        Collisions, joint positions, speeds and torques of the simulated arm against the
        robot's limits (gating); TCP error (information)."""
        rep = self.report()
        names = [f"{c['geom1']}/{c['geom2']} {c['max_depth_mm']:.1f} mm at {c['start_s']:.2f} s"
                 for c in rep["collisions"]]  # fmt: skip
        pos = rep["joint_position"]
        return Verdict((
            Check("collisions", "collisions in the simulation", len(names), 0, relation="<=",
                  ok=not names, detail="\n".join(names[:8])),
            Check("joint_position", "simulated joints within their ranges",
                  "yes" if pos["within_limits"] else "no", "yes", relation="==",
                  ok=bool(pos["within_limits"]), detail="a joint leaves its position range"),
            Check.at_most("joint_speed", "simulated joint speed / limit",
                          rep["joint_speed"]["max_ratio"], RATIO_MAX),
            Check.at_most("joint_torque", "simulated joint torque / limit",
                          rep["joint_torque"]["max_ratio"], RATIO_MAX,
                          detail="a joint needs more torque than it has"),
            Check.info("tcp_error", "TCP position error (simulated vs reference)",
                       rep["tcp_position_error_mm"]["max"], "mm"),
        ))  # fmt: skip

    def report(self) -> dict[str, Any]:
        """The playback report as a JSON-ready dict (keys documented in ``docs/sim.md``).

        Measured once per result (a pure function of it), a fresh copy each call."""
        cached = self.__dict__.get("_report")
        if cached is None:
            cached = self._measure()
            object.__setattr__(self, "_report", cached)
        return copy.deepcopy(cached)

    def _measure(self) -> dict[str, Any]:
        r = self.robot
        e = self.joint_error()
        pe = self.tcp_position_error()
        oe = self.tcp_orientation_error()
        speed = np.abs(self.qd).max(axis=0)
        speed_ref = np.abs(self.qd_ref).max(axis=0)
        tau = np.abs(self.torque).max(axis=0)
        tau_ratio = tau / r.max_torque
        speed_ratio = speed / r.max_velocity
        within = bool(np.all(r.within_limits(self.q)))
        within_ref = bool(np.all(r.within_limits(self.q_ref)))
        acc = (
            np.abs(np.gradient(self.qd_ref, self.timestep, axis=0)).max(axis=0)
            if self.t.size > 2
            else np.zeros(r.n_joints)
        )
        acc_ratio = acc / r.max_acceleration

        def stats(x: FloatArray, scale: float) -> dict[str, float]:
            return {
                "max": float(np.max(np.abs(x)) * scale),
                "rms": float(np.sqrt(np.mean(x * x)) * scale),
            }

        wire: dict[str, Any] | None = None
        if self.wire_inside is not None:
            inside = self.wire_inside > 0.0
            idx = np.flatnonzero(inside)
            wire = {
                "in_stock_s": float(inside.sum() * self.timestep),
                "in_stock_fraction": float(inside.mean()),
                "first_in_stock_s": float(self.t[idx[0]]) if idx.size else None,
                "last_in_stock_s": float(self.t[idx[-1]]) if idx.size else None,
                "max_length_in_stock_mm": float(self.wire_inside.max() * 1e3),
            }
        collisions = [c.as_dict() for c in self.collisions]
        ok = (
            not collisions
            and within
            and bool(np.all(tau_ratio <= RATIO_MAX))
            and bool(np.all(speed_ratio <= RATIO_MAX))
        )
        return {
            "format": REPORT_FORMAT,
            "robot": r.name,
            "duration_s": self.duration,
            "samples": int(self.t.size),
            "timestep_s": self.timestep,
            "control_period_s": r.control_period,
            "servo": {
                "feedforward": self.feedforward,
                "kp": self.gains.kp.tolist(),
                "kv": self.gains.kv.tolist(),
            },
            "joint_error_rad": {**stats(e, 1.0), "max_per_joint": np.abs(e).max(axis=0).tolist()},
            "tcp_position_error_mm": stats(pe, 1e3),
            "tcp_orientation_error_deg": stats(oe, 180.0 / np.pi),
            "joint_speed": {
                "peak_rad_s": speed.tolist(),
                "peak_reference_rad_s": speed_ref.tolist(),
                "limit_rad_s": r.max_velocity.tolist(),
                "ratio": speed_ratio.tolist(),
                "max_ratio": float(speed_ratio.max()),
            },
            "joint_torque": {
                "peak_nm": tau.tolist(),
                "limit_nm": [float(v) if np.isfinite(v) else None for v in r.max_torque],
                "ratio": [float(v) for v in tau_ratio],
                "max_ratio": float(tau_ratio.max()),
            },
            "joint_position": {
                "min_rad": self.q.min(axis=0).tolist(),
                "max_rad": self.q.max(axis=0).tolist(),
                "within_limits": within,
                "reference_within_limits": within_ref,
            },
            "joint_acceleration": {
                "peak_reference_rad_s2": acc.tolist(),
                "limit_rad_s2": r.max_acceleration.tolist(),
                "ratio": acc_ratio.tolist(),
                "max_ratio": float(acc_ratio.max()),
            },
            "collisions": collisions,
            "collision_count": len(collisions),
            "wire": wire,
            "realtime_factor": self.realtime_factor,
            "physics_realtime_factor": (
                self.duration / self.physics_time if self.physics_time > 0 else None
            ),
            "wall_time_s": self.wall_time,
            "ok": ok,
        }

    # ------------------------------------------------------------------ output

    def write(
        self, out_dir: str | os.PathLike[str], *, plots: bool = True, trajectory: bool = True
    ) -> dict[str, Path]:
        """Write the playback's report, plots and simulated trajectory into ``out_dir``.

        ``report.json``, ``tracking.png``, ``limits.png`` and ``simulated.csv`` (the
        simulated trajectory with its sidecar, ``ruledrobot.io.trajectory``); returns
        ``{name: path}``.  Every file is written atomically.
        """
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths: dict[str, Path] = {}
        rep = self.report()
        rep["verdict"] = self.verdict().as_dict()
        paths["report"] = atomic_write_json(out / "report.json", rep)
        if plots:
            paths.update(self.plot(out))
        if trajectory and self.robot.n_joints == 6:
            from ..io.trajectory import write_trajectory
            from ..robot.motion.trajectory import Trajectory, TrajectoryMeta

            base_inv = se3.inverse(np.asarray(self.robot.base))
            meta = TrajectoryMeta.for_model(
                self.robot, source="simulated by ruledrobot.sim.playback (MuJoCo)"
            )
            paths["simulated"] = write_trajectory(
                out / "simulated.csv", Trajectory(self.t, self.q, base_inv @ self.tcp, meta)
            )
        return paths

    def plot(self, out_dir: str | os.PathLike[str]) -> dict[str, Path]:
        """Draw ``tracking.png`` and ``limits.png`` (matplotlib Agg).

        ``tracking.png``: joint, TCP position and orientation errors over time;
        ``limits.png``: |torque| / limit and |speed| / limit per joint.
        """
        import matplotlib

        matplotlib.use("Agg", force=False)
        from matplotlib.figure import Figure

        from ..io.pictures import thinned_series, write_png

        out = Path(out_dir)
        t = self.t
        J = self.robot.n_joints
        labels = [f"q{i + 1}" for i in range(J)]

        # fixed margins (where constrained layout put the axes of the planner's plots):
        # a layout engine measures every tick label first, a third of the drawing time
        fig = Figure(figsize=(9, 8), dpi=100)
        fig.subplots_adjust(left=0.09, right=0.99, bottom=0.06, top=0.95, hspace=0.07)
        ax = fig.subplots(3, 1, sharex=True)
        ax[0].plot(*thinned_series(t, self.joint_error() * 1e3), lw=0.8)
        ax[0].set_ylabel("joint error [mrad]")
        ax[0].legend(labels, ncol=J, fontsize=7, loc="upper right")
        ax[1].plot(*thinned_series(t, self.tcp_position_error() * 1e3), lw=0.8, color="C3")
        ax[1].set_ylabel("TCP position error [mm]")
        ax[2].plot(*thinned_series(t, np.degrees(self.tcp_orientation_error())), lw=0.8,
                   color="C4")
        ax[2].set_ylabel("TCP orientation error [deg]")
        ax[2].set_xlabel("time [s]")
        for c in self.collisions:
            for a in ax:
                a.axvspan(c.start, max(c.end, c.start + self.timestep), color="red", alpha=0.15)
        fig.suptitle(f"{self.robot.name}: tracking ({self.feedforward} feed-forward)")
        paths = {"tracking_plot": write_png(fig, out / "tracking.png")}

        fig = Figure(figsize=(9, 6), dpi=100)
        fig.subplots_adjust(left=0.075, right=0.99, bottom=0.08, top=0.93, hspace=0.06)
        ax = fig.subplots(2, 1, sharex=True)
        lim_t = np.where(np.isfinite(self.robot.max_torque), self.robot.max_torque, np.inf)
        ax[0].plot(*thinned_series(t, np.abs(self.torque) / lim_t), lw=0.8)
        ax[0].axhline(1.0, color="k", ls="--", lw=0.8)
        ax[0].set_ylabel("|torque| / limit")
        ax[0].legend(labels, ncol=J, fontsize=7, loc="upper right")
        ax[1].plot(*thinned_series(t, np.abs(self.qd) / self.robot.max_velocity), lw=0.8)
        ax[1].axhline(1.0, color="k", ls="--", lw=0.8)
        ax[1].set_ylabel("|speed| / limit")
        ax[1].set_xlabel("time [s]")
        fig.suptitle(f"{self.robot.name}: joint torques and speeds against their limits")
        paths["limits_plot"] = write_png(fig, out / "limits.png")
        return paths
