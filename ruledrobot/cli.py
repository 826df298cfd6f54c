"""The ``ruledrobot`` command line (typer).

Sub-commands grow with the project; each prints an example in ``--help`` and
says where it wrote its files.  Errors in user input exit with status 2 and a
one-line message (no traceback).
"""

from __future__ import annotations

from enum import Enum
from pathlib import Path

import typer
from rich.console import Console

app = typer.Typer(
    name="ruledrobot",
    help="Robot motion planning on ruled surfaces: refine line sequences, plan, simulate, export.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console(stderr=False, soft_wrap=True)
err = Console(stderr=True, soft_wrap=True)


class AlgorithmName(str, Enum):
    projection = "projection"
    combined = "combined"
    dh = "dh"


class SchemeName(str, Enum):
    chaikin = "chaikin"
    bspline3 = "bspline3"
    four_point = "four_point"
    six_point = "six_point"
    ternary_four_point = "ternary_four_point"


def _fail(message: str) -> typer.Exit:
    """Print a bad-input error literally (no markup: ``[cut]`` stays) and exit 2."""
    from rich.text import Text

    err.print(Text("error: ", style="bold red") + Text(str(message)), highlight=False)
    return typer.Exit(code=2)


def _print_verdict(verdict, title: str) -> None:
    """The table of checks (value, limit, ok) and the verdict line, printed literally."""
    from rich.table import Table
    from rich.text import Text

    table = Table(title=title, title_justify="left", show_edge=False, pad_edge=False)
    for col in ("check", "value", "limit", "ok"):
        table.add_column(col, justify="right" if col in ("value", "limit") else "left")
    for c in verdict.checks:
        mark = (Text("ok", style="green") if c.ok else Text("FAIL", style="bold red")) \
            if c.gating else Text("info", style="dim")
        table.add_row(Text(c.label), Text(c.value_text), Text(c.limit_text), mark)
    console.print(table)
    for c in verdict.failed:
        for line in c.detail.splitlines():
            err.print(Text(f"  {c.name}: ", style="bold red") + Text(line), highlight=False)
    style = "bold green" if verdict.ok else "bold red"
    word = "PASS" if verdict.ok else "FAIL"
    console.print(Text(f"verdict: {word} — {verdict.summary()}", style=style), highlight=False)


@app.command(
    epilog="Example:  ruledrobot refine lines.json --algorithm dh --scheme four_point "
    "--steps 4 --out refined.json --mesh refined.stl"
)
def refine(
    lines_file: Path = typer.Argument(..., help="Lines file (.json or .csv, ruledrobot.lines/1)."),
    out: Path = typer.Option(Path("refined.json"), "--out", "-o", help="Output .json or .csv."),
    algorithm: AlgorithmName = typer.Option(AlgorithmName.dh, help="Refinement algorithm."),
    scheme: SchemeName = typer.Option(SchemeName.four_point, help="Subdivision scheme."),
    steps: int = typer.Option(4, min=0, max=20, help="Number of subdivision steps."),
    closed: bool | None = typer.Option(
        None, "--closed/--open", help="Override the file's closed flag."
    ),
    w: float | None = typer.Option(None, help="four_point shape parameter (default 1/16)."),
    mu: float | None = typer.Option(None, help="ternary_four_point parameter (default 1/11)."),
    mesh: Path | None = typer.Option(
        None, help="Also write a triangle strip of the refined surface (.stl or .obj)."
    ),
    half_width: float = typer.Option(0.1, help="Half width (m) of the --mesh strip."),
) -> None:
    """Refine a discrete ruled surface (projection, combined or dh algorithm)."""
    import numpy as np

    from .algorithms import refine as do_refine
    from .geometry.ruled import RuledSurface
    from .io.lines import read_lines_document, save_lines

    params = {k: v for k, v in (("w", w), ("mu", mu)) if v is not None}
    try:
        doc = read_lines_document(lines_file)
        is_closed = doc.closed if closed is None else closed
        surf = RuledSurface(doc.lines, closed=is_closed)
        res = do_refine(surf, algorithm.value, scheme.value, steps, **params)
        save_lines(
            out,
            res.lines,
            closed=res.closed,
            frames=res.frames if out.suffix.lower() == ".json" else None,
            striction=res.striction if out.suffix.lower() == ".json" else None,
        )
        if mesh is not None:
            from .geometry.mesh import strip_mesh
            from .io.mesh import write_obj, write_stl

            vertices, faces = strip_mesh(res.surface(), half_width=half_width)
            writer = {".stl": write_stl, ".obj": write_obj}.get(mesh.suffix.lower())
            if writer is None:
                raise ValueError(f"{mesh}: mesh must be .stl or .obj")
            writer(mesh, vertices, faces)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    kind = "closed with a flip" if res.flip else ("closed" if res.closed else "open")
    l = res.lines.plucker
    constraint = float(
        max(
            np.abs(np.linalg.norm(l[:, :3], axis=1) - 1).max(),
            np.abs((l[:, :3] * l[:, 3:]).sum(1)).max(),
        )
    )
    console.print(
        f"{len(doc.lines)} -> {len(res.lines)} rulings ({kind}), {algorithm.value}/{scheme.value}, "
        f"{steps} steps; line-manifold residual {constraint:.1e}"
    )
    console.print(f"wrote {out}")
    if mesh is not None:
        console.print(f"wrote {mesh}")


@app.command(epilog="Example:  ruledrobot gallery --out out/gallery")
def gallery(
    out: Path = typer.Option(Path("out/gallery"), "--out", "-o", help="Output folder."),
) -> None:
    """Run the paper's six examples, write PNGs and checks.json; exit 1 if a check fails."""
    from .gallery import run_gallery

    with console.status("gallery") as status:
        result = run_gallery(out, progress=lambda msg: status.update(f"gallery: {msg}"))
    for ex in result["examples"]:
        ok = all(c["passed"] for c in ex["checks"])
        mark = "[green]ok[/]" if ok else "[bold red]FAILED[/]"
        console.print(f"{mark}  {ex['name']}  ({ex['algorithm']}/{ex['scheme']})")
        for c in ex["checks"]:
            console.print(
                f"      {c['name']}: {c['value']:.3g} (limit {c['limit']:.3g})", highlight=False
            )
    console.print(f"wrote {out}/checks.json and {len(result['examples'])} PNGs in {out}")
    if not result["passed"]:
        raise typer.Exit(code=1)


@app.command(epilog="Example:  ruledrobot chain lines.json --out chain.xml")
def chain(
    lines_file: Path = typer.Argument(..., help="Lines file (.json or .csv)."),
    out: Path = typer.Option(Path("chain.xml"), "--out", "-o", help="Output MJCF file."),
) -> None:
    """Write the serial chain whose joint axes are the given lines, as MuJoCo MJCF.

    At zero joint angles the joint axes coincide with the lines (the paper's view of
    a discrete ruled surface as the axes of a robot).
    """
    from .sim import write_chain

    try:
        path = write_chain(lines_file, out)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    console.print(f"wrote {path}")


@app.command(epilog="Example:  ruledrobot simulate out/demo/trajectory.csv --out out/sim --video")
def simulate(
    trajectory: Path = typer.Argument(..., help="Trajectory CSV (t,q1..q6,x,y,z,rx,ry,rz)."),
    out: Path = typer.Option(Path("out/sim"), "--out", "-o", help="Output folder."),
    video: bool = typer.Option(False, "--video/--no-video", help="Render video.mp4 too."),
) -> None:
    """Play a joint trajectory in MuJoCo: collisions, limits, torques, tracking, video.

    Exits 1 when a check fails (collision, joint range, speed, torque)."""
    from .sim import RenderUnavailable
    from .sim import simulate as do_simulate

    try:
        scene, where = _cell_of(trajectory)
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
        raise _fail(str(exc)) from None
    except RenderUnavailable as exc:
        err.print(f"[yellow]no video:[/] {exc}")
        files = {"report": out / "report.json"}
    import json

    from .robot.verdict import Verdict

    report = json.loads((out / "report.json").read_text())
    verdict = Verdict.from_dict(report["verdict"])
    _print_verdict(verdict, f"checks of the playback of {trajectory}")
    for name, path in files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
    if not verdict.ok:
        raise typer.Exit(code=1)


def _say_program_size(path: Path) -> None:
    """Warn about a long URScript program (its header says so too)."""
    for line in path.read_text().splitlines()[:8]:
        if line.strip().startswith("# long program"):
            err.print("warning: " + line.strip()[2:], highlight=False, markup=False)


def _cell_of(trajectory: Path):
    """The scene of the job a trajectory names (its file, or the plan folder's copy
    ``job.toml``, with the same SHA-256), else None: the robot alone on a table."""
    import hashlib

    from .io.trajectory import read_trajectory
    from .robot import model_for

    meta = read_trajectory(trajectory).meta
    ref = meta.job or {}
    for cand in (Path(ref.get("path", "")), trajectory.parent / "job.toml"):
        if ref and cand.is_file() and hashlib.sha256(cand.read_bytes()).hexdigest() == ref.get(
            "sha256"
        ):
            from .sim import Scene
            from .wirecut.job import load_job

            job = load_job(cand)
            robot = model_for(meta).with_base(job.robot.base)
            return Scene.from_job(job, robot=robot), f"the cell of {cand} (arm, bow, stock, table)"
    return None, "the robot on a table (the trajectory names no job file that is at hand)"


class ScriptMode(str, Enum):
    servoj = "servoj"
    movep = "movep"
    movel = "movel"


class ExportFormat(str, Enum):
    csv = "csv"
    json = "json"
    npz = "npz"
    urscript = "urscript"


@app.command(
    epilog="Example:  ruledrobot export out/demo/trajectory.csv --out cut.script --format urscript"
)
def export(
    trajectory: Path = typer.Argument(..., help="Trajectory CSV."),
    out: Path = typer.Option(..., "--out", "-o", help="Output file."),
    fmt: ExportFormat | None = typer.Option(
        None, "--format", "-f", help="csv, json, npz or urscript (default: from the suffix)."
    ),
    mode: ScriptMode = typer.Option(ScriptMode.servoj, help="URScript motion."),
    allow_long: bool = typer.Option(
        False, "--allow-long", help="Write a URScript program beyond the safe size (see docs)."
    ),
) -> None:
    """Export a trajectory as CSV/JSON/NPZ or a standalone URScript program for the pendant.

    Every program sets the TCP and the payload from the trajectory's metadata."""
    from .export import export_trajectory
    from .io.trajectory import read_trajectory

    try:
        traj = read_trajectory(trajectory)
        is_script = (fmt and fmt.value == "urscript") or out.suffix in (".script", ".urscript")
        options = {"mode": mode.value, "allow_long": allow_long} if is_script else {}
        path = export_trajectory(traj, out, None if fmt is None else fmt.value, **options)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    if is_script:
        _say_program_size(path)
    console.print(f"wrote {path}")


class RunModeName(str, Enum):
    servoj = "servoj"
    path = "path"


@app.command(
    epilog="Example:  ruledrobot run out/demo/trajectory.csv --host 192.168.1.10   "
    "(--dry-run checks without motion; --resume N re-enters the cut at sample N; without "
    "--host a local emulator is used)"
)
def run(
    trajectory: Path = typer.Argument(..., help="Trajectory CSV."),
    host: str | None = typer.Option(
        None, help="Robot controller address; default: an embedded emulator on 127.0.0.42."
    ),
    mode: RunModeName = typer.Option(
        RunModeName.servoj, help="servoj (stream one servoJ per period) or path (moveL path)."
    ),
    speed_scale: float = typer.Option(1.0, min=0.01, max=1.0, help="Slow the whole run down."),
    resume: int | None = typer.Option(
        None, "--resume", min=0, help="Re-enter the cut at sample N (printed when a run stops)."
    ),
    yes: bool = typer.Option(False, "--yes", "-y", help="Start without asking (scripts)."),
    dry_run: bool = typer.Option(False, "--dry-run", help="Check everything, move nothing."),
    force: bool = typer.Option(
        False, "--force", help="Run although the controller's kinematics differ from the plan's."
    ),
) -> None:
    """Stream a planned trajectory to a UR controller through RTDE (ur_rtde): checks the
    controller (robot model, period, state) and shows the approach move before asking to
    start; monitors the motion, stops safely, says where and how to resume; records the
    actual trajectory (<name>.run-NNN.csv).  Exit 0 completed, 1 refused or stopped, 2 bad
    input."""
    import sys

    if not (yes or dry_run or sys.stdin.isatty()):
        raise _fail("no terminal to confirm the motion on: pass --yes to start without asking")
    if force:
        err.print("--force: the controller's kinematics are NOT checked against the plan's; "
                  "the wire may miss the cut", style="bold red", highlight=False,
                  markup=False)  # fmt: skip
    result = _stream(trajectory, host, yes=yes, mode=mode.value, speed_scale=speed_scale,
                     dry_run=dry_run, start_index=resume or 0,
                     force_kinematics=force)  # fmt: skip
    if not result.completed or (result.verdict is not None and not result.verdict.ok):
        raise typer.Exit(code=1)


def _stream(trajectory: Path, host: str | None, *, yes: bool = False, **options):
    """Run ``trajectory`` (the CLI's side of :func:`run_trajectory`): checks table,
    confirmation, progress bar, where it stopped and the resume command."""
    from rich.text import Text

    from .export import ControllerError, Emulator, run_trajectory
    from .export.run_report import RunProgress, resume_command
    from .io.trajectory import read_trajectory

    try:
        traj = read_trajectory(trajectory)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    dry_run = bool(options.get("dry_run"))
    target = host
    shown: list[bool] = []

    def show_plan(plan) -> None:
        shown.append(True)
        where = plan.host or "no controller"
        _print_verdict(plan.verdict, f"checks before motion ({trajectory} on {where})")
        for line in plan.describe():
            console.print(Text(f"  {line}"), highlight=False)

    def confirm(plan) -> bool:
        show_plan(plan)
        if yes:
            console.print("  --yes: starting without asking", highlight=False)
            return True
        return typer.confirm("Start the motion?", default=False)

    bar = RunProgress(traj, console)
    emulator = None
    try:
        if host is None and not dry_run:
            target = "127.0.0.42"
            console.print(f"no --host: starting the embedded MuJoCo-backed controller emulator "
                          f"on {target}")  # fmt: skip
            from .export.emulator.physics import MujocoBackend

            emulator = Emulator(target, traj.meta.robot, q0=traj.q[0], backend=MujocoBackend)
            emulator.start()
        try:
            result = run_trajectory(trajectory, target, traj.meta.robot, progress=bar.update,
                                    confirm=confirm, **options)  # fmt: skip
        finally:
            bar.stop()
    except (ValueError, ControllerError) as exc:
        raise _fail(str(exc)) from None
    finally:
        if emulator is not None:
            emulator.close()
    if not shown and result.verdict is not None:
        from .export import RunPlan

        show_plan(RunPlan(result.verdict, result.entry, target, options.get("mode", "servoj"),
                          traj, options.get("approach_speed", 0.25),
                          options.get("speed_scale", 1.0)))  # fmt: skip
    style = "bold green" if result.completed else "bold red"
    console.print(Text(f"{result.status}: {result.message}", style=style), highlight=False)
    if result.status == "dry_run":
        console.print("  dry run: nothing moved", highlight=False)
    elif result.moved:
        console.print(f"  max deviation actual vs plan: {result.max_deviation:.3g} rad",
                      highlight=False)  # fmt: skip
    if result.stop is not None and result.status != "completed":
        console.print(Text(f"  stopped at {result.stop.describe()}"), highlight=False)
        cmd = resume_command(trajectory, host, options.get("mode", "servoj"),
                             options.get("speed_scale", 1.0), result.resume_index)  # fmt: skip
        console.print(Text(f"  resume with: {cmd}", style="bold"), highlight=False)
    if result.client:
        err.print(Text(f"  ur_rtde client: {result.client}"), highlight=False)
    if result.actual_path is not None:
        console.print(f"wrote {result.actual_path}  (recording of the actual motion)",
                      highlight=False, markup=False)  # fmt: skip
    return result


@app.command(epilog="Example:  ruledrobot ursim --host 127.0.0.2 --model ur5e")
def ursim(
    host: str = typer.Option("127.0.0.1", help="Address to listen on (loopback by default)."),
    model: str = typer.Option("ur5e", help="Robot model."),
    programs: Path | None = typer.Option(
        None, help="Folder the dashboard's `load` serves programs from (default: an empty one)."
    ),
    duration: float | None = typer.Option(
        None, min=0.0, help="Stop after this many seconds (default: run until Ctrl-C)."
    ),
    fault: list[str] = typer.Option(
        [],
        "--fault",
        help="KIND@WHEN[:ARG], repeatable: KIND protective_stop, emergency_stop, drop, freeze, "
        "slow, clear; WHEN seconds after start (5s, 500ms) or SIGUSR1/SIGUSR2; ARG seconds "
        "(drop: refuse new connections, freeze: how long, slow: the delay). E.g. --fault "
        "protective_stop@5s --fault freeze@10s:3s --fault clear@SIGUSR2",
    ),
    physics: str = typer.Option(
        "kinematic", help="The arm behind the controller: kinematic, or mujoco (simulated)."
    ),
    calibration: str | None = typer.Option(
        None,
        help="The robot's factory calibration: a ruledrobot.calibration/1 file, or random:SEED "
        "(a seeded realistic one).  The emulator then serves its KinematicsInfo on 30001/30002 "
        "and uses the calibrated kinematics for everything (default: nominal).",
    ),
) -> None:
    """Run the controller emulator (RTDE 30004, dashboard 29999, script 30003, primary 30001,
    secondary 30002) until Ctrl-C, optionally calibrated and with faults on a timer or on a
    signal (docs/rtde.md)."""
    from .export import serve
    from .export.emulator.faults import FaultSchedule, parse_fault
    from .export.emulator.server import emulated_model

    if physics not in ("kinematic", "mujoco"):
        raise typer.BadParameter(f"expected kinematic or mujoco, got {physics!r}",
                                 param_hint="'--physics'")  # fmt: skip
    try:
        specs = [parse_fault(f) for f in fault]
    except ValueError as exc:
        raise _fail(f"--fault: {exc}") from None
    arm = None
    if calibration is not None:
        from .robot import random_calibration

        try:
            if calibration.startswith("random:"):
                seed_text = calibration[len("random:") :]
                if not seed_text.isdigit():
                    raise ValueError(f"random:SEED needs a seed >= 0, got {seed_text!r}")
                arm = emulated_model(model, random_calibration(model, int(seed_text)))
            else:  # the file is read, and another model's calibration refused, here
                arm = emulated_model(model, calibration)
        except ValueError as exc:
            raise _fail(f"--calibration: {exc}") from None
    kinematics = ("nominal kinematics" if arm is None or arm.calibration is None
                  else f"calibrated kinematics ({arm.calibration.source})")  # fmt: skip
    schedule = FaultSchedule(specs, on_fire=lambda s: console.print(
        f"fault: {s.describe()}", highlight=False, markup=False))  # fmt: skip

    def ready(emu) -> None:  # printed once the ports are bound, never before
        p = emu.ports
        console.print(
            f"UR controller emulator ({model}, {physics}, {kinematics}) listening on {host}: "
            f"RTDE {p['rtde']}, dashboard {p['dashboard']}, script {p['script']}, primary "
            f"{p['primary']}, secondary {p['secondary']}; programs in {emu.programs_dir}; "
            "Ctrl-C to stop", highlight=False, markup=False,
        )  # fmt: skip
        for s in specs:
            console.print(f"scheduled fault: {s.describe()}", highlight=False, markup=False)
        schedule.start(emu)

    options: dict = {} if programs is None else {"programs_dir": str(programs)}
    if physics == "mujoco":
        from .export.emulator.physics import MujocoBackend

        options["backend"] = MujocoBackend
    if arm is not None:
        options["calibration"] = arm.calibration
    try:
        serve(host, model, duration=duration, ready=ready, **options)
    except KeyboardInterrupt:
        pass
    except (ValueError, OSError) as exc:
        raise _fail(str(exc)) from None
    finally:
        schedule.stop()


def _run_plan(job_path: Path, out: Path, video: bool = False):
    """Plan a job file into ``out``; prints the table of checks and the verdict.

    Exit 2 on bad input (nothing written), 1 when a check fails (report and plots
    written, no trajectory); returns the :class:`~ruledrobot.wirecut.planner.PlanResult`.
    """
    from .wirecut.job import load_job
    from .wirecut.planner import plan as do_plan

    try:
        job = load_job(job_path)
        with console.status("planning") as status:
            result = do_plan(
                job, out, progress=lambda msg: status.update(f"planning: {msg}"), video=video
            )
    except ValueError as exc:
        raise _fail(str(exc)) from None
    for note in result.report.get("notes", []):
        err.print(f"note: {note}", highlight=False, markup=False)
    _print_verdict(result.verdict, f"checks of {job_path}")
    for name, path in result.files.items():
        console.print(f"wrote {path}  ({name})", highlight=False, markup=False)
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
    """Plan a hot-wire cut: refine, choose the wire motion, time it, verify it in MuJoCo,
    write the trajectory.  Exits with status 1 (and the reasons) when infeasible."""
    try:
        _run_plan(job, out, video=video)
    except typer.Exit as stop:
        if view and stop.exit_code == 1:  # a failed plan is worth a look too
            _view(out)
        raise
    if view:
        _view(out)


def _view(folder: Path, export: Path | None = None, **options) -> None:
    """Serve the viewer of a plan folder until Ctrl-C, or write its static export; exit 2
    on a folder that is not a plan folder, a refused address or a missing viewer extra."""
    from .view import ViewerUnavailable, export_html, serve

    try:
        if export is not None:
            path = export_html(folder, export)
            console.print(f"wrote {path}  ({path.stat().st_size / 1e6:.1f} MB, opens in a "
                          "browser with no Python and no network)", highlight=False,
                          markup=False)  # fmt: skip
            return
        serve(folder, ready=lambda srv: console.print(
            f"viewer of {folder} at {srv.url}  (open it in a browser; Ctrl-C stops)",
            highlight=False, markup=False), **options)  # fmt: skip
    except (ValueError, ViewerUnavailable, OSError) as exc:
        raise _fail(str(exc)) from None


@app.command(epilog="Example:  ruledrobot view out/cut     or:  ruledrobot view out/cut "
             "--export scene.html")
def view(
    folder: Path = typer.Argument(..., help="Plan folder (what `ruledrobot plan` writes)."),
    export: Path | None = typer.Option(None, "--export", help="Write one self-contained HTML "
                                       "file of the scene instead of serving it."),
    host: str = typer.Option("127.0.0.1", help="Address to serve on (loopback only, unless "
                             "--allow-remote)."),
    port: int = typer.Option(8080, min=0, max=65535, help="Port (0: any free port)."),
    allow_remote: bool = typer.Option(False, "--allow-remote", help="Serve on a non-loopback "
                                      "address (the viewer has no authentication)."),
    duration: float | None = typer.Option(None, min=0.0, help="Stop after this many seconds "
                                          "(default: run until Ctrl-C)."),
) -> None:
    """Show a plan folder in the browser: the arm, bow and wire moving through the stock,
    the cut surface, the rulings, a timeline to play and scrub, phase and live figures,
    collisions and near misses, the table of checks.  Never plans anything."""
    _view(folder, export, host=host, port=port, allow_remote=allow_remote, duration=duration)


@app.command(epilog="Example:  ruledrobot demo --out out/demo")
def demo(
    out: Path = typer.Option(Path("out/demo"), "--out", "-o", help="Output folder."),
    video: bool = typer.Option(True, "--video/--no-video", help="Render video.mp4 too."),
    stream: bool = typer.Option(
        True, "--stream/--no-stream", help="Stream the cut to the embedded RTDE emulator."
    ),
) -> None:
    """Run the whole chain on the built-in example (a hyperbolic paraboloid cut in foam):
    refine, plan, time, verify in MuJoCo, render a video, export URScript, and stream
    the cut through ur_rtde to the embedded controller emulator."""
    import tempfile

    from .export import export_trajectory
    from .wirecut.demo import DEMO_JOB

    console.print("[bold]ruledrobot demo[/]: hyperbolic paraboloid through a foam block, UR5e")
    with tempfile.TemporaryDirectory() as tmp:
        job_path = Path(tmp) / "job.toml"
        job_path.write_text(DEMO_JOB, encoding="utf-8")
        result = _run_plan(job_path, out, video=video)
    traj_path = out / "trajectory.csv"
    try:
        script = export_trajectory(result.trajectory, out / "cut.script")
    except ValueError as exc:
        raise _fail(str(exc)) from None
    console.print(f"wrote {script}  (URScript for the teach pendant; streaming is the route for "
                  "long cuts: docs/rtde.md)", highlight=False, markup=False)  # fmt: skip
    _say_program_size(script)
    if stream:
        res = _stream(traj_path, None, yes=True)
        if res.status != "completed":
            raise typer.Exit(code=1)
    console.print(f"job file: {out / 'job.toml'} (edit it and run: ruledrobot plan)",
                  highlight=False, markup=False)  # fmt: skip


calibration_app = typer.Typer(
    help="A robot's own kinematics: fetch it from a controller, show a calibration file.",
    no_args_is_help=True,
)
app.add_typer(calibration_app, name="calibration")


@calibration_app.command(
    "fetch",
    epilog="Example:  ruledrobot calibration fetch --host 192.168.1.10 --out robot.calib.json",
)
def calibration_fetch(
    host: str = typer.Option(..., help="Controller address (primary interface port 30001)."),
    out: Path = typer.Option(Path("robot.calib.json"), "--out", "-o", help="Calibration file."),
    model: str | None = typer.Option(None, help="Robot model; default: ask the dashboard."),
    timeout: float = typer.Option(5.0, min=0.5, help="Give up after this many seconds."),
) -> None:
    """Read the controller's calibrated kinematics (KinematicsInfo) and write them as a
    calibration file for the job's ``[robot] calibration``."""
    from .export.fetch_calibration import fetch_calibration
    from .robot.calibration import save_calibration

    try:
        cal = fetch_calibration(host, model, timeout=timeout)
        path = save_calibration(out, cal)
    except (ValueError, OSError) as exc:
        raise _fail(str(exc)) from None
    _show_calibration(cal)
    console.print(f"wrote {path}", highlight=False, markup=False)


@calibration_app.command("show", epilog="Example:  ruledrobot calibration show robot.calib.json")
def calibration_show(path: Path = typer.Argument(..., help="Calibration file.")) -> None:
    """Print a calibration: model, source, status and its deviations from the nominal arm."""
    from .robot.calibration import load_calibration

    try:
        cal = load_calibration(path)
    except ValueError as exc:
        raise _fail(str(exc)) from None
    _show_calibration(cal)


def _show_calibration(cal) -> None:
    import numpy as np

    from .robot.calibration import calibration_deviations

    dev = calibration_deviations(cal)
    lines = [repr(cal)]
    if "axis_tilt" in dev:
        lines += [
            "  joint axes tilted (mrad): " + " ".join(f"{1e3 * v:.2f}" for v in dev["axis_tilt"]),
            "  joint axes moved (mm):    " + " ".join(f"{1e3 * v:.2f}" for v in dev["axis_offset"]),
            f"  flange at q = 0: {1e3 * dev['flange_position']:.2f} mm and "
            f"{1e3 * dev['flange_rotation']:.2f} mrad from the nominal arm",
            f"  d2 + d3 + d4 - nominal: {1e3 * dev['d_sum']:.3f} mm; theta2 + theta3 + theta4: "
            f"{1e3 * dev['theta_sum']:.3f} mrad",
        ]
    lines.append("  effective DH [theta_offset, a, d, alpha] per joint:")
    lines += [f"    {k + 1}: " + np.array2string(r, precision=9) for k, r in enumerate(cal.dh())]
    for line in lines:
        console.print(line, highlight=False, markup=False)


def main() -> None:
    """Console-script entry point."""
    from .sim import configure_gl

    configure_gl()  # choose EGL/OSMesa before anything imports MuJoCo
    app()


if __name__ == "__main__":  # pragma: no cover
    main()
