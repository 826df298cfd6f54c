"""Planning a job, the pure step: rulings -> passes -> timed motion -> measured trajectory.

:func:`make_plan` writes nothing and runs no simulation; :mod:`.verify` plays the
result in MuJoCo, :mod:`.report.outcome` turns both into the report and the verdict,
:mod:`.report.files` writes the files.  Every number measured here is measured on the
*sampled* joints through forward kinematics (what the controller receives).
"""

from __future__ import annotations

import dataclasses
import hashlib
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from ..geometry.ranges import runs_of
from ..geometry.se3 import transform_points
from ..robot.arm.model import RobotModel
from ..robot.motion.rates import trajectory_limits_report
from ..robot.motion.servo import servo_time_constant, servo_track
from ..robot.motion.trajectory import Heat, Trajectory, model_for, phases_from_labels
from ..robot.tool import BowTool
from ..robot.wire.cut import FeedWindow, WireCut
from ..robot.wire.face import FaceError, FaceTarget
from .cut.clearance import SINGULAR_MIN
from .cut.kerf import face_rulings
from .cut.order import check_cut_order
from .cut.passes import CutPath, cut_paths, job_search
from .cut.wire_geometry import distance_from_rulings
from .cut.wire_pose import SearchOptions
from .job.spec import Job
from .motion.assemble import Motion, PassNotTimed, assemble_motion
from .motion.densify import target_frames
from .motion.heat import heat_schedule
from .motion.timing import TimingFailure
from .motion.transit import TransitFailure, TransitNotFound

__all__ = [
    "SINGULARITY_MARGIN", "Plan", "PlannedMeasures", "SearchOptions", "make_plan",
    "transit_between", "wire_cut", "wire_deviation",
]

#: the verdict's singularity threshold: the wire-pose search's own (one home)
SINGULARITY_MARGIN = SINGULAR_MIN


@dataclass(frozen=True, eq=False)
class PlannedMeasures:
    """Measurements of the planned (sampled) motion, per sample (M,) where arrays."""

    flange: FloatArray = field(repr=False)  # (M, 4, 4) flange poses
    feed: FloatArray = field(repr=False)  # m/s, the cutting speed (NaN outside the stock)
    deviation: FloatArray = field(repr=False)  # m, wire from its target ruling (0 outside)
    ratios: dict = field(repr=False)  # trajectory_limits_report
    position_ratio: float
    singularity_min: float
    collisions: tuple[dict, ...]
    sentences: tuple[str, ...]
    #: ``face_error`` per cut name (:meth:`Trajectory.face_errors` of the planned motion,
    #: computed once: the verdict's figures, report.json's ``predicted_kerf_mm`` and
    #: ``plots.png``'s kerf panel all read these arrays)
    faces: dict[str, FaceError] = field(default_factory=dict, repr=False)
    #: (M,) W/m: the wire's power, the set-points delayed by the heat's lag
    #: (:meth:`Trajectory.wire_power`, what ``faces`` were judged with); None: no heat model
    wire_power: FloatArray | None = field(default=None, repr=False)
    #: ``face_error`` per cut name of the motion as servoj follows it (:func:`_followed_faces`)
    faces_followed: dict[str, FaceError] = field(default_factory=dict, repr=False)


@dataclass(frozen=True, eq=False)
class Plan:
    """A planned job.

    ``motion``/``trajectory``/``measured`` are None when some pass has no feasible wire
    motion (``reasons`` say why), a transit between passes has no clear route
    (``transit_failures`` say which, and what is in the way) or the time law found no usable
    trajectory for a pass (``timing_failures``).
    """

    job: Job
    model: RobotModel = field(repr=False)  # flange, no tool, the job's base
    passes: tuple[CutPath, ...] = field(repr=False)
    motion: Motion | None = field(repr=False)
    trajectory: Trajectory | None = field(repr=False)
    measured: PlannedMeasures | None = field(repr=False)
    reasons: tuple[str, ...]
    notes: tuple[str, ...]
    timings: dict[str, float]
    #: the job's bow, built once for the whole plan (None: build it from ``job.tool``)
    bow: BowTool | None = field(default=None, repr=False)
    #: the job file's bytes as planned, read once (None: a job built in memory, or not read)
    source_bytes: bytes | None = field(default=None, repr=False)
    #: ``{"path", "sha256"}`` of the job file (:func:`job_reference`), hashed once
    job_ref: dict[str, str] | None = field(default=None, repr=False)
    #: the transits no clear route was found for (the plan has no motion then: no move
    #: through the stock, the table or the arm is kept), ``what`` naming the passes
    transit_failures: tuple[TransitFailure, ...] = ()
    #: the passes the time law found no usable trajectory for (an absurd duration, a
    #: stalled path speed), in words: the pass, its rulings, what binds there (no motion)
    timing_failures: tuple[str, ...] = ()

    @property
    def reachable(self) -> bool:
        """Whether every pass has a feasible wire motion and every transit a clear route.

        Then ``motion`` is not None.
        """
        return self.motion is not None


def job_source_bytes(job: Job) -> bytes | None:
    """Return the job file's bytes as loaded: the job file is not read again.

    :func:`~.job.load.load_job` read them; None: a job built in memory, or without its
    bytes.
    """
    return None if job.source is None else job.source_bytes


def job_reference(job: Job | Plan) -> dict[str, str] | None:
    """Return ``{"path", "sha256"}`` of the job file (None for a job built in memory).

    Of a :class:`Plan`, the reference it hashed when it was made.
    """
    if isinstance(job, Plan):
        return job.job_ref if job.job_ref is not None else job_reference(job.job)
    return _reference(job, job_source_bytes(job))


def _reference(job: Job, data: bytes | None) -> dict[str, str] | None:
    """``{"path", "sha256"}`` of the job file's bytes ``data`` (None: none)."""
    return None if data is None else {"path": str(job.source),
                                      "sha256": hashlib.sha256(data).hexdigest()}  # fmt: skip


def wire_deviation(plan: Plan, q: FloatArray) -> FloatArray:
    """Return per sample the distance [m] of the wire from its pass's target ruling.

    Per sample (M,) the distance of the wire's chord ends, with joints ``q`` (M, 6), from
    the target ruling of its pass at the same path parameter — the z axis of the wire's
    frame motion there (the screw geodesic between neighbouring frames); 0 outside the
    stock.  The chord is the planned one (the one model, ``plan.motion.wire``), as points of
    the wire.
    """
    return _deviation_at(plan.model.fk(q), plan.passes, plan.motion)


def _deviation_at(flange: FloatArray, passes: tuple[CutPath, ...], mo: Motion) -> FloatArray:
    """:func:`wire_deviation` from the flange poses (M, 4, 4) of the joints."""
    out = np.zeros(len(flange))
    for k, cp in enumerate(passes):
        rows = np.flatnonzero((mo.pass_of == k) & mo.in_stock)
        if not rows.size:
            continue
        _, target = target_frames(cp, mo.s[rows])
        pts = transform_points(flange[rows], mo.ends[rows])
        out[rows] = distance_from_rulings(pts, target)
    return out


def wire_cut(job: Job, motion: Motion, bow: BowTool | None = None) -> WireCut:
    """Return what the planned trajectory cuts: block, wire and each pass's feed window.

    The sidecar's ``cut``: the block, the wire and per pass the feed window — the pass's
    samples, the cut's feed and tolerance, and where the feed is held (its cut phase less
    the corner stops and slits) — and, for a cut that names the part's side (``keep``), the
    face it must leave (``face_error``'s target: the target rulings' lines and normals,
    the samples on the face), and the job's material.  ``bow``: the job's, when the caller
    built it.
    """
    held_all = motion.surface & ~(False if motion.corner_stop is None else motion.corner_stop)
    feeds, faces = [], []
    for k, cp in enumerate(motion.passes):
        rows = np.flatnonzero(motion.pass_of == k)
        if not rows.size:
            continue
        cut = cp.cut
        mask = np.zeros(len(motion.pass_of), dtype=bool)
        mask[rows] = True
        feeds.append(FeedWindow(cut.name, int(rows[0]), int(rows[-1]) + 1, cut.feed_speed,
                                cut.feed_tolerance, runs_of(held_all & mask),
                                cut.wire_tolerance))  # fmt: skip
        # the face: the surface's own rulings (a lead-in/out or slit that runs in the block
        # to reach a profile inside it cuts waste), the extrapolation too when it is cut on
        # through the block (extend = true)
        a, z = (0, 0) if cut.extend and not cp.closed else cp.extended
        own = np.zeros(len(cp.s), dtype=bool)
        own[a : len(cp.s) - z] = True
        s_lo, s_hi = cp.s[a], cp.s[len(cp.s) - 1 - z]
        on_surface = (motion.s >= s_lo - 1e-9) & (motion.s <= s_hi + 1e-9)
        on_face = runs_of(motion.surface & mask & on_surface)
        if cut.keep is not None and on_face:  # the part's side is known: its face is judged
            lines = face_rulings(cp.target_frames, cp.frames, job.stock, cut.keep, cp.closed,
                                 own)  # fmt: skip
            faces.append(FaceTarget(cut.name, **lines, ranges=on_face, kerf=cut.kerf,
                                    tolerance=cut.tolerance))  # fmt: skip
    bow = BowTool.of(job.tool if bow is None else bow)
    return WireCut(job.stock, bow.wire_length, tuple(feeds), tuple(faces), job.material)


def _bow_outside_cuts(
    job: Job, bow: BowTool, motion: Motion, flange: FloatArray
) -> tuple[tuple[dict, ...], tuple[str, ...]]:
    """The planner's bow model (rods and wire) in the stock where no pass cuts."""
    segs = bow.segments()
    world = transform_points(flange, segs.reshape(6, 3))
    world = world.reshape(-1, 3, 2, 3)
    cutting = motion.pass_of >= 0
    hits = job.stock.segment_hits(world[:, :, 0], world[:, :, 1]).any(axis=1) & ~cutting
    collisions, sentences = [], []
    t, labels = motion.timed.t, motion.labels
    for what, mask in (("the bow", hits),):
        if mask.any():
            k = np.flatnonzero(mask)
            collisions.append({"what": f"{what} vs stock outside the cut",
                               "first_t": float(t[k[0]]), "samples": int(k.size)})  # fmt: skip
            sentences.append(f"{what} (planner's model) is in the stock outside the cut at "
                             f"{k.size} samples from t = {t[k[0]]:.2f} s "
                             f"({labels[k[0]]})")  # fmt: skip
    return tuple(collisions), tuple(sentences)


def _pass_name(passes: list[CutPath], k: int) -> str:
    """Pass ``k`` in words: ``'side'``, or ``'plug' (pass 2 of 2)`` of a cut in passes."""
    same = [i for i, cp in enumerate(passes) if cp.name == passes[k].name]
    name = f"'{passes[k].name}'"
    return name if len(same) == 1 else f"{name} (pass {same.index(k) + 1} of {len(same)})"


def transit_between(job: Job, passes: list[CutPath], failure: TransitFailure) -> str:
    """The passes a failed transit connects, in words: ``"from 'top' to 'side'"``.

    The assembly names a transit by one pass (``to X``, ``into X``: from the last pass,
    or home, to X's entry pose and from it into X; ``from X``: out of X to its exit pose;
    ``home``: back home); the pass is the one of that name whose first (last) joints lie
    nearest the transit's goal (start): a cut of several passes has one name."""
    what = failure.what
    verb, _, name = what.partition(" ")
    start = job.robot.home is not None

    def nearest(q: tuple[float, ...], end: int) -> int:
        ks = [k for k, cp in enumerate(passes) if cp.name == name]
        if not ks or not q:
            return ks[0] if ks else -1
        return min(ks, key=lambda k: float(np.abs(passes[k].motion.q[end] - q).max()))

    if verb in ("to", "into"):
        k = nearest(failure.qb, 0)
        if k < 0:
            return what
        if k == 0 and not start:  # the motion starts at the first pass's entry pose
            return f"into {_pass_name(passes, k)} from its entry pose"
        before = _pass_name(passes, k - 1) if k > 0 else "home"
        how = " (the move from its entry pose into the pass)" if verb == "into" else ""
        return f"from {before} to {_pass_name(passes, k)}{how}"
    if verb == "from":
        k = nearest(failure.qa, -1)
        if k < 0:
            return what
        after = (_pass_name(passes, k + 1) if k + 1 < len(passes)
                 else "home" if start else "the end")  # fmt: skip
        how = " (the move out of the pass to its exit pose)"
        return f"from {_pass_name(passes, k)} to {after}{how}"
    if what == "home" and passes:
        return f"from {_pass_name(passes, len(passes) - 1)} to home"
    return what


def _heat(job: Job, motion: Motion) -> Heat | None:
    h = job.tool.heat
    if h is None:
        return None
    return Heat(h.kind, h.index, h.value, runs_of(motion.heat), h.preheat, h.mode,
                h.full_scale, h.lag)  # fmt: skip


def _followed_faces(trajectory: Trajectory) -> dict[str, FaceError]:
    """``face_error`` per cut of the motion as the controller's servoj follows it.

    The joints through the servo's tracking law, one sample per control period
    (:func:`~ruledrobot.robot.motion.servo.servo_track` with the runs' and programs' default
    ``lookahead`` and ``gain``, :func:`~ruledrobot.robot.motion.servo.servo_time_constant`:
    the emulator's arm), the wire by the trajectory's own kinematics and TCP, judged by the
    one face check.  Where the planned motion turns fast the servo cuts inside the turn:
    a roughing loop's corner planned 0.018 mm from the part's face ran 0.184 mm from it on
    the emulator at lookahead 0.1 s (this predicted 0.230 mm), and 0.046 mm at the default
    0.03 s (this predicts 0.064 mm; docs/kerf.md).  {} when no cut names a face."""
    cut = trajectory.meta.cut
    if cut is None or not cut.faces:
        return {}
    q = servo_track(trajectory.q, trajectory.meta.control_period, servo_time_constant())
    return trajectory.face_errors(cut.measure(trajectory.t, model_for(trajectory.meta).fk(q)))


def make_plan(
    job: Job,
    model: RobotModel | None = None,
    progress: Callable[[str], None] | None = None,
    search: SearchOptions | None = None,
) -> Plan:
    """Plan every cut of ``job`` (no files, no simulation): see the module doc.

    ``search``: the options of every pass's wire-pose search (default: the planner's).

    Each thing once: the job file's bytes are hashed once, the bow and the clearance cell
    are built once, each cut's input rulings (read when the job was loaded) are placed
    once; all are handed down.  No file is opened here."""
    say = progress or (lambda msg: None)
    t0 = time.perf_counter()
    timings: dict[str, float] = {}
    model = job.robot_model() if model is None else model
    data = job_source_bytes(job)
    ref = _reference(job, data)
    bow = BowTool.from_spec(job.tool)
    options = job_search(job, search)
    cell = options.cell(model, bow, job.stock)
    documents = tuple(cut.surface.document() for cut in job.cuts)
    check_cut_order(job, documents)
    passes: list[CutPath] = []
    for cut, doc in zip(job.cuts, documents, strict=True):
        say(f"refining the rulings and choosing the wire motion ({cut.name})"
            if len(job.cuts) > 1 else "refining the rulings and choosing the wire motion")
        passes += cut_paths(job, cut, model, options, cell=cell, document=doc)
    timings["path_s"] = time.perf_counter() - t0
    reasons = tuple(f"{cp.name}: {r}" if len(job.cuts) > 1 else r
                    for cp in passes for r in cp.motion.reasons)  # fmt: skip
    notes = tuple(n for cp in passes for n in cp.notes)
    if not all(cp.feasible for cp in passes):
        return Plan(job, model, tuple(passes), None, None, None, reasons, notes, timings,
                    bow, data, ref)  # fmt: skip
    say("timing the cut")
    t1 = time.perf_counter()
    try:
        motion = assemble_motion(job, model, passes, cell)
    except TransitNotFound as exc:  # no move through stock, table or arm is kept
        timings["timing_s"] = time.perf_counter() - t1
        failure = dataclasses.replace(exc.failure,
                                      what=transit_between(job, passes, exc.failure))
        return Plan(job, model, tuple(passes), None, None, None, reasons, notes, timings,
                    bow, data, ref, (failure,))  # fmt: skip
    except (PassNotTimed, TimingFailure) as exc:  # hours for a loop: a failed plan, not bad input
        timings["timing_s"] = time.perf_counter() - t1
        what = (exc.sentence() if isinstance(exc, PassNotTimed) else
                f"a joint move (approach, transit or retract): {exc}")  # fmt: skip
        return Plan(job, model, tuple(passes), None, None, None, reasons, notes, timings,
                    bow, data, ref, timing_failures=(what,))  # fmt: skip
    passes = list(motion.passes)
    timings["timing_s"] = time.perf_counter() - t1
    say("measuring the planned motion")
    t2 = time.perf_counter()
    timed = motion.timed
    flange = model.fk(timed.q)
    feed = motion.wire.feed
    dev = _deviation_at(flange, tuple(passes), motion)
    collisions, sentences = _bow_outside_cuts(job, bow, motion, flange)
    robot = model.with_tool(bow.wire_frame()).with_base(np.eye(4))
    robot = dataclasses.replace(robot, tool_mass=job.tool.mass, tool_com=bow.inertia()[0])
    trajectory = Trajectory.from_joints(
        timed.t, timed.q, robot, base=job.robot.base, phases=phases_from_labels(motion.labels),
        in_stock=motion.wire.runs(), job=ref, source="ruledrobot plan",
        heat=_heat(job, motion), cut=wire_cut(job, motion, bow),
    )  # fmt: skip
    power = heat_schedule(job, motion)
    if power is not None:
        trajectory = dataclasses.replace(trajectory, heat_power=power)
    cutting = motion.pass_of >= 0
    measured = PlannedMeasures(
        flange=flange, feed=feed, deviation=dev,
        ratios=trajectory_limits_report(timed.t, timed.q, model.max_velocity,
                                        model.max_acceleration),
        position_ratio=model.position_ratio(timed.q),
        singularity_min=float(model.singularity_measure(timed.q[cutting]).min()),
        collisions=collisions, sentences=sentences,
        faces=trajectory.face_errors(motion.wire), wire_power=trajectory.wire_power(),
        faces_followed=_followed_faces(trajectory),
    )  # fmt: skip
    timings["measure_s"] = time.perf_counter() - t2
    return Plan(job, model, tuple(passes), motion, trajectory, measured, reasons,
                notes + motion.notes, timings, bow, data, ref)  # fmt: skip
