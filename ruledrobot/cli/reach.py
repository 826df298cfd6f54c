"""Commands of the cell's layout: the reachability map of a job, and where to put the block."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from ._common import app, console, err, fail

if TYPE_CHECKING:
    from ..place.run import PlaceOutcome


@app.command(epilog="Example:  ruledrobot reach job.toml --out out/reach   (docs/place.md)")
def reach(
    job: Path = typer.Argument(..., help="Cut job file (.toml)."),
    out: Path = typer.Option(Path("out/reach"), "--out", "-o", help="Output folder."),
    rulings: int = typer.Option(240, min=2, help="Rulings per pass on the map."),
    rolls: int = typer.Option(72, min=4, help="Rolls of the wire over a turn."),
    slides: int = typer.Option(1, min=1, max=9, help="Slides of the wire along the ruling: "
                               "the planner's, and more spread over the chord's freedom "
                               "(each cell keeps its best)."),
) -> None:
    """Map where the arm can hold the wire.

    For every ruling of every pass and every roll about the wire, the margin or why not (out of
    reach, joint limit, singularity, which collision). Writes reach.png (one panel per cut, the
    planner's path drawn on it) and reach.json.  Exits 1 when some pass has no feasible path."""
    from ..wirecut.job.load import load_job
    from ..wirecut.reach.report import summary_lines, write_reach

    try:
        spec = load_job(job)
        with console.status("mapping") as status:
            rm, files = write_reach(spec, out, rulings, rolls,
                                    progress=lambda msg: status.update(msg),
                                    slides=slides)  # fmt: skip
    except ValueError as exc:
        raise fail(str(exc)) from None
    for line in summary_lines(rm):
        console.print(line, highlight=False, markup=False)
    for name, path in files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    if not all(pm.feasible for pm in rm.passes):
        raise typer.Exit(code=1)


def _grid(text: str) -> tuple[int, int, int]:
    parts = text.lower().split("x")
    try:
        n = tuple(int(p) for p in parts)
    except ValueError:
        n = ()
    if len(n) != 3 or min(n) < 1 or max(n) > 60:
        raise ValueError(f"--grid: expected NXxNYxNYAW with 1..60 each, e.g. 9x9x9; got {text!r}")
    return n  # type: ignore[return-value]


@app.command(
    epilog="Example:  ruledrobot place job.toml --x 0.3:0.8 --y -0.3:0.3 --yaw -90:90 "
    "--out out/place   (--move robot: search the robot base's move instead; docs/place.md)"
)
def place(
    job: Path = typer.Argument(..., help="Cut job file (.toml)."),
    out: Path = typer.Option(Path("out/place"), "--out", "-o", help="Output folder."),
    x: str | None = typer.Option(None, "--x", help="LOW:HIGH (m): the block centre's x "
                                 "(--move robot: the base's move). Default: the job's +-0.3."),
    y: str | None = typer.Option(None, "--y", help="LOW:HIGH (m), as --x."),
    yaw: str = typer.Option("-90:90", "--yaw", help="LOW:HIGH (degrees): turn of the block "
                            "about the vertical through its centre (or of the robot base)."),
    move: str = typer.Option("stock", "--move", help="stock (the block moves on the table) or "
                             "robot (the block stays, the robot base moves)."),
    grid: str = typer.Option("9x9x9", "--grid", help="Samples along x, y and yaw."),
    refine: int = typer.Option(2, min=0, max=6, help="Refinement steps around the best."),
    turns: str = typer.Option("z90,z180,z270", "--turns", help="Turns allowed between "
                              "setups: z90, z180 (about the vertical), x90, y180 (tipped "
                              "over a bottom edge)...; '' for none."),
    rulings: int = typer.Option(48, min=2, help="Rulings sampled per pass and candidate."),
    rolls: int = typer.Option(36, min=4, help="Rolls of the wire over a turn (36: the "
                              "planner's own grid)."),
    tries: int = typer.Option(3, min=1, help="Candidates verified by the planner at most."),
    verify: bool = typer.Option(True, "--verify/--no-verify",
                                help="Plan the best with MuJoCo verification."),
    workers: int | None = typer.Option(None, "--workers", min=1, help="Score the candidates "
                                       "on a local Dask cluster of this many processes (the "
                                       "batch extra; default: in this process)."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Score the candidates on "
                                         "the workers of this Dask scheduler "
                                         "(tcp://HOST:8786; docs/batch.md)."),
) -> None:
    """Search where to put the block (or the robot) so that the arm reaches every ruling.

    Every ruling of every cut, with the largest worst margin; verify the best with the
    planner and MuJoCo; when no single placement serves a job of several cuts, split it into
    setups and say what to do between them.  Writes job.toml (the placement filled in),
    plan/, margin.png, place.json (and setupN/, setups.txt).  Exits 1 when nothing found
    passes.
    """
    import contextlib
    import functools
    import math

    from ..batch.engine import EngineUnavailable  # Dask itself is imported when used
    from ..place.regions import Region, parse_range, parse_turns
    from ..place.run import run_place
    from ..wirecut.job.load import load_job

    def program(trajectory, folder: Path) -> Path | None:
        """URScript for the pendant (servoj; movep when servoj would be too long; none when
        both are: the trajectory in plan/ is then streamed with ruledrobot run)."""
        from ..export import export_trajectory

        for mode in ("servoj", "movep"):
            try:
                return export_trajectory(trajectory, folder / "cut.script", mode=mode)
            except ValueError as exc:
                why = str(exc)
        err.print(f"note: no cut.script in {folder}: {why}", highlight=False, markup=False)
        return None

    try:
        spec = load_job(job)
        if move not in ("stock", "robot"):
            raise ValueError(f"--move: expected stock or robot, got {move!r}")
        default = Region.around(spec, move)
        region = Region(parse_range(x, "--x") if x is not None else default.x,
                        parse_range(y, "--y") if y is not None else default.y,
                        parse_range(yaw, "--yaw", math.pi / 180.0), move)  # fmt: skip
        with contextlib.ExitStack() as stack:
            scorer = None
            if workers is not None or scheduler is not None:
                from ..batch.engine import Engine
                from ..batch.place import DistributedEvaluator

                eng = stack.enter_context(Engine(workers, scheduler))
                scorer = functools.partial(DistributedEvaluator, engine=eng)
            status = stack.enter_context(console.status("placing"))
            res = run_place(spec, region, out, grid=_grid(grid), refine=refine,
                            turns=parse_turns(turns), tries=tries, rulings=rulings, rolls=rolls,
                            verify=verify, progress=lambda msg: status.update(msg),
                            program=program, scorer=scorer)  # fmt: skip
    except ValueError as exc:
        raise fail(str(exc)) from None
    except EngineUnavailable as exc:  # no Dask, or no scheduler there
        raise fail(str(exc)) from None
    _print_place(res)
    if not res.ok:
        raise typer.Exit(code=1)


def _print_place(res: PlaceOutcome) -> None:
    from rich.table import Table

    from ..io.words import mm

    for line in res.lines:
        console.print(line, highlight=False, markup=False)
    names = [c.name for c in res.result.job.cuts]
    table = Table(title="best placements (worst margin: mm)", title_justify="left",
                  show_edge=False, pad_edge=False)  # fmt: skip
    cols = ("#", "x mm", "y mm", "yaw deg", "turn", "worst", *(names if len(names) > 1 else ()))
    for col in cols:
        table.add_column(col, justify="right")
    for k, c in enumerate(res.result.ranked, start=1):
        p = c.placement
        row = [str(k), mm(p.x), mm(p.y), f"{math.degrees(p.yaw) + 0.0:.1f}",
               p.turn.label, f"{c.margin * 1e3:.1f}"]
        if len(names) > 1:
            row += [f"{m * 1e3:.1f}" for m in c.cut_margins]
        table.add_row(*row)
    console.print(table)
    for step in res.steps:
        console.print(step, highlight=False, markup=False)
    for name, path in res.files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    if not res.ok and res.closing:
        err.print(res.closing, highlight=False, markup=False)



