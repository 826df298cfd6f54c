"""``ruledrobot kerf``: calibrate the kerf model — the ladder of test cuts, the fit of what
was measured (docs/kerf.md, "Calibration")."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import app, console, err, fail, literal, numbers, print_verdict

kerf_app = typer.Typer(
    help=literal("Calibrate the kerf model: test cuts (ladder), their measurements fitted "
                 "(fit) into the [material] table of a job."),
    no_args_is_help=True,
)
app.add_typer(kerf_app, name="kerf")


@kerf_app.command("ladder", epilog="Example:  ruledrobot kerf ladder job.toml --out ladder "
                  "--speeds 2,4,6,8 --powers 20,35 --full-scale 60   (docs/kerf.md)")
def ladder(
    job: Path = typer.Argument(..., help=literal(
        "Job file: its [stock], [robot] and [tool] (an analog heat output) are kept.")),
    out: Path = typer.Option(Path("out/ladder"), "--out", "-o", help="Output folder."),
    speeds: str | None = typer.Option(None, help=literal(
        "Speeds, mm/s, comma-separated [default: 0.5, 0.75, 1, 1.5 x the job's feed].")),
    powers: str | None = typer.Option(None, help=literal(
        "Wire powers, W per metre of wire, comma-separated [default: 0.6, 1, 1.4 x the job's "
        "heat power, if it gives one].")),
    spacing: float | None = typer.Option(None, help=literal(
        "Distance between the cuts, mm [default: the block's length over the cuts + 1, at "
        "most 20].")),
    full_scale: float | None = typer.Option(None, "--full-scale", help=literal(
        "W/m at the analog output's 1.0 [default: the job's heat full_scale].")),
) -> None:
    """Write a kerf ladder: straight test cuts through the job's block.

    Every speed at every power, one job per power (powerN/job.toml) — with ladder.md
    saying what to measure and where, and measured.csv to fill in.  Exits 2 on bad
    input (nothing written)."""
    from ..kerf import write_ladder

    try:
        v = numbers(speeds, "--speeds")
        res = write_ladder(job, out, None if v is None else [x * 1e-3 for x in v],
                           numbers(powers, "--powers"),
                           spacing=None if spacing is None else spacing * 1e-3,
                           full_scale=full_scale)  # fmt: skip
    except ValueError as exc:
        raise fail(str(exc)) from None
    powers_used = sorted({c.power for c in res.cuts})
    speeds_used = sorted({c.speed * 1e3 for c in res.cuts})
    console.print(f"{len(res.cuts)} cuts, {res.spacing * 1e3:g} mm apart along the block's "
                  f"{res.spacing_axis}: speeds {', '.join(f'{s:g}' for s in speeds_used)} "
                  f"mm/s at powers {', '.join(f'{p:g}' for p in powers_used)} W/m ("
                  f"{res.heat})", highlight=False, markup=False)  # fmt: skip
    for path in res.jobs:
        console.print(f"wrote {path}", highlight=False, markup=False)
    for name in ("ladder.md", "measured.csv"):
        console.print(f"wrote {res.out / name}", highlight=False, markup=False)


@kerf_app.command("fit", epilog="Example:  ruledrobot kerf fit ladder/measured.csv   "
                  "(docs/kerf.md)")
def fit(
    measured: Path = typer.Argument(..., help="CSV with columns speed_mm_s, power_w_m, "
                                    "kerf_mm (and optionally failed)."),
    out: Path | None = typer.Option(None, "--out", "-o", help=literal(
        "Where to write the [material] table [default: material.toml beside the CSV].")),
) -> None:
    """Fit the kerf model to measured test cuts by least squares.

    Each constant with its standard error, every row's residual and its error predicted
    from the other rows, the verdict (is the fit good enough), and the [material] table
    to paste, written only when every check holds.  Exits 1 when a check fails, 2 on bad input."""
    from rich.text import Text

    from ..io.atomic import atomic_write_text
    from ..kerf import fit_kerf, material_text, read_measured
    from ..kerf.fit import FIT_HEADER

    try:
        res = fit_kerf(read_measured(measured))
    except ValueError as exc:
        raise fail(str(exc)) from None
    _print_fit(res)
    for w in res.warnings:
        err.print(Text("warning: ", style="bold yellow") + Text(w), highlight=False)
    for note in res.notes:
        console.print(f"note: {note}", highlight=False, markup=False)
    print_verdict(res.verdict, "is the fit good enough")
    if res.material is None:
        raise typer.Exit(code=1)
    text = material_text(res)
    if not res.verdict.ok:
        console.print("the table the fit gives (not written, not good enough):",
                      highlight=False, markup=False)  # fmt: skip
        console.print(text, highlight=False, markup=False)
        raise typer.Exit(code=1)
    target = out or measured.with_name("material.toml")
    if target.exists() and not target.read_text(errors="replace").startswith(FIT_HEADER):
        # a file of the user's own (a table pasted and edited by hand) is never written over
        raise fail(f"{target}: exists and was not written by kerf fit; give another --out "
                   "or move it")  # fmt: skip
    path = atomic_write_text(target, text)
    console.print(text, highlight=False, markup=False)
    console.print(f"wrote {path}", highlight=False, markup=False)


def _print_fit(res) -> None:
    """The constants with their standard errors, and a row per measurement."""
    import math

    from rich.table import Table

    scale = {"m": (1e3, "mm"), "W/m": (1.0, "W/m")}
    consts = Table(title="constants", title_justify="left", show_edge=False, pad_edge=False)
    for col in ("constant", "value", "standard error", "relative"):
        consts.add_column(col, justify="left" if col == "constant" else "right")
    for c in res.constants:
        k, unit = scale.get(c.unit, (1.0, c.unit))
        if math.isnan(c.value):
            consts.add_row(c.name, "undetermined", "-", "-")
        else:
            consts.add_row(c.name, f"{c.value * k:.4g} {unit}", f"{c.sigma * k:.2g} {unit}",
                           f"{100 * c.relative:.1f} %")  # fmt: skip
    console.print(consts)
    rows = Table(title="rows (mm)", title_justify="left", show_edge=False, pad_edge=False)
    for col in ("line", "speed mm/s", "power W/m", "kerf", "predicted", "residual",
                "held out", "fitted"):  # fmt: skip
        rows.add_column(col, justify="right" if col != "fitted" else "left")
    m = res.measured

    def mm(x: float) -> str:
        return "-" if not math.isfinite(x) else f"{x * 1e3:+.3f}"

    for i in range(m.speed.size):
        used = "yes" if res.used[i] else ("failed" if m.failed[i] else "below threshold")
        rows.add_row(str(m.lines[i]), f"{m.speed[i] * 1e3:g}", f"{m.power[i]:g}",
                     "-" if m.failed[i] else f"{m.kerf[i] * 1e3:.3f}",
                     "-" if not math.isfinite(res.predicted[i]) else
                     f"{res.predicted[i] * 1e3:.3f}",
                     mm(res.residual[i]), mm(res.held_out[i]), used)  # fmt: skip
    console.print(rows)
