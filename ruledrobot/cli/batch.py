"""The ``batch`` command: many jobs planned on Dask (``docs/batch.md``)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import app, console, err, fail


@app.command(epilog="Example:  ruledrobot batch 'pieces/*.toml' --out out/pieces --workers 2"
             "     or:  ruledrobot batch jobs.toml --out out/pieces --scheduler "
             "tcp://10.0.0.5:8786")  # fmt: skip
def batch(
    jobs: list[str] = typer.Argument(..., help="Job files (.toml), globs, or job lists "
                                     "(.toml with \\[\\[jobs]] tables, or .json) naming job "
                                     "files with folder names and overrides."),
    out: Path = typer.Option(..., "--out", "-o", help="Output folder: a folder per job, "
                             "batch.json and batch.csv."),
    workers: int | None = typer.Option(None, "--workers", "-w", min=1, help="Worker "
                                       "processes of the local cluster (default: one per "
                                       "core, as memory allows)."),
    scheduler: str | None = typer.Option(None, "--scheduler", help="Address of a running "
                                         "Dask scheduler (tcp://HOST:8786) to plan on "
                                         "instead of a local cluster."),
    force: bool = typer.Option(False, "--force", help="Replan every job, also those whose "
                               "results (same content hash) are already there."),
) -> None:
    """Plan many jobs in parallel, each into its own folder, with a manifest of the results.

    The manifest holds every job's result (feasible, infeasible and why, bad input,
    crashed).

    A rerun keeps the results whose jobs did not change (resume after a crash or a
    Ctrl-C).  Exits 0 when every job is feasible, 1 when some job is not (they are
    listed), 2 on bad input to the batch itself, 130 when stopped by Ctrl-C."""
    from ..batch import BatchInputError, EngineUnavailable, run_batch
    from ..batch.progress import BatchBar, job_line

    bar = BatchBar(console)
    try:
        result = run_batch(jobs, out, workers=workers, scheduler=scheduler, force=force,
                           progress=bar)  # fmt: skip
    except (BatchInputError, EngineUnavailable, ValueError) as exc:
        raise fail(str(exc)) from None
    finally:
        bar.stop()
    counts: dict[str, int] = {}
    for r in result.records:
        counts[r.status] = counts.get(r.status, 0) + 1
    engine = result.engine or {}
    where = (f" on {engine.get('workers')} workers ({engine.get('kind')}, "
             f"{engine.get('scheduler')})" if engine else "")  # fmt: skip
    tally = ", ".join(f"{n} {s}" for s, n in counts.items())
    console.print(f"{len(result.records)} jobs: {tally}; planned {result.planned}, kept "
                  f"{result.kept}{where} in {result.elapsed_s:.1f} s", highlight=False,
                  markup=False)  # fmt: skip
    for r in result.not_feasible:
        err.print(f"  {job_line(r)}", highlight=False, markup=False)
    console.print(f"wrote {result.manifest} and {out / 'batch.csv'}", highlight=False,
                  markup=False)  # fmt: skip
    if result.error:
        err.print(f"stopped: {result.error}", highlight=False, markup=False)
    if result.interrupted:
        err.print("stopped by Ctrl-C: the jobs not planned are 'pending' in batch.json; run "
                  "the same command again (without --force) to plan them", highlight=False,
                  markup=False)  # fmt: skip
    raise typer.Exit(code=result.exit_code)
