"""``ruledrobot carve``: a cell file in, the cuts, the jobs, the carved block and the report out.

:func:`carve` reads the cell and the part, checks that the part fits the block, finds
the cuts (:mod:`.plan_cuts`), meshes the carved block and the baseline's, and writes
into a staged output folder (swapped in whole, :class:`ruledrobot.io.outdir.StagedFolder`):
``job.toml`` (or ``setupN/job.toml``) with its lines files, ``carve.json``,
``carved.stl`` and ``carve.png``.  Its verdict: every check holds — no cut enters the
part, every exact cut reproduces its face within the tolerance, the carved block is a
closed mesh that holds the part.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import atomic_write_json
from ..io.mesh import write_stl
from ..io.outdir import StagedFolder
from .carved import Carved, carve_block
from .cell import Cell, load_cell
from .jobs import setups_of, write_jobs
from .meshquery import MeshQuery
from .model import CarveCut
from .plan_cuts import CutPlan, find_cuts
from .readers import PartMesh, edge_counts, read_part
from .robotcheck import RobotCheck, next_best

__all__ = ["CarveResult", "carve", "cell_cuts", "check_fits", "read_input"]

FORMAT = "ruledrobot.carve/1"


@dataclass(frozen=True)
class CarveResult:
    """What :func:`carve` did: its report, cut plan, files and verdict.

    ``report`` (the content of ``carve.json``), the cut plan, ``files`` (name -> path) and
    ``ok`` (every check holds)."""

    report: dict[str, Any] = field(repr=False)
    plan: CutPlan = field(repr=False)
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """Whether every check holds (the report's ``ok``)."""
        return bool(self.report["ok"])


def _ratio(volume: float, part: float) -> float | None:
    """``volume / part - 1`` to 5 decimals, None when ``volume`` is not estimated (NaN)."""
    return None if not math.isfinite(volume) else round(volume / part - 1.0, 5)


def check_fits(part: PartMesh, cell: Cell) -> None:
    """ValueError naming the part file when the part does not fit in the block."""
    local = cell.stock.to_box(part.vertices)
    over = np.abs(local) - 0.5 * cell.stock.size
    if over.max() > 1e-6:
        k = int(np.argmax(over.max(axis=0)))
        raise ValueError(f"{cell.where}: [part] {part.source}: the part does not fit the block: "
                         f"{int(np.sum(over.max(axis=1) > 1e-6))} vertices outside [stock], up "
                         f"to {over.max() * 1e3:.2f} mm along the block's axis {'xyz'[k]} "
                         "(check [part] units and pose, and [stock] size)")  # fmt: skip


def _checks(plan: CutPlan, carved, part_volume: float, closed_ok: bool, tol: float,
            spread: float) -> list[dict[str, Any]]:  # fmt: skip
    gouge = max((m.gouge for m in plan.measures), default=0.0)
    exact = [m.deviation for c, m in zip(plan.cuts, plan.measures, strict=True)
             if c.kind == "exact"]  # fmt: skip
    dev = max(exact, default=0.0)
    out = [
        {"name": "no_gouge", "ok": gouge == 0.0, "value_mm": round(gouge * 1e3, 4),
         "limit_mm": 0.0, "what": "no ruling enters the part beyond the tolerance"},
        {"name": "exact_faces", "ok": dev <= tol, "value_mm": round(dev * 1e3, 4),
         "limit_mm": round(tol * 1e3, 4),
         "what": "every ruled face within the tolerance of its cut"},
        {"name": "carved_closed", "ok": closed_ok, "what": "carved.stl is a closed 2-manifold"},
        {"name": "holds_part", "ok": carved is not None and spread <= tol + 0.002,
         "value_mm": round(spread * 1e3, 3), "limit_mm": round((tol + 0.002) * 1e3, 3),
         "what": "the part lies within the carved block (its vertices at most the "
                 "tolerance plus the mesh's 2 mm grid outside it)"},
    ]  # fmt: skip
    if not exact:
        out.pop(1)
    left = [v for v in plan.faces.values() if v not in ("exact", "block face")]
    if not plan.cuts and left:
        why = [n for n in plan.notes if "the arm cannot" in n]
        out.insert(0, {"name": "cuts", "ok": False, "what": "the robot can make a cut of the part",
                       "detail": "no cut: " + ("; ".join(why) if why else left[0])
                       + ("; `ruledrobot place` searches for a placement or turn of the block "
                          "where the arm can" if why else "")})  # fmt: skip
    return out


def _offer_turn(plan: CutPlan, check: RobotCheck, cell: Cell) -> CutPlan:
    """``plan`` with the next best for its largest refused face (:func:`.robotcheck.next_best`)
    added to that face's words and the notes."""
    cut = plan.refused[0]
    words = next_best(check, cut, cell.stock, cell.part.pose, cell.tables)
    if not words:
        return plan
    faces = dict(plan.faces)
    if cut.region is not None and cut.region in faces:
        faces[cut.region] = f"{faces[cut.region]}; {words}"
    return dataclasses.replace(plan, faces=faces, notes=(*plan.notes, f"{cut.what}: {words}"))


def read_input(cell_path: str | os.PathLike[str]) -> tuple[Cell, PartMesh]:
    """Read a cell file and its part as :func:`carve` does, every input check made.

    carve's first stage alone: the cell's tables and fields, the part's file, units,
    mesh and repair (:func:`.readers.read_part`), its fit in the block
    (:func:`check_fits`); ValueError naming the file on bad input, nothing written."""
    cell = load_cell(cell_path)
    part = read_part(cell.part, cell.stock, cell.where)
    check_fits(part, cell)
    return cell, part


def cell_cuts(cell: Cell, part: PartMesh, query: MeshQuery,
              check: Callable[[CarveCut], str] | None = None,
              progress: Callable[[str], None] = lambda msg: None) -> CutPlan:  # fmt: skip
    """Return the cuts of a cell's part, as :func:`carve` finds them.

    :func:`.plan_cuts.find_cuts` with the cell's tolerance, roughing loops and lead (the
    planner's default lead when ``[cut]`` names none).  ``check``: the robot
    (:class:`.robotcheck.RobotCheck`, as :func:`carve` asks it); None: the geometry alone
    (the block-turn search of a refused face, carve's, is not made)."""
    from ..wirecut import CutSpec  # its defaults: the lead the planner uses

    lead = float(cell.tables.get("cut", {}).get("lead_in", CutSpec.lead_in))
    return find_cuts(part, cell.stock, query, cell.part.tolerance, cell.part.rough_cuts, lead,
                     progress, check)  # fmt: skip


def carve(cell_path: str | os.PathLike[str], out: str | os.PathLike[str],
          progress=lambda msg: None) -> CarveResult:  # fmt: skip
    """Carve the part of a cell file into ``out`` (module doc); ValueError on bad input."""
    times: dict[str, float] = {}
    t = time.perf_counter()
    cell, part = read_input(cell_path)
    staged = StagedFolder(out)  # refuses a folder of the user's own files at once
    times["read"] = time.perf_counter() - t
    with staged:
        t = time.perf_counter()
        query = MeshQuery(part)
        check = RobotCheck(cell.tables)
        try:
            plan = cell_cuts(cell, part, query, check, progress)
            # a face's trouble, not a block out of reach; ``turns = false``: name it only
            if plan.refused and plan.cuts and cell.part.turns:
                progress("trying the block turned for the largest face the arm cannot make")
                plan = _offer_turn(plan, check, cell)
        finally:
            check.close()
        times["robot_check"] = check.seconds
        if check.unchecked:
            plan = dataclasses.replace(plan, notes=(*plan.notes, (
                f"{check.unchecked} cuts were not checked with the robot: {check.calls} were "
                "(the most carve checks); the plan judges them")))  # fmt: skip
        times["cuts"] = time.perf_counter() - t
        t = time.perf_counter()
        progress("meshing the carved block")
        exact = tuple(c for c in plan.cuts if c.kind == "exact")
        made = carve_block(exact, cell.stock, plan.loops) if plan.cuts else None
        carved = made.mesh if made is not None else None
        base = carve_block(exact, cell.stock, plan.baseline).mesh if plan.baseline else None
        times["carved"] = time.perf_counter() - t
        t = time.perf_counter()
        files = _write(staged.path, cell, part, plan, carved)
        report = _report(cell, part, plan, carved, base, query, times, made)
        atomic_write_json(staged.path / "carve.json", report)
        progress("drawing")
        from .plot import draw

        draw(staged.path / "carve.png", part, plan, carved, cell.stock, report)
        report["timings_s"]["write"] = round(time.perf_counter() - t, 3)
        atomic_write_json(staged.path / "carve.json", report)
        target = staged.commit({"command": "carve", "cell": str(cell.source)})
    files = {k: target / v.relative_to(staged.path) for k, v in files.items()}
    files["report"], files["picture"] = target / "carve.json", target / "carve.png"
    return CarveResult(report, plan, files)


def _write(folder: Path, cell: Cell, part: PartMesh, plan: CutPlan, carved) -> dict[str, Path]:
    files: dict[str, Path] = {}
    if plan.cuts:
        for k, p in enumerate(write_jobs(folder, cell.tables, plan.cuts, part.source.name
                                         if part.source else "the part")):  # fmt: skip
            files[f"job{k + 1}" if p.parent != folder else "job"] = p
    if carved is not None:
        files["carved"] = write_stl(folder / "carved.stl", carved.vertices, carved.faces,
                                    header="ruledrobot carve: the block after the cuts, "
                                    "m")  # fmt: skip
    return files


def _report(cell: Cell, part: PartMesh, plan: CutPlan, carved, base, query: MeshQuery,
            times: dict[str, float], made: Carved | None = None) -> dict[str, Any]:  # fmt: skip
    from ..wirecut import signed_volume

    vp = part.volume
    vc = signed_volume(carved.vertices, carved.faces) if carved is not None else cell_volume(cell)
    vb = signed_volume(base.vertices, base.faces) if base is not None else None
    closed_ok = carved is not None and edge_counts(carved.faces) == (0, 0)
    far = 0.0
    spread = 0.0
    if carved is not None:
        v = carved.vertices[:: max(1, len(carved.vertices) // 20000)]
        far = float(query.distance(v).max())
        from .meshquery import MeshQuery as _MQ
        from .readers import PartMesh as _PM

        cq = _MQ(_PM(carved.vertices, carved.faces))
        pv = part.vertices[:: max(1, len(part.vertices) // 20000)]
        spread = max(0.0, float(cq.signed(pv).max()))  # outside the carved block
    setups = setups_of(plan.cuts) if plan.cuts else []
    setup_of = {c.name: k + 1 for k, g in enumerate(setups) for c in g}
    tol = cell.part.tolerance
    checks = _checks(plan, carved, vp, closed_ok, tol, spread)
    cuts = [{"name": c.name, "kind": c.kind, "what": c.what, "rulings": len(c.lines),
             "closed": c.closed, "keep": c.keep if isinstance(c.keep, str)
             else [round(float(x), 6) for x in c.keep], "setup": setup_of.get(c.name),
             **m.as_dict()} for c, m in zip(plan.cuts, plan.measures, strict=True)]  # fmt: skip
    rough = [c for c in plan.cuts if c.kind == "rough"]
    return {
        "format": FORMAT,
        "cell": str(cell.source),
        "part": {"file": str(part.source), "units": cell.part.units,
                 "repair": cell.part.repair, "repaired": list(part.repairs),
                 "triangles": len(part.faces), "regions": len(plan.regions),
                 "faces": {str(k): v for k, v in sorted(plan.faces.items())}},
        "cuts": cuts,
        "whole": {"part_volume_l": round(vp * 1e3, 5), "carved_volume_l": round(vc * 1e3, 5),
                  "excess": round(vc / vp - 1.0, 5), "largest_distance_mm": round(far * 1e3, 3),
                  "cuts": len(plan.cuts), "exact_cuts": len(plan.cuts) - len(rough),
                  "rough_cuts": len(rough), "setups": len(setups)},
        "baseline": None if vb is None else {
            "what": f"visual hull of {len(plan.baseline)} parallel directions (a foam "
                    "cutter's parallel wire with a turntable), chosen the same way",
            "directions": [[round(float(x), 4) for x in lp.axis] for lp in plan.baseline],
            "carved_volume_l": round(vb * 1e3, 5), "excess": round(vb / vp - 1.0, 5),
            # voxel estimates: null when not made (no roughing loop was chosen)
            "rough_excess_voxel": _ratio(plan.kept_voxel, vp),
            "baseline_excess_voxel": _ratio(plan.baseline_kept_voxel, vp)},
        "carved": None if made is None else made.as_dict(),
        "notes": [f"repaired: {r}" for r in part.repairs] + list(plan.notes)
                 + ([made.note()] if made is not None and made.note() else []),
        "checks": checks,
        "ok": all(c["ok"] for c in checks),
        "timings_s": {k: round(v, 3) for k, v in times.items()},
    }  # fmt: skip


def cell_volume(cell: Cell) -> float:
    """The block's volume [m^3]."""
    return float(np.prod(cell.stock.size))
