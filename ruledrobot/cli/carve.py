"""``ruledrobot carve``: a part (mesh or 3DM) and a block in, the ruled cuts that make it out."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from ._common import app, console, err, fail, literal

#: the cell file argument of ``carve`` and ``make`` (one text for both commands' help)
CELL_ARGUMENT = typer.Argument(..., help=literal(
    "Cell file (.toml): [part] file, units, pose, tolerance, rough_cuts, repair, and the "
    "[stock], [robot], [tool], [cut] of a job (docs/carve.md)."))  # fmt: skip


@app.command(epilog="Example:  ruledrobot carve cell.toml --out out/carve   then  ruledrobot "
             "plan out/carve/job.toml --out out/carve-plan   (docs/carve.md)")  # fmt: skip
def carve(
    cell: Path = CELL_ARGUMENT,
    out: Path = typer.Option(Path("out/carve"), "--out", "-o", help="Output folder."),
) -> None:
    """Turn a part (a closed STL, OBJ, PLY mesh or 3DM model) into the ruled cuts that make it.

    The cuts make it from the block: its ruled faces cut exactly along their own rulings,
    the rest roughed by loops that never enter it (compared with the visual hull of as many
    parallel directions).  Writes job.toml (or setupN/job.toml) with its lines files,
    carve.json, carved.stl and carve.png.  Exits 1 when a check fails, 2 on bad input.
    """
    from ..carve import carve as run_carve

    try:
        with console.status("carving") as status:
            res = run_carve(cell, out, progress=lambda msg: status.update(msg))
    except ValueError as exc:
        raise fail(str(exc)) from None
    print_carve(res.report)
    for name, path in res.files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    if not res.ok:
        raise typer.Exit(code=1)


def print_carve(report: dict[str, Any]) -> None:
    """The cuts and the whole as tables, the checks, and the verdict line."""
    from rich.table import Table
    from rich.text import Text

    from ..io.words import counted

    table = Table(title="cuts (mm)", title_justify="left", show_edge=False, pad_edge=False)
    for col in ("cut", "kind", "rulings", "setup", "face within", "closest", "loosest",
                "gouge", "what"):  # fmt: skip
        table.add_column(col, justify="left" if col in ("cut", "kind", "what") else "right")

    def mm(v) -> str:
        return "-" if v is None else f"{v:.3f}"

    for c in report["cuts"]:
        table.add_row(c["name"], c["kind"], str(c["rulings"]), str(c["setup"]),
                      mm(c["deviation_mm"]), mm(c["closest_mm"]), mm(c["farthest_mm"]),
                      mm(c["gouge_mm"]), c["what"])  # fmt: skip
    console.print(table)
    w, b = report["whole"], report.get("baseline")
    whole = Table(title="the whole", title_justify="left", show_edge=False, pad_edge=False)
    for col in ("", "volume L", "excess %", "largest distance to the part mm"):
        whole.add_column(col, justify="right" if col else "left")
    whole.add_row("part", f"{w['part_volume_l']:.4f}", "", "")
    whole.add_row(f"carved ({counted(w['cuts'], 'cut')}, {counted(w['setups'], 'setup')})",
                  f"{w['carved_volume_l']:.4f}", f"{100 * w['excess']:.2f}",
                  f"{w['largest_distance_mm']:.2f}")  # fmt: skip
    if b:
        whole.add_row(f"visual hull, {len(b['directions'])} parallel directions",
                      f"{b['carved_volume_l']:.4f}", f"{100 * b['excess']:.2f}", "")  # fmt: skip
    console.print(whole)
    reasons = print_faces(report["part"].get("faces", {}))
    for note in report["notes"]:
        if note not in reasons:  # a face's reason is printed with the faces
            console.print(f"note: {note}", highlight=False, markup=False)
    for c in report["checks"]:
        if not c["ok"]:
            value = f" ({c['value_mm']} mm, limit {c['limit_mm']} mm)" if "value_mm" in c else ""
            err.print(Text(f"  {c['name']}: ", style="bold red") + Text(c["what"] + value),
                      highlight=False)  # fmt: skip
    ok = report["ok"]
    failed = [c["name"] for c in report["checks"] if not c["ok"]]
    console.print(Text(f"verdict: {'PASS' if ok else 'FAIL'} — "
                       + ("every check holds" if ok else "failed: " + ", ".join(failed)),
                       style="bold green" if ok else "bold red"), highlight=False)  # fmt: skip


#: faces left to roughing listed by name (the rest counted; all in carve.json)
FACES_LISTED = 8


def print_faces(faces: dict[str, str]) -> set[str]:
    """Print one line of what became of the part's faces (regions), and why for those left.

    For each face left to the roughing loops, why (at most :data:`FACES_LISTED`); the
    reasons printed.
    """
    from ..io.words import counted

    kinds = {"exact": 0, "block face": 0}
    left: list[tuple[str, str]] = []
    for k, v in faces.items():
        if v in kinds:
            kinds[v] += 1
        else:
            left.append((k, v))
    line = f"faces: {kinds['exact']} cut exactly"
    if kinds["block face"]:
        line += f", {counted(kinds['block face'], 'face')} of the block"
    if left:
        line += f", {len(left)} left to the roughing loops:"
    console.print(line, highlight=False, markup=False)
    for k, v in left[:FACES_LISTED]:
        text = v if v.startswith(f"region {k}:") else f"region {k}: {v}"
        console.print(f"  {text}", highlight=False, markup=False)
    if len(left) > FACES_LISTED:
        console.print(f"  and {len(left) - FACES_LISTED} more (carve.json, part.faces)",
                      highlight=False, markup=False)  # fmt: skip
    return {v for _, v in left}
