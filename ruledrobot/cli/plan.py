"""Commands of the cut planner: plan a job, play a trajectory in MuJoCo, the demo."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import app, console, err, fail, literal, print_verdict


@app.command(epilog="Example:  ruledrobot simulate out/demo/trajectory.csv --out out/sim --video")
def simulate(
    trajectory: Path = typer.Argument(..., help="Trajectory CSV (t,q1..q6,x,y,z,rx,ry,rz)."),
    out: Path = typer.Option(Path("out/sim"), "--out", "-o", help="Output folder."),
    video: bool = typer.Option(False, "--video/--no-video", help="Render video.mp4 too."),
) -> None:
    """Play a joint trajectory in MuJoCo: collisions, limits, torques, tracking, video.

    Exits 1 when a check fails (collision, joint range, speed, torque)."""
    from ..sim import RenderUnavailable
    from ..sim import simulate as do_simulate
    from ..wirecut.job.scene import scene_of_trajectory

    try:
        scene, where = scene_of_trajectory(trajectory)
        console.print(f"scene: {where}", highlight=False, markup=False)
        with console.status("simulating") as status:
            files = do_simulate(
                trajectory,
                out,
                model_or_scene=scene,
                video=video,
                progress=lambda f, stage: status.update(f"{stage}: {100 * f:.0f} %"),
            )
    except ValueError as exc:
        raise fail(str(exc)) from None
    except RenderUnavailable as exc:
        err.print(f"[yellow]no video:[/] {exc}")
        files = {"report": out / "report.json"}
    import json

    from ..robot.verdict import Verdict

    report = json.loads((out / "report.json").read_text())
    verdict = Verdict.from_dict(report["verdict"])
    print_verdict(verdict, f"checks of the playback of {trajectory}")
    for name, path in files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    if not verdict.ok:
        raise typer.Exit(code=1)


def _run_plan(job_path: Path, out: Path, video: bool = False):
    """Plan a job file into ``out``; prints the table of checks and the verdict.

    Exit 2 on bad input (nothing written), 1 when a check fails (report and plots
    written, no trajectory); returns the :class:`~ruledrobot.wirecut.planner.PlanResult`.
    """
    from ..wirecut.job.load import load_job
    from ..wirecut.planner import plan as do_plan

    try:
        job = load_job(job_path)
        with console.status("planning") as status:
            result = do_plan(
                job, out, progress=lambda msg: status.update(f"planning: {msg}"), video=video
            )
    except ValueError as exc:
        raise fail(str(exc)) from None
    for note in result.report.get("notes", []):
        err.print(f"note: {note}", highlight=False, markup=False)
    print_verdict(result.verdict, f"checks of {job_path}")
    for name, path in result.files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    for path in result.kept:
        console.print(f"kept {path}  (a recording of an earlier run)", highlight=False,
                      markup=False)  # fmt: skip
    if not result.feasible:
        err.print(f"no trajectory written: the plan fails ({out / 'report.json'} says why)",
                  highlight=False, markup=False)  # fmt: skip
        raise typer.Exit(code=1)
    return result


@app.command(epilog="Example:  ruledrobot plan job.toml --out out/cut   (job format: README)")
def plan(
    job: Path = typer.Argument(..., help="Cut job file (.toml)."),
    out: Path = typer.Option(Path("out/plan"), "--out", "-o", help="Output folder."),
    video: bool = typer.Option(False, "--video/--no-video", help="Render video.mp4 too."),
    view: bool = typer.Option(False, "--view", help="Then show it in the browser viewer "
                              "(ruledrobot view OUT, on 127.0.0.1:8080; Ctrl-C stops)."),
) -> None:
    """Plan a hot-wire cut.

    Refine, choose the wire motion, time it, verify it in MuJoCo, write the trajectory. Exits
    with status 1 (and the reasons) when infeasible."""
    from .view import show

    try:
        _run_plan(job, out, video=video)
    except typer.Exit as stop:
        if view and stop.exit_code == 1:  # a failed plan is worth a look too
            show(out)
        raise
    if view:
        show(out)


@app.command(epilog="Example:  ruledrobot demo --out out/demo     or:  ruledrobot demo --part"
             "     or:  ruledrobot demo --carve")
def demo(
    out: Path | None = typer.Option(None, "--out", "-o",
                                    help=literal("Output folder [default: out/demo, out/part].")),
    part: bool = typer.Option(False, "--part", help="The part demo: three cuts (one all the "
                              "way round), kerf compensated, the wire's heat switched."),
    carve: bool = typer.Option(False, "--carve", help="The carve demo: a hyperboloid column "
                               "made from its closed form and made into programs (ruledrobot "
                               "make: carved, each setup planned, cut.script, the viewer); no "
                               "video or streaming."),
    video: bool = typer.Option(True, "--video/--no-video", help="Render video.mp4 too."),
    stream: bool = typer.Option(
        True, "--stream/--no-stream", help="Stream the cut to the embedded RTDE emulator."
    ),
) -> None:
    """Run the whole chain on a built-in example, from refining to streaming the cut.

    A hyperbolic paraboloid cut in foam; with --part, a part of three cuts: refine, plan,
    time, verify in MuJoCo, render a video, export URScript, and stream the cut through
    ur_rtde to the embedded controller emulator.
    """
    from ..export import export_trajectory
    from ..export.urscript import MAX_MOTION_LINES
    from ..io.atomic import atomic_write_text
    from ..io.outdir import check_replaceable
    from ..wirecut.job.demo import DEMO_JOB, PART_JOB
    from .robot import say_program_size
    from .robot import stream as stream_run

    if carve:
        _demo_carve(out if out is not None else Path("out/carve-demo"))
        return
    out = out if out is not None else Path("out/part" if part else "out/demo")
    if part:
        console.print("[bold]ruledrobot demo --part[/]: a foam plug in three cuts (saddle top, "
                      "twisted side, all the way round), kerf compensated, heat switched, UR5e")
    else:
        console.print("[bold]ruledrobot demo[/]: hyperbolic paraboloid through a foam block, UR5e")
    # the job file lives in the output folder (the plan keeps it there as job.toml), so the
    # reports name a file that exists; written only where a plan may write
    try:
        check_replaceable(out)
        job_path = atomic_write_text(out / "job.toml", PART_JOB if part else DEMO_JOB)
    except (OSError, ValueError) as exc:
        raise fail(str(exc)) from None
    result = _run_plan(job_path, out, video=video)
    traj_path = out / "trajectory.csv"
    mode = "servoj" if result.trajectory.n <= MAX_MOTION_LINES else "movep"
    try:
        script = export_trajectory(result.trajectory, out / "cut.script", mode=mode)
    except ValueError as exc:
        raise fail(str(exc)) from None
    console.print(f"wrote {script}  (URScript for the teach pendant, mode {mode}; streaming is "
                  "the route for long cuts: docs/rtde.md)", highlight=False,
                  markup=False)  # fmt: skip
    say_program_size(script)
    if stream:
        res = stream_run(traj_path, None, yes=True)
        if res.status != "completed":
            raise typer.Exit(code=1)
    console.print(f"job file: {out / 'job.toml'} (edit it and run: ruledrobot plan)",
                  highlight=False, markup=False)  # fmt: skip


def _demo_carve(out: Path) -> None:
    """``demo --carve``: make's demo -- the column's STL and cell written into ``out/part``
    and made into ``out`` (carve, plan every setup, programs, viewer; docs/make.md).  Exit
    1 when carve or a setup fails, 2 on bad input."""
    from ..make.demo import demo_cell
    from .make import run_make

    console.print("[bold]ruledrobot demo --carve[/]: a hyperboloid column from its closed form, "
                  "carved from the foam block, planned and made into programs (ruledrobot "
                  "make), UR5e")  # fmt: skip
    run_make(None, out, prepare=demo_cell)
