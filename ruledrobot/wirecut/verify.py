"""Verifying a plan in MuJoCo: the job's cell (arm, bow, stock, table) plays the
trajectory; the wire's deviation and the collisions are measured from the
*simulated* joints."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from .plan import Plan, wire_deviation
from .report.verdict import collision_sentence

__all__ = ["Verification", "verify_plan"]


@dataclass(frozen=True, eq=False)
class Verification:
    """The MuJoCo playback of a plan and what was measured on it.

    ``playback``: :class:`~ruledrobot.sim.PlaybackResult`; ``report``: its report dict;
    ``deviation`` (M,) [m]: the simulated wire from its target ruling (0 outside the
    stock); ``collisions``: the playback's contact events as dicts with their
    ``phase``; ``sentences``: the same in words; ``seconds``: wall time.
    """

    playback: object = field(repr=False)
    report: dict = field(repr=False)
    deviation: FloatArray = field(repr=False)
    collisions: tuple[dict, ...]
    sentences: tuple[str, ...]
    seconds: float


def verify_plan(plan: Plan, progress: Callable[[str], None] | None = None) -> Verification:
    """Play ``plan``'s trajectory in the job's cell (needs a reachable plan)."""
    if plan.motion is None:
        raise ValueError("verify_plan: the plan has no trajectory (a pass is infeasible)")
    from ..sim import Scene, play

    (progress or (lambda msg: None))("verifying in MuJoCo")
    t0 = time.perf_counter()
    timed, labels = plan.motion.timed, plan.motion.labels
    scene = Scene.from_job(plan.job, robot=plan.model, bow=plan.bow)
    pb = play(scene, timed.t, timed.q, timed.qd)
    report = pb.report()
    dev = wire_deviation(plan, pb.q)
    collisions, sentences = [], []
    for c in pb.collisions:
        d = c.as_dict()
        k = int(np.clip(np.searchsorted(timed.t, c.start), 0, len(timed.t) - 1))
        d["phase"] = str(labels[k])
        collisions.append(d)
        sentences.append(collision_sentence(d, d["phase"]))
    return Verification(pb, report, dev, tuple(collisions), tuple(sentences),
                        time.perf_counter() - t0)  # fmt: skip
