"""Setups: when no single placement serves every cut, the block is turned and clamped
again between groups of cuts.

Rules (``docs/place.md``):

* A setup makes whole cuts; every cut is made in exactly one setup.
* Each setup has its own placement: one of the turns the user allows (and the block
  as clamped), then a place in the region.  The cuts of a setup are made in the
  job's order; setups follow the order of their first cut; the resulting order must
  pass the job's cut-order rules (:func:`~ruledrobot.wirecut.cut.order.check_cut_order`).
* The fewest setups whose worst margin is >= 0 win; among those, the largest worst
  margin.  Each group's placement is then searched again for its own cuts.

Between setups the operator is told what to do: which way to turn or tip the block,
and where three marked corners of it go (``A``: the block's corner at -x, -y, -z of
its own axes as the job first gives them; ``B`` at +x, -y, -z; ``D`` at -x, +y, -z),
in millimetres in the robot base frame.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from ..geometry.checks import FloatArray
from ..io.words import mm
from ..wirecut.cut.order import check_cut_order
from ..wirecut.job.spec import Job
from ..wirecut.reach.evaluate import Evaluator
from .regions import AS_CLAMPED, Region, Turn, moved_job
from .search import Candidate, PlaceResult, search

__all__ = ["Setup", "SetupPlan", "corners", "operator_steps", "plan_setups"]

#: cuts beyond which setups are not searched (the number of groupings grows fast)
MAX_CUTS = 8
#: most setups considered
MAX_SETUPS = 4


@dataclass(frozen=True)
class Setup:
    """One setup.

    The cuts it makes (indices into the job's cuts) and its placement (the best of ``ranked``,
    its search's best candidates)."""

    number: int
    cuts: tuple[int, ...]
    candidate: Candidate
    ranked: tuple[Candidate, ...] = ()


@dataclass(frozen=True)
class SetupPlan:
    """The setups found (fewest first, then largest worst margin) and the worst margin."""

    setups: tuple[Setup, ...]
    margin: float
    tried: int


def _partitions(n: int, k: int) -> Iterator[list[tuple[int, ...]]]:
    """Set partitions of ``range(n)`` into ``k`` non-empty groups, each group sorted,
    groups ordered by their first element."""
    for labels in itertools.product(range(k), repeat=n):
        # canonical: first occurrences of labels in order 0, 1, 2, ...
        seen = list(dict.fromkeys(labels))
        if seen != list(range(k)):
            continue
        yield [tuple(i for i in range(n) if labels[i] == g) for g in range(k)]


def plan_setups(
    job: Job,
    region: Region,
    evaluator: Evaluator,
    turns: tuple[Turn, ...],
    grid: tuple[int, int, int] = (7, 7, 7),
    refine: int = 2,
    progress: Callable[[str], None] | None = None,
) -> SetupPlan | None:
    """Return the setups of ``job`` (module doc), or None.

    None when the job has one cut, more than :data:`MAX_CUTS`, or no grouping into at most
    :data:`MAX_SETUPS` setups has a worst margin >= 0 on the sampled placements.
    """
    say = progress or (lambda msg: None)
    n = len(job.cuts)
    if n < 2 or n > MAX_CUTS:
        return None
    options: list[tuple[Turn, PlaceResult]] = []
    for turn in (AS_CLAMPED, *turns):
        say(f"setups: scoring placements of the block turned {turn.label}")
        options.append((turn, search(job, region, evaluator, grid, 0, turn=turn)))
    cm = np.concatenate([r.cut_margins for _, r in options])  # (N, n)
    subsets = {}
    for size in range(1, n + 1):
        for group in itertools.combinations(range(n), size):
            subsets[group] = float(cm[:, list(group)].min(axis=1).max())
    best = None
    tried = 0
    for k in range(2, min(n, MAX_SETUPS) + 1):
        for part in _partitions(n, k):
            tried += 1
            value = min(subsets[g] for g in part)
            if value < 0.0 or (best is not None and value <= best[0]):
                continue
            order = [i for g in part for i in g]
            try:
                check_cut_order(dataclasses.replace(job, cuts=tuple(job.cuts[i] for i in order)))
            except ValueError:
                continue
            best = (value, part)
        if best is not None:
            break
    if best is None:
        return None
    setups = []
    for number, group in enumerate(best[1], start=1):
        # the turn whose samples serve this group best, then a finer search for it
        values = [float(r.cut_margins[:, list(group)].min(axis=1).max()) for _, r in options]
        turn = options[int(np.argmax(values))][0]
        say(f"setups: placing setup {number} ({', '.join(job.cuts[i].name for i in group)})")
        res = search(job, region, evaluator.subset(list(group)), grid, refine, turn=turn,
                     cuts=list(group))  # fmt: skip
        setups.append(Setup(number, group, res.best, res.ranked))
    worst = min(s.candidate.margin for s in setups)
    return SetupPlan(tuple(setups), worst, tried)


def corners(job: Job, T: FloatArray) -> FloatArray:
    """The marked corners A, B, D (3, 3) [m] of the job's block moved by T (4, 4)."""
    st = job.stock
    local = np.array([[-1, -1, -1], [1, -1, -1], [-1, 1, -1]]) * 0.5 * st.size
    pts = st.centre + local @ st.rotation.T
    return pts @ T[:3, :3].T + T[:3, 3]


_FACES = {(0, 1): "+x", (0, -1): "-x", (1, 1): "+y", (1, -1): "-y", (2, 1): "top",
          (2, -1): "bottom"}  # fmt: skip


def _down_face(job: Job, T: FloatArray) -> str:
    """Which face of the block (its own axes in the job) faces down after T."""
    R = T[:3, :3] @ job.stock.rotation
    down = -R[2]  # the block axes' components along world -z
    k = int(np.argmax(np.abs(down)))
    return _FACES[(k, 1 if down[k] > 0 else -1)]


def _mm(p: FloatArray) -> str:
    return "(" + ", ".join(mm(v) for v in p) + ") mm"


def operator_steps(job: Job, plan: SetupPlan) -> list[str]:
    """What the operator does for each setup, in words (module doc)."""
    lines = []
    prev = np.eye(4)
    first_face = _down_face(job, prev)
    for s in plan.setups:
        T = s.candidate.placement.transform(job)
        A, B, D = corners(job, T)
        names = ", ".join(job.cuts[i].name for i in s.cuts)
        face = _down_face(job, T)
        rel = T[:3, :3] @ prev[:3, :3].T
        if s.number == 1:
            how = (f"Mark the block's corners A (-x, -y, bottom, of the block as the job "
                   f"file gives it), B (+x, -y, bottom) and D (-x, +y, bottom). Set the "
                   f"block on its {face} face")  # fmt: skip
        else:
            how = "Unclamp the block. "
            old = _down_face(job, prev)
            if face != old:
                opposite = {"+x": "-x", "-x": "+x", "+y": "-y", "-y": "+y", "top": "bottom",
                            "bottom": "top"}  # fmt: skip
                if opposite[face] == old:
                    how += f"Turn it upside down, onto its {face} face"
                else:
                    how += (f"Tip it 90 deg over its bottom edge between the {old} and {face} "
                            f"faces, onto its {face} face")  # fmt: skip
                how += (f" (the {first_face} face was down at first), then turn it about the "
                        "vertical")  # fmt: skip
            else:
                yaw = np.degrees(np.arctan2(rel[1, 0], rel[0, 0]))
                turn = ("counter-clockwise" if yaw > 0 else "clockwise")
                how += (f"Turn it {abs(yaw):.0f} deg {turn} (seen from above) about the "
                        f"vertical, still on its {face} face")  # fmt: skip
        lines.append(
            f"Setup {s.number} (cuts: {names}; worst margin {s.candidate.margin * 1e3:.0f} mm): "
            f"{how}; put corner A at {_mm(A)}, B at {_mm(B)}, D at {_mm(D)} (robot base "
            f"frame; block centre at {_mm(moved_job(job, T).stock.centre)}, "
            f"yaw {np.degrees(_yaw(job, T)):.1f} deg). Clamp it and run setup{s.number}/job.toml."
        )
        prev = T
    return lines


def _yaw(job: Job, T: FloatArray) -> float:
    """The block's x axis direction in the horizontal plane after T (rad)."""
    x = (T[:3, :3] @ job.stock.rotation)[:, 0]
    return float(np.arctan2(x[1], x[0]))
