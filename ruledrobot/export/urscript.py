"""Standalone URScript programs from a joint trajectory, and trajectory export in four formats.

:func:`urscript_program` writes a program a UR controller runs by itself
(send it to port 30003, or load it on the pendant)::

    def ruledrobot_cut():
      set_tcp(p[...])                                  # the model's tool
      movej([q0...], a=0.5, v=0.25)                    # approach at reduced speed
      servoj([q...], t=0.002, lookahead_time=0.1, gain=300)   # one line per sample
      ...
      stopj(2.0)
    end

``mode="servoj"`` streams every sample (``t`` = the time to the next
sample: the controller period for trajectories sampled at it; the last one
holds for ``5 * lookahead`` so that the arm settles on it);
``mode="movep"`` / ``"movel"`` replaces the samples by linear moves through
the TCP path decimated to a tolerance, with blends, each at the speed the
trajectory has there.

:func:`export_trajectory` writes a trajectory as CSV (the project format),
JSON, NPZ or URScript, atomically.
"""

from __future__ import annotations

import io
import json
import os
from pathlib import Path

import numpy as np

from ..geometry.se3 import ur_vector_from_pose
from ..io.atomic import atomic_write_bytes, atomic_write_text
from ..io.trajectory import HEADER, Trajectory, write_trajectory
from ..robot import RobotModel, load
from .decimate import decimate_tcp_path

__all__ = ["EXPORT_FORMATS", "export_trajectory", "urscript_program"]

#: formats of :func:`export_trajectory` and the file suffixes that select them
EXPORT_FORMATS = {".csv": "csv", ".json": "json", ".npz": "npz", ".script": "urscript",
                  ".urscript": "urscript"}  # fmt: skip


def _num(x: float, digits: int) -> str:
    s = f"{float(x):.{digits}g}"
    return "0" if s in ("-0", "0") else s


def _vec(v: np.ndarray, digits: int) -> str:
    return "[" + ", ".join(_num(x, digits) for x in v) + "]"


def urscript_program(
    traj: Trajectory,
    model: RobotModel | str = "ur5e",
    *,
    mode: str = "servoj",
    lookahead: float = 0.1,
    gain: float = 300.0,
    approach_speed: float = 0.25,
    approach_acceleration: float = 0.5,
    tolerance: float = 0.0005,
    angle_tolerance: float = 0.005,
    blend: float = 0.002,
    acceleration: float = 1.0,
    name: str = "ruledrobot_cut",
    set_tcp: bool = True,
    digits: int = 10,
) -> str:
    """A standalone URScript program playing ``traj`` (see the module docstring).

    Parameters
    ----------
    traj : the trajectory (joint samples; the TCP column is used by the path modes).
    model : robot model or name (its tool is written as ``set_tcp``).
    mode : ``"servoj"`` (one ``servoj`` per sample), ``"movep"`` or ``"movel"``
        (decimated linear moves with blends).
    lookahead, gain : servoj parameters (0.03-0.2 s, 100-2000).
    approach_speed, approach_acceleration : the initial ``movej`` [rad/s, rad/s^2].
    tolerance, angle_tolerance : decimation of the path modes [m, rad].
    blend : blend radius of the path modes [m] (clipped to 45 % of the shorter
        neighbouring segment).
    acceleration : tool acceleration of the path modes [m/s^2].
    name : the program's function name.
    digits : significant digits of every number.
    """
    robot = load(model) if isinstance(model, str) else model
    if mode not in ("servoj", "movep", "movel"):
        raise ValueError(f"mode: expected 'servoj', 'movep' or 'movel', got {mode!r}")
    if not name.isidentifier():
        raise ValueError(f"name: {name!r} is not a URScript identifier")
    if not 0.03 <= lookahead <= 0.2:
        raise ValueError(f"lookahead: {lookahead} s outside [0.03, 0.2]")
    if not 100 <= gain <= 2000:
        raise ValueError(f"gain: {gain} outside [100, 2000]")
    t = np.asarray(traj.t, dtype=float)
    q = np.asarray(traj.q, dtype=float)
    if q.ndim != 2 or q.shape[1] != 6 or q.shape[0] != t.size or t.size < 1:
        raise ValueError(f"trajectory: expected t (M,) and q (M, 6), got {t.shape}, {q.shape}")
    if not np.all(np.isfinite(q)):
        k = int(np.argwhere(~np.isfinite(q))[0, 0])
        raise ValueError(f"trajectory sample {k}: not a finite joint vector")
    period = float(robot.control_period)
    out = io.StringIO()
    w = out.write
    w(f"def {name}():\n")
    w(f"  # ruledrobot trajectory program: {t.size} samples, {t[-1] - t[0]:.3f} s, "
      f"robot {robot.name}, mode {mode}\n")  # fmt: skip
    for c in traj.comments:
        w(f"  # {c}\n")
    if set_tcp:
        w(f"  set_tcp(p{_vec(ur_vector_from_pose(robot.tool), digits)})\n")
    w('  textmsg("ruledrobot: moving to the start")\n')
    w(f"  movej({_vec(q[0], digits)}, a={_num(approach_acceleration, digits)}, "
      f"v={_num(approach_speed, digits)})\n")  # fmt: skip
    w('  textmsg("ruledrobot: cut")\n')
    if mode == "servoj":
        # the last servoj holds the final sample while the lookahead filter settles
        settle = max(period, 5.0 * lookahead)
        dts = np.append(np.diff(t), settle) if t.size > 1 else np.array([settle])
        la, g = _num(lookahead, digits), _num(gain, digits)
        for qk, dt in zip(q, dts, strict=True):
            w(f"  servoj({_vec(qk, digits)}, t={_num(dt, digits)}, lookahead_time={la}, "
              f"gain={g})\n")  # fmt: skip
        w("  stopj(2.0)\n")
    else:
        tcp = np.asarray(traj.tcp, dtype=float)
        keep = decimate_tcp_path(tcp, tolerance, angle_tolerance)
        p = tcp[:, :3]
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        lengths = np.diff(arc[keep])
        for n, k in enumerate(keep[1:], start=1):
            i = keep[n - 1]
            L = float(lengths[n - 1])
            v = float(np.clip(L / max(t[k] - t[i], 1e-6), 1e-4, 3.0))
            r = min(blend, 0.45 * L, 0.45 * float(lengths[n])) if n < len(keep) - 1 else 0.0
            w(f"  {mode}(p{_vec(tcp[k], digits)}, a={_num(acceleration, digits)}, "
              f"v={_num(v, digits)}, r={_num(max(r, 0.0), digits)})\n")  # fmt: skip
    w('  textmsg("ruledrobot: done")\n')
    w("end\n")
    return out.getvalue()


def export_trajectory(
    traj: Trajectory,
    path: str | os.PathLike[str],
    fmt: str | None = None,
    *,
    model: RobotModel | str = "ur5e",
    **urscript_options: object,
) -> Path:
    """Write ``traj`` to ``path`` as ``"csv"``, ``"json"``, ``"npz"`` or ``"urscript"`` (atomic).

    ``fmt`` defaults to the suffix (:data:`EXPORT_FORMATS`).  CSV is the
    project's trajectory format; JSON is ``{"format": "ruledrobot.trajectory/1",
    "units": ..., "header": [...], "t": [...], "q": [[...]], "tcp": [[...]],
    "comments": [...]}``; NPZ holds arrays ``t``, ``q``, ``tcp`` and
    ``comments``; URScript is :func:`urscript_program` (``model`` and
    ``urscript_options`` go to it).  Returns the path written.
    """
    p = Path(path)
    if fmt is None:
        fmt = EXPORT_FORMATS.get(p.suffix.lower())
        if fmt is None:
            raise ValueError(
                f"{p}: cannot tell the format from the suffix {p.suffix!r}; pass fmt= one of "
                "'csv', 'json', 'npz', 'urscript'"
            )
    t = np.asarray(traj.t, dtype=float)
    q = np.asarray(traj.q, dtype=float)
    tcp = np.asarray(traj.tcp, dtype=float)
    if fmt == "csv":
        return write_trajectory(p, t, q, tcp, traj.comments)
    if fmt == "json":
        doc = {
            "format": "ruledrobot.trajectory/1",
            "units": {"t": "s", "q": "rad", "tcp": "m, rad (UR pose vector)"},
            "header": HEADER,
            "comments": list(traj.comments),
            "t": t.tolist(),
            "q": q.tolist(),
            "tcp": tcp.tolist(),
        }
        return atomic_write_text(p, json.dumps(doc, indent=None, separators=(",", ":")) + "\n")
    if fmt == "npz":
        buf = io.BytesIO()
        np.savez_compressed(buf, t=t, q=q, tcp=tcp, comments=np.array(traj.comments, dtype=str))
        return atomic_write_bytes(p, buf.getvalue())
    if fmt == "urscript":
        return atomic_write_text(p, urscript_program(traj, model, **urscript_options))  # type: ignore[arg-type]
    raise ValueError(f"fmt: expected 'csv', 'json', 'npz' or 'urscript', got {fmt!r}")
