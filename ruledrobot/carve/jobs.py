"""The jobs carve writes: ``job.toml`` (one setup) or ``setupN/job.toml``, and their lines.

Every cut is a ``[[cut]]`` with its ``name``, its ``keep`` side, the cell's ``[cut]``
fields and a ``[cut.surface]`` naming its lines file (beside the job), refined by the
planner to ``SPACING`` between rulings.  The cell's ``[stock]``, ``[robot]`` and
``[tool]`` are copied as they are.  A closed cut that keeps its inside frees the part
(docs/wirecut.md, "Cut order"): with more than one loop the cuts go into setups — the
first holds the open cuts and the first loop, each further one a loop — and between
setups the operator puts the freed piece back in its place in the block (the offcuts
taped round it, as foam cutters do between silhouettes), so that every setup plans on
the same block.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import atomic_write_text
from ..io.lines import save_lines
from ..io.toml_text import toml_table
from .model import CarveCut

__all__ = ["SPACING", "setups_of", "toml_text", "write_jobs"]

#: largest gap [m] between the planner's refined rulings
SPACING = 0.003


def toml_text(tables: dict[str, Any], cuts: list[tuple[CarveCut, str]], title: str) -> str:
    """A job file: the cell's tables and ``cuts`` as ``(cut, lines file name)``."""
    out = [f"# {title}", "# written by ruledrobot carve; plan it with: ruledrobot plan job.toml "
           "--out DIR", ""]  # fmt: skip
    for name in ("stock", "robot", "tool"):
        if name in tables:
            out += toml_table(name, tables[name])
    defaults = dict(tables.get("cut", {}))
    for cut, file in cuts:
        entry: dict[str, Any] = {"name": cut.name,
                                 "keep": cut.keep if isinstance(cut.keep, str)
                                 else np.asarray(cut.keep).tolist(), **defaults}  # fmt: skip
        out.append(f"# {cut.kind}: {cut.what}")
        out += toml_table("cut", entry, "[[{}]]")
        out += toml_table("cut.surface", {"file": file, "spacing": SPACING})
    return "\n".join(out)


def setups_of(cuts: tuple[CarveCut, ...]) -> list[list[CarveCut]]:
    """The cuts by setup (module doc): one list when at most one loop."""
    loops = [c for c in cuts if c.closed]
    opens = [c for c in cuts if not c.closed]
    if len(loops) <= 1:
        return [list(cuts)]
    return [opens + loops[:1]] + [[c] for c in loops[1:]]


def write_jobs(folder: Path, tables: dict[str, Any], cuts: tuple[CarveCut, ...],
               part_name: str) -> list[Path]:  # fmt: skip
    """Write the lines files and the job(s) into ``folder``; the job files written."""
    setups = setups_of(cuts)
    jobs = []
    for k, group in enumerate(setups, start=1):
        where = folder if len(setups) == 1 else folder / f"setup{k}"
        named = []
        for cut in group:
            save_lines(where / f"{cut.name}.json", cut.lines, closed=cut.closed)
            named.append((cut, f"{cut.name}.json"))
        title = f"the cuts of {part_name}" + ("" if len(setups) == 1 else
                                              f", setup {k} of {len(setups)}")  # fmt: skip
        jobs.append(atomic_write_text(where / "job.toml", toml_text(tables, named, title)))
    return jobs
