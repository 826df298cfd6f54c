"""Commands that meet the robot: export, run (RTDE), the controller emulator, calibrations."""

from __future__ import annotations

import contextlib
from enum import Enum
from pathlib import Path

import typer

from ._common import app, console, err, fail, literal, print_verdict


def say_program_size(path: Path) -> None:
    """Warn about a long URScript program (its header says so too)."""
    for line in path.read_text().splitlines()[:8]:
        if line.strip().startswith("# long program"):
            err.print("warning: " + line.strip()[2:], highlight=False, markup=False)


class ScriptMode(str, Enum):
    """URScript motion command of ``export --format urscript`` (``--mode``)."""
    servoj = "servoj"
    movep = "movep"
    movel = "movel"


class ExportFormat(str, Enum):
    """File format of ``export`` (``--format``)."""
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
    tolerance: float | None = typer.Option(
        None, min=1e-6, help=literal(
            "movel/movep: decimation tolerance at the wire's ends [m] (default a quarter of "
            "--wire-tolerance).")),
    blend: float = typer.Option(0.002, min=0.0, help=literal("movel/movep: blend radius [m].")),
    wire_tolerance: float | None = typer.Option(
        None, min=1e-6, help=literal(
            "movel/movep: the wire's largest distance from the planned wire in the stock [m] "
            "(default: the plan's [cut] wire_tolerance).")),
    force: bool = typer.Option(False, "--force", help="Replace files the export did not "
                               "write (a user's file, a recording) at --out."),
) -> None:
    """Export a trajectory as CSV/JSON/NPZ or a standalone URScript program for the pendant.

    Every program sets the TCP and the payload from the trajectory's metadata.  A movel or
    movep program's motion is generated and measured against the plan (feed, wire) before
    it is written: exit 1, nothing written, when it would not cut as planned.  An export
    replaces only files of the kind it writes (an earlier export): anything else at --out
    (or at a CSV's sidecar) is refused, exit 2, unless --force."""
    from ..export import EXPORT_FORMATS, export_targets, export_trajectory
    from ..export.verify_program import ProgramRefused
    from ..io.trajectory import read_trajectory

    try:
        traj = read_trajectory(trajectory)
        is_script = (fmt and fmt.value == "urscript") or out.suffix in (".script", ".urscript")
        options: dict[str, object] = {}
        if is_script:
            options = {"mode": mode.value, "allow_long": allow_long}
            if mode.value != "servoj":
                options |= {"tolerance": tolerance, "blend": blend,
                            "wire_tolerance": wire_tolerance}  # fmt: skip
        kind = fmt.value if fmt is not None else EXPORT_FORMATS.get(out.suffix.lower())
        targets = export_targets(out, kind) if kind else [out]
        existed = {t for t in targets if t.exists()}
        path = export_trajectory(traj, out, None if fmt is None else fmt.value, force=force,
                                 **options)  # fmt: skip
    except ProgramRefused as exc:
        err.print(f"refused: {exc}", highlight=False, markup=False)
        raise typer.Exit(code=1) from None
    except ValueError as exc:
        raise fail(str(exc)) from None
    if is_script:
        say_program_size(path)
        for line in path.read_text().splitlines()[:12]:
            if line.strip().startswith("# verified"):
                console.print(line.strip()[2:], highlight=False, markup=False)
    for target in targets:
        notes = ([] if target == path else [f"the sidecar of {path.name}"]) + \
            (["replaced an earlier export"] if target in existed else [])  # fmt: skip
        said = f"  ({'; '.join(notes)})" if notes else ""
        console.print(f"wrote {target}{said}", highlight=False, markup=False)


class RunModeName(str, Enum):
    """How ``run`` drives the robot (``--mode``).

    ``forward``, ``servoj`` (or its other name ``stream``) or ``path``."""
    forward = "forward"
    servoj = "servoj"
    stream = "stream"
    path = "path"


@app.command(
    epilog="Example:  ruledrobot run out/demo/trajectory.csv --host 192.168.1.10   "
    "(--dry-run checks without motion; --resume N re-enters the cut at sample N; without "
    "--host a local emulator is used)"
)
def run(
    trajectory: Path = typer.Argument(..., help="Trajectory CSV."),
    host: str | None = typer.Option(
        None, help="Robot controller address; default: an embedded emulator on 127.0.0.42 "
        "(or the next free loopback address when another emulator runs there)."
    ),
    mode: RunModeName = typer.Option(
        RunModeName.forward, help="forward (the samples sent ahead of time to a program that "
        "plays them on the controller's clock: a busy PC changes nothing), servoj or stream "
        "(stream one servoJ per period on this computer's clock) or path (the plan's "
        "movel/movej program at its speeds, verified before motion)."
    ),
    buffer: float = typer.Option(
        0.5, min=0.05, max=5.0, help=literal(
            "forward mode: the longest stall of this computer the motion rides through "
            "unchanged [s]; a longer one stops along the path, heat off.")
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
    wire_tolerance: float | None = typer.Option(
        None, "--wire-tolerance", min=1e-6, help=literal(
            "The largest distance of the wire from the planned wire in the stock [m] (the "
            "run's verdict, the path program's check; default: the plan's [cut] "
            "wire_tolerance).")),
) -> None:
    """Stream a planned trajectory to a UR controller through RTDE (ur_rtde).

    Checks the controller (robot model, period, state) and shows the approach move before
    asking to start; monitors the motion, stops safely, says where and how to resume; records
    the actual trajectory (<name>.run-NNN.csv) and measures it: the run's verdict (the feed and
    the wire in the block, samples skipped in the foam) is printed and written into the
    recording's sidecar. Exit 0 completed and every check holds, 1 refused, stopped or a check
    of the executed cut failed, 2 bad input."""
    import sys

    if not (yes or dry_run or sys.stdin.isatty()):
        raise fail("no terminal to confirm the motion on: pass --yes to start without asking")
    if force:
        err.print("--force: the controller's kinematics are NOT checked against the plan's; "
                  "the wire may miss the cut", style="bold red", highlight=False,
                  markup=False)  # fmt: skip
    result = stream(trajectory, host, yes=yes, mode=mode.value, speed_scale=speed_scale,
                     dry_run=dry_run, start_index=resume or 0, force_kinematics=force,
                     wire_tolerance=wire_tolerance, buffer=buffer)  # fmt: skip
    if not result.ok:
        raise typer.Exit(code=1)


def stream(trajectory: Path, host: str | None, *, yes: bool = False, **options):
    """Run ``trajectory``: the CLI's side of :func:`run_trajectory`.

    Checks table, confirmation, progress bar, where it stopped and the resume command, the
    run's verdict.  A run that completed but whose executed cut broke a check exits 1 here
    (``typer.Exit``), after everything is printed and written.
    """
    from rich.text import Text

    from ..export import ControllerError, run_trajectory
    from ..export.run_report import RunProgress, resume_command
    from ..io.trajectory import read_trajectory
    from ..ursim import EMBEDDED_HOST, embedded_emulator

    try:
        traj = read_trajectory(trajectory)
    except ValueError as exc:
        raise fail(str(exc)) from None
    dry_run = bool(options.get("dry_run"))
    target = host
    emu = None
    shown: list[bool] = []

    def show_plan(plan) -> None:
        shown.append(True)
        where = plan.host or "no controller"
        print_verdict(plan.verdict, f"checks before motion ({trajectory} on {where})")
        for line in plan.describe():
            console.print(Text(f"  {line}"), highlight=False)

    def confirm(plan) -> bool:
        show_plan(plan)
        if yes:
            console.print("  --yes: starting without asking", highlight=False)
            return True
        return typer.confirm("Start the motion?", default=False)

    bar = RunProgress(traj, console)
    try:
        with contextlib.ExitStack() as stack:
            if host is None and not dry_run:
                try:
                    emu = stack.enter_context(embedded_emulator(traj.meta.robot, traj.q[0]))
                except OSError as exc:
                    raise fail(f"the embedded controller emulator cannot start: {exc}") from None
                target = emu.host
                moved = ("" if target == EMBEDDED_HOST else
                         f"{EMBEDDED_HOST} is taken (another emulator runs there?): ")
                console.print(f"no --host: {moved}the embedded MuJoCo-backed controller "
                              f"emulator listens on {target}", highlight=False)  # fmt: skip
            try:
                result = run_trajectory(trajectory, target, traj.meta.robot,
                                        progress=bar.update, confirm=confirm,
                                        **options)  # fmt: skip
            finally:
                bar.stop()
            if emu is not None:
                say_emulator_clock(emu)
    except (ValueError, ControllerError) as exc:
        raise fail(str(exc)) from None
    if not shown and result.verdict is not None:
        from ..export import RunPlan

        show_plan(RunPlan(result.verdict, result.entry, target, options.get("mode", "forward"),
                          traj, options.get("approach_speed", 0.25),
                          options.get("speed_scale", 1.0)))  # fmt: skip
    style = "bold green" if result.completed else "bold red"
    console.print(Text(f"{result.status}: {result.message}", style=style), highlight=False)
    if result.status == "dry_run":
        console.print("  dry run: nothing moved", highlight=False)
    elif result.moved:
        console.print(f"  max deviation actual vs plan: {result.max_deviation:.3g} rad",
                      highlight=False)  # fmt: skip
        if result.samples_skipped:
            console.print(f"  the stream fell behind its schedule by up to "
                          f"{1e3 * result.max_slip:.0f} ms and skipped "
                          f"{result.samples_skipped} samples to keep the plan's timing",
                          highlight=False)  # fmt: skip
    if result.moved and not result.realtime and result.priority:
        err.print(Text(f"  runner: the streaming process ran at {result.priority}: "
                       "a busy machine may delay its commands"), highlight=False)  # fmt: skip
    if result.stop is not None and result.status != "completed":
        console.print(Text(f"  stopped at {result.stop.describe()}"), highlight=False)
        cmd = resume_command(trajectory, host, options.get("mode", "forward"),
                             options.get("speed_scale", 1.0), result.resume_index)  # fmt: skip
        console.print(Text(f"  resume with: {cmd}", style="bold"), highlight=False)
    if result.client:
        err.print(Text(f"  ur_rtde client: {result.client}"), highlight=False)
    if result.run_verdict is not None:
        print_verdict(result.run_verdict, "the executed cut (measured on the recording)")
    if result.actual_path is not None:
        console.print(f"wrote {result.actual_path}  (recording of the actual motion; its "
                      "measures and verdict in the sidecar's \"run\")", highlight=False,
                      markup=False)  # fmt: skip
    if result.status == "completed" and not result.ok:
        raise typer.Exit(code=1)
    return result


def say_emulator_clock(emu) -> None:
    """After a run on the embedded emulator.

    Its clock in one line (on time, or how many periods it ran late to catch up after its host
    stalled), and when it could not run at real-time priority."""
    from rich.text import Text

    try:  # the process-backed emulator calls it stats(), the threaded one stats_summary()
        get = getattr(emu, "stats_summary", None) or emu.stats
        s = get()
    except Exception:  # the emulator is gone: nothing to say
        return
    if not s.get("realtime_clock", 0.0):
        err.print(Text("  emulator: its clock thread ran at normal priority (SCHED_FIFO "
                       "refused: no CAP_SYS_NICE): a busy machine may delay the controller's "
                       "periods"), highlight=False)  # fmt: skip
    if s.get("missed", 0.0):
        console.print(Text(f"  emulator clock: its host woke it late; it ran "
                           f"{s['missed']:.0f} of {s['ticks']:.0f} periods late to catch up "
                           f"(longest stall {s.get('stall_max_ms', 0.0):.1f} ms): the arm "
                           "moved on controller time, the stall was the emulator's, not the "
                           "robot's"), highlight=False)  # fmt: skip
    else:
        console.print(Text(f"  emulator clock: on time ({s['ticks']:.0f} periods, latest "
                           f"{s['lateness_max_ms']:.1f} ms)"), highlight=False)  # fmt: skip
    if s.get("resyncs", 0.0):
        err.print(Text(f"  emulator: its host stalled beyond the catch-up bound "
                       f"{s['resyncs']:.0f} times: controller time jumped"), highlight=False)


#: where ``ruledrobot ursim`` listens without ``--host`` (or the next free loopback address)
DEFAULT_URSIM_HOST = "127.0.0.1"


@app.command(epilog="Example:  ruledrobot ursim --host 127.0.0.2 --model ur5e")
def ursim(
    host: str | None = typer.Option(
        None, help=literal(
            "Address to listen on [default: 127.0.0.1, or the next free loopback address "
            "(127.0.0.2, ...) when it is taken]; a given address that is taken is an error.")),
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
    """Run the controller emulator until Ctrl-C, optionally calibrated and with faults.

    RTDE 30004, dashboard 29999, script 30003, primary 30001, secondary 30002; the faults on
    a timer or on a signal (docs/rtde.md).
    """
    from ..ursim import serve
    from ..ursim.address import address_in_use
    from ..ursim.arm.emulated import emulated_model
    from ..ursim.faults import FaultSchedule, parse_fault

    if physics not in ("kinematic", "mujoco"):
        raise typer.BadParameter(f"expected kinematic or mujoco, got {physics!r}",
                                 param_hint="'--physics'")  # fmt: skip
    try:
        specs = [parse_fault(f) for f in fault]
    except ValueError as exc:
        raise fail(f"--fault: {exc}") from None
    arm = None
    if calibration is not None:
        try:  # a file is read, and another model's calibration refused, here
            arm = emulated_model(model, calibration)
        except ValueError as exc:
            raise fail(f"--calibration: {exc}") from None
    kinematics = ("nominal kinematics" if arm is None or arm.calibration is None
                  else f"calibrated kinematics ({arm.calibration.source})")  # fmt: skip
    schedule = FaultSchedule(specs, on_fire=lambda s: console.print(
        f"fault: {s.describe()}", highlight=False, markup=False))  # fmt: skip

    def ready(emu) -> None:  # printed once the ports are bound, never before
        p = emu.ports
        if emu.host != first:
            console.print(f"{first} is taken (another emulator runs there?): listening on "
                          f"{emu.host} instead", highlight=False, markup=False)  # fmt: skip
        console.print(
            f"UR controller emulator ({model}, {physics}, {kinematics}) listening on {emu.host}: "
            f"RTDE {p['rtde']}, dashboard {p['dashboard']}, script {p['script']}, primary "
            f"{p['primary']}, secondary {p['secondary']}; programs in {emu.programs_dir}; "
            "Ctrl-C to stop", highlight=False, markup=False,
        )  # fmt: skip
        for s in specs:
            console.print(f"scheduled fault: {s.describe()}", highlight=False, markup=False)
        schedule.start(emu)

    options: dict = {} if programs is None else {"programs_dir": str(programs)}
    if physics == "mujoco":
        from ..ursim.arm.physics import MujocoBackend

        options["backend"] = MujocoBackend
    if arm is not None:
        options["calibration"] = arm.calibration
    first = DEFAULT_URSIM_HOST if host is None else host
    try:
        serve(first, model, duration=duration, ready=ready, find_free_host=host is None,
              **options)  # fmt: skip
    except KeyboardInterrupt:
        pass
    except OSError as exc:
        if host is not None and address_in_use(exc):
            raise fail(f"--host {host} is taken (another emulator or controller listens "
                       f"there: {exc}); give another --host, or none to take a free "
                       "loopback address") from None  # fmt: skip
        raise fail(str(exc)) from None
    except ValueError as exc:
        raise fail(str(exc)) from None
    finally:
        schedule.stop()


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
    """Read the controller's calibrated kinematics and write them as a calibration file.

    The kinematics are the controller's KinematicsInfo; the file is for the job's
    ``\\[robot] calibration``.
    """
    from ..export.fetch_calibration import fetch_calibration
    from ..io.calibration import save_calibration

    try:
        cal = fetch_calibration(host, model, timeout=timeout)
        path = save_calibration(out, cal)
    except (ValueError, OSError) as exc:
        raise fail(str(exc)) from None
    _show_calibration(cal)
    console.print(f"wrote {path}", highlight=False, markup=False)


@calibration_app.command("show", epilog="Example:  ruledrobot calibration show robot.calib.json")
def calibration_show(path: Path = typer.Argument(..., help="Calibration file.")) -> None:
    """Print a calibration: model, source, status and its deviations from the nominal arm."""
    from ..io.calibration import load_calibration

    try:
        cal = load_calibration(path)
    except ValueError as exc:
        raise fail(str(exc)) from None
    _show_calibration(cal)


def _show_calibration(cal) -> None:
    import numpy as np

    from ..robot.arm.calibration import calibration_deviations

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


