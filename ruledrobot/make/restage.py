"""A setup's plan folder staged again: to list what make added, or to drop what could run.

The planner writes a setup's folder whole, with its ``manifest.json``
(:class:`~ruledrobot.io.outdir.StagedFolder`); make then writes the program into it
(``cut.script``, a name an output folder may hold) and :func:`restage` stages the folder
again from hard links with the lines files of the setup's cuts added (so that the folder
stands alone: its ``job.toml`` names them beside it), so that its manifest lists every
file it holds (the planner's own fields kept, make's added).

**A failed make leaves nothing runnable.**  Setups are made one after the other on one
block: a program of setup 1 is no use when setup 2 cannot be made, and running it would
spend the block.  So when any setup fails, :func:`strip_runnable` takes from every setup's
folder what could move a robot -- the trajectory and its sidecar, the simulated trajectory,
the program -- as a failed plan's folder has none (docs/verdict.md, "Output folders that
cannot mislead"), and its manifest says why they are gone.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from fnmatch import fnmatch
from pathlib import Path
from typing import Any

from ..io.outdir import MANIFEST, StagedFolder, read_manifest

__all__ = ["RUNNABLE", "is_runnable", "restage", "strip_runnable"]

#: what could move a robot (paths in a plan folder, glob patterns)
RUNNABLE = ("trajectory.csv", "trajectory.json", "cut.*", "simulation/simulated.*")
_MANIFEST_OWN = ("format", "complete", "written", "files", "kept")


def is_runnable(rel: str) -> bool:
    """Whether a path in a plan folder (POSIX, relative) is one of :data:`RUNNABLE`."""
    return any(fnmatch(rel, pattern) for pattern in RUNNABLE)


def _link(src: Path, dst: Path) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def restage(folder: Path, info: dict[str, Any] | None = None,
            drop: Callable[[str], bool] = lambda rel: False,
            add: dict[str, Path] | None = None) -> list[str]:  # fmt: skip
    """Stage ``folder`` again with files dropped and added; return the paths dropped.

    Without the files ``drop`` names (relative POSIX paths) and with the files ``add`` maps
    to their names in it, its manifest's fields kept and ``info`` added.
    """
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    kept_info = {k: v for k, v in (read_manifest(folder) or {}).items() if k not in _MANIFEST_OWN}
    gone = []
    with StagedFolder(folder) as stage:
        for p in files:
            rel = p.relative_to(folder).as_posix()
            if rel == MANIFEST:
                continue
            if drop(rel):
                gone.append(rel)
                continue
            _link(p, stage.path / rel)
        for rel, src in (add or {}).items():
            if not (stage.path / rel).exists():  # never over a file of the plan
                _link(src, stage.path / rel)
        stage.commit({**kept_info, **(info or {})})
    return gone


def strip_runnable(folder: Path, why: str) -> list[str]:
    """Stage ``folder`` again without its runnable files (module doc); the paths removed."""
    return restage(folder, {"runnable_removed": why}, drop=is_runnable)
