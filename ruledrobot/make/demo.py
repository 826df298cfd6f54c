"""make's demo: the carve demo's hyperboloid column, made into programs.

``ruledrobot demo --carve`` writes the column (from its closed form,
:mod:`ruledrobot.carve.demo`) and its cell file into the make folder's ``part/`` and makes
it there: carve, plan, program, viewer, as ``ruledrobot make part/cell.toml`` does.
"""

from __future__ import annotations

from pathlib import Path

from ..carve.demo import write_demo_cell

__all__ = ["DEMO_PART", "demo_cell"]

#: the folder of the demo's part and cell in the make folder
DEMO_PART = "part"


def demo_cell(folder: Path) -> Path:
    """Write the demo column and its cell into ``folder/part``.

    The cell file (the ``prepare`` of :func:`ruledrobot.make.make`)."""
    return write_demo_cell(Path(folder) / DEMO_PART)
