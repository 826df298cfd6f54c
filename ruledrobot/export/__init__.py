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

from .limits import check_trajectory
from .run_plan import recording_path_for
from .runner import ControllerError, RunMode, RunPlan, RunResult, run_trajectory
from .urscript import EXPORT_FORMATS, export_trajectory, urscript_program

__all__ = [
    "EXPORT_FORMATS",
    "ControllerError",
    "RunMode",
    "RunPlan",
    "RunResult",
    "check_trajectory",
    "export_trajectory",
    "recording_path_for",
    "run_trajectory",
    "urscript_program",
]
