"""The value types of a cut's geometry: its refined rulings and the passes of its wire."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...geometry.checks import FloatArray
from ..job.spec import CutSpec
from .wire_pose import RedundancyResult

__all__ = ["CutPath", "RefinedCut"]


@dataclass(frozen=True)
class CutPath:
    """One pass of the wire: frames (M, 4, 4) the wire follows and the chosen motion.

    ``frames`` are the wire's rulings (kerf-compensated), ``surface_frames`` the
    target surface's rulings at the same samples (equal when not compensated),
    ``kerf_error`` (M,) the predicted error [m] of the kept surface there.  ``param``
    (M,): the path parameter of the rulings, increasing (None: 0, 1, ..., M - 1; a
    ruling added halfway between two gets the mean of theirs, so that the parameter
    stays proportional to the distance along the surface).  ``cut``: the job's cut this
    pass makes (the object itself: its feed, tolerances, keep; ``name`` is its name).
    """

    frames: FloatArray = field(repr=False)
    motion: RedundancyResult
    steps: int
    extended: tuple[int, int]  # frames added before / after (lead-in/out, slits)
    input_rulings: int
    name: str = "cut"
    surface_frames: FloatArray | None = field(default=None, repr=False)
    kerf_error: FloatArray | None = field(default=None, repr=False)
    compensated: bool = False
    closed: bool = False
    notes: tuple[str, ...] = ()
    param: FloatArray | None = field(default=None, repr=False)
    cut: CutSpec | None = field(default=None, repr=False, compare=False)

    @property
    def s(self) -> FloatArray:
        """(M,) the rulings' path parameter (see ``param``)."""
        return np.arange(len(self.frames), dtype=np.float64) if self.param is None else self.param

    def locate(self, s: FloatArray) -> tuple[np.ndarray, FloatArray]:
        """For path parameters ``s`` (K,).

        The ruling before each (K,) int, clipped to ``0 .. M - 2``, and the fraction (K,) of
        the way to the next."""
        p = self.s
        i0 = np.clip(np.searchsorted(p, s, side="right") - 1, 0, len(p) - 2)
        frac = np.clip((np.asarray(s) - p[i0]) / (p[i0 + 1] - p[i0]), 0.0, 1.0)
        return i0, frac

    @property
    def feasible(self) -> bool:
        """Whether the chosen motion reaches every ruling (the motion's ``feasible``)."""
        return self.motion.feasible

    @property
    def target_frames(self) -> FloatArray:
        """(M, 4, 4) the target surface's rulings.

        ``surface_frames``, or ``frames`` when the pass is not kerf-compensated (None given)."""
        return self.frames if self.surface_frames is None else self.surface_frames


@dataclass(frozen=True)
class RefinedCut:
    """A cut's refined rulings: frames (M, 4, 4), steps taken, topology."""

    frames: FloatArray = field(repr=False)
    steps: int
    closed: bool
    flip: bool
    input_rulings: int
