"""``ruledrobot make``: from a part to robot programs -- carve, plan every setup, export,
view -- and the summary (docs/make.md)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import typer

from ._common import app, console, err, fail, print_verdict
from .carve import CELL_ARGUMENT


@app.command(epilog="Example:  ruledrobot make cell.toml --out out/part   (the cell file: "
             "docs/carve.md; what make writes: docs/make.md)")  # fmt: skip
def make(
    cell: Path = CELL_ARGUMENT,
    out: Path = typer.Option(Path("out/make"), "--out", "-o", help="Output folder."),
) -> None:
    """Make a part.

    Carve it from the block, plan every setup (verified in MuJoCo), write each setup's program
    (cut.script), trajectory and viewer file, and say what to do by hand between setups. Exits
    0 when every setup passes, 1 when one fails (which, and why; no program is left), 2 on bad
    input (the file and field named)."""
    run_make(cell, out)


def run_make(cell: Path | None, out: Path, prepare: Callable[[Path], Path] | None = None) -> None:
    """Run make with progress bars, print what it found.

    Exit 1 when a setup fails, 2 on bad input (``prepare``: the demo's cell, written into the
    folder)."""
    from ..make import make as do_make
    from ..make.progress import MakeBars

    try:
        with MakeBars(console) as bars:
            res = do_make(cell, out, progress=bars, prepare=prepare)
    except ValueError as exc:
        raise fail(str(exc)) from None
    print_make(res)
    if not res.ok:
        raise typer.Exit(code=1)


def _s(v: float | None) -> str:
    return "-" if v is None else f"{v:.1f}"


def _program(prog: dict[str, Any] | None, ok: bool) -> str:
    """The program column: the file and mode; none (stream it); removed (a failed run)."""
    if prog is None:
        return "-"
    if prog["file"]:
        return f"{prog['file']} ({prog['mode']})"
    return "none: stream trajectory.csv" if ok else ("removed" if prog["mode"] else "-")


def print_make(res: Any) -> None:
    """carve's tables, each setup's checks, the summary, what to do by hand, the verdict."""
    from rich.table import Table
    from rich.text import Text

    from ..io.words import counted
    from ..make.summary import failed_checks
    from .carve import print_carve

    print_carve(res.carve)
    for o in res.setups:
        where = res.out / o.setup.folder_name
        if o.verdict is None:
            err.print(Text(f"setup {o.setup.number}: ", style="bold red") + Text(o.refused))
        else:
            print_verdict(o.verdict, f"checks of setup {o.setup.number} ({where})")
    doc = res.document
    table = Table(title=f"make: {counted(doc['carve']['cuts'], 'cut')} in "
                  f"{counted(len(res.setups), 'setup')}",
                  title_justify="left", show_edge=False, pad_edge=False)  # fmt: skip
    for col in ("setup", "cuts", "verdict", "motion s", "cutting s", "program", "why"):
        table.add_column(col, justify="right" if col.endswith(" s") else "left")
    for o, entry in zip(res.setups, doc["setups"], strict=True):
        prog = entry["program"]
        why = ", ".join(c["name"] for c in failed_checks(o))  # the details: the tables above
        table.add_row(str(o.setup.number), ", ".join(o.setup.cuts),
                      Text("PASS", style="green") if o.ok else Text("FAIL", style="bold red"),
                      _s(o.duration_s), _s(o.cut_duration_s),
                      _program(prog, res.ok), Text(why))  # fmt: skip
    console.print(table)
    c = doc["carve"]
    console.print(f"excess material: {100 * c['excess']:.2f} % (the carved block "
                  f"{c['carved_volume_l']:.4f} L for the part's {c['part_volume_l']:.4f} L; "
                  f"{counted(c['exact_cuts'], 'exact cut')}, "
                  f"{counted(c['rough_cuts'], 'roughing loop')})",
                  highlight=False, markup=False)  # fmt: skip
    totals = doc["totals"]
    if totals["duration_s"] is not None:
        console.print(f"robot time: {totals['duration_s']:.1f} s of motion, "
                      f"{totals['cut_duration_s']:.1f} s of it cutting (lead-in to lead-out; "
                      "the rest approach, transits, retract)", highlight=False,
                      markup=False)  # fmt: skip
    for o in res.setups if res.ok else ():
        if o.program is not None and o.program.path is None:
            console.print(f"note: setup {o.setup.number} has no pendant program ({o.program.what}"
                          f"); stream its trajectory: ruledrobot run "
                          f"{res.out / o.setup.folder_name / 'trajectory.csv'} --host ROBOT",
                          highlight=False, markup=False)  # fmt: skip
    for note in res.notes:
        console.print(f"note: {note}", highlight=False, markup=False)
    if res.ok:
        console.print("[bold]by hand[/] (also in setups.txt):")
        for line in res.hand:
            console.print(f"  {line}", highlight=False, markup=False)
    t = doc["timings_s"]
    console.print(f"make took {t['total']:.1f} s (carve {t['carve']:.1f} s); wrote {res.out} "
                  "(make.json, manifest.json)", highlight=False, markup=False)  # fmt: skip
    _verdict_line(res)


def _verdict_line(res: Any) -> None:
    from rich.text import Text

    from ..make.summary import failed_checks

    if res.ok:
        n = len(res.setups)
        run = ", ".join(f"{o.setup.folder_name}/{o.program.path.name}" if o.program.path
                        else f"{o.setup.folder_name}/trajectory.csv (stream it)"
                        for o in res.setups)  # fmt: skip
        console.print(Text(f"make: PASS — {n} setup{'s' if n != 1 else ''}, every check holds; "
                           f"to run: {run}", style="bold green"), highlight=False)  # fmt: skip
        return
    doc = res.document
    if not doc["carve"]["ok"]:
        why = "carve fails: " + ", ".join(doc["carve"]["failed"])
    elif not res.setups:
        why = "carve made no cut"
    else:
        why = "; ".join(f"setup {o.setup.number} fails ("
                        + ", ".join(c["name"] for c in failed_checks(o)) + ")"
                        for o in res.failed)  # fmt: skip
    console.print(Text(f"make: FAIL — {why}; no program or trajectory written", style="bold red"),
                  highlight=False)  # fmt: skip
