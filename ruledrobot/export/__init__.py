"""UR export: trajectory files, URScript programs, RTDE streaming (the runner).

* :func:`export_trajectory` — CSV / JSON / NPZ / URScript files (atomic).
* :func:`urscript_program` — a standalone URScript program (servoj or movep/movel).
* :func:`run_trajectory` — play a trajectory on a controller through ur_rtde,
  monitored, with safe stops and a recording of the actual motion.

The controller emulator the runner is tested against is its own package,
:mod:`ruledrobot.ursim`.

See ``docs/rtde.md``.  ``ur_rtde`` itself is imported only when a run starts.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..io.export_targets import WouldReplace, check_export_targets, export_targets
from ..robot.motion.trajectory import Trajectory
from .limits import check_trajectory
from .run_plan import recording_path_for
from .runner import ControllerError, RunMode, RunPlan, RunResult, run_trajectory
from .urscript import EXPORT_FORMATS, urscript_program
from .urscript import export_trajectory as _write_export

__all__ = [
    "EXPORT_FORMATS",
    "ControllerError",
    "RunMode",
    "RunPlan",
    "RunResult",
    "WouldReplace",
    "check_trajectory",
    "export_targets",
    "export_trajectory",
    "recording_path_for",
    "run_trajectory",
    "urscript_program",
]


def export_trajectory(
    traj: Trajectory,
    path: str | os.PathLike[str],
    fmt: str | None = None,
    *,
    force: bool = False,
    **urscript_options: object,
) -> Path:
    """Write ``traj`` to ``path`` as ``"csv"``, ``"json"``, ``"npz"`` or ``"urscript"``.

    Atomic; :func:`ruledrobot.export.urscript.export_trajectory`.

    An export never replaces a file it did not write: when a file it would write (a CSV:
    the CSV and its sidecar) exists and is not of the kind it writes there -- a user's
    file, a JSON export where the sidecar would go, a run's recording -- it raises
    :class:`WouldReplace` (a ValueError) naming the file, unless ``force``
    (:func:`ruledrobot.io.export_targets.check_export_targets`, docs/trajectory.md)."""
    p = Path(path)
    kind = fmt or EXPORT_FORMATS.get(p.suffix.lower())
    if kind is not None and not force:
        check_export_targets(p, kind)
    return _write_export(traj, p, fmt, **urscript_options)
