"""Whether the arm can make a cut where it stands: the planner's own first stage, alone.

:func:`cut_reasons` runs what :func:`ruledrobot.wirecut.plan` runs first for each cut —
the refinement, the kerf offset and the wire-pose search (:mod:`.wire_pose`: reach,
IK branch continuity with the joint steps between rulings, singularity, the clearance
of arm, bow and wire against the stock, the table and the arm itself) — and says, per
cut, why no pass was found ("" when every pass of the cut has a motion), or why the
kerf offset cannot hold the kept surface (the verdict's ``kept_surface`` check, on the
offset's own error and the cut's ``wire_tolerance``).  One model:
carve chooses its cuts with it (docs/carve.md, "Cuts chosen with the robot"), the plan
judges them with it.  It does not time the motion (the feed is the time law's, in the
plan).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .passes import cut_paths, job_search

if TYPE_CHECKING:
    from ...robot.arm.model import RobotModel
    from ..job.spec import Job

__all__ = ["cut_reasons"]


def cut_reasons(job: Job, model: RobotModel | None = None,
                names: tuple[str, ...] | None = None) -> dict[str, str]:  # fmt: skip
    """Why the planner's wire-pose search finds no motion for each cut of ``job``.

    Per cut (or those ``names``): "" when it finds one for every pass of the cut; a
    cut the planner refuses outright (a ValueError: no ruling near the block, a
    surface short of it) gives the refusal's words."""
    model = job.robot_model() if model is None else model
    cell = job_search(job, None).cell(model, job.tool, job.stock)
    out: dict[str, str] = {}
    for cut in job.cuts:
        if names is not None and cut.name not in names:
            continue
        try:
            passes = cut_paths(job, cut, model, cell=cell)
        except ValueError as exc:
            out[cut.name] = str(exc).splitlines()[0]
            continue
        bad = [p for p in passes if not p.feasible]
        why = [r for p in bad for r in p.motion.reasons] or (["no motion found"] if bad else [])
        # the verdict's kept_surface check, on the same error (the kerf offset's) and limit
        err = max((float(p.kerf_error.max()) for p in passes
                   if p.compensated and p.kerf_error is not None and p.kerf_error.size),
                  default=0.0)  # fmt: skip
        if err > cut.wire_tolerance:
            why.append(f"the kept surface would lie {err * 1e3:.3g} mm from the target "
                       f"(limit {cut.wire_tolerance * 1e3:.3g} mm): a straight wire's kerf "
                       "offset cannot follow the surface there")  # fmt: skip
        out[cut.name] = "; ".join(why)
    return out
