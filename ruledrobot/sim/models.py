"""The generated MJCF files the repository commits under ``models/`` (for viewers and users).

:func:`write_models` writes the catalogue arms (:func:`ruledrobot.sim.mjcf.robot_mjcf`)
and the example hot-wire cell (:func:`ruledrobot.sim.scene.example_scene`) into a
folder the caller names; ``scripts/write_models.py`` regenerates the committed
files, and the test suite checks they equal this output.
"""

from __future__ import annotations

import os
from pathlib import Path

from ..io.atomic import atomic_write_text
from .mjcf import robot_mjcf
from .scene import example_scene

__all__ = ["COMMITTED_MODELS", "EXAMPLE_SCENE_FILE", "write_models"]

#: Catalogue models written by :func:`write_models`.
COMMITTED_MODELS: tuple[str, ...] = ("ur5e", "ur10e")
#: File name of the example work cell.
EXAMPLE_SCENE_FILE = "ur5e_hotwire_cell.xml"


def write_models(
    folder: str | os.PathLike[str], names: tuple[str, ...] = COMMITTED_MODELS
) -> list[Path]:
    """Write the catalogue models' MJCF and the example cell into ``folder``; return the paths.

    ``<name>.xml`` for each catalogue model in ``names`` and the example cell
    ``ur5e_hotwire_cell.xml``, atomically.
    """
    from ..robot import load

    out = Path(folder)
    paths = [atomic_write_text(out / f"{name}.xml", robot_mjcf(load(name))) for name in names]
    paths.append(atomic_write_text(out / EXAMPLE_SCENE_FILE, example_scene().mjcf()))
    return paths
