"""The value types of a cut's geometry: its refined rulings and the passes of its wire."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..geometry.checks import FloatArray
from .redundancy import RedundancyResult

__all__ = ["CutPath", "RefinedCut"]


@dataclass(frozen=True)
class CutPath:
    """One pass of the wire: frames (M, 4, 4) the wire follows and the chosen motion.

    ``frames`` are the wire's rulings (kerf-compensated), ``surface_frames`` the
    target surface's rulings at the same samples (equal when not compensated),
    ``kerf_error`` (M,) the predicted error [m] of the kept surface there.
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

    @property
    def feasible(self) -> bool:
        return self.motion.feasible

    @property
    def target_frames(self) -> FloatArray:
        return self.frames if self.surface_frames is None else self.surface_frames


@dataclass(frozen=True)
class RefinedCut:
    """A cut's refined rulings: frames (M, 4, 4), steps taken, topology."""

    frames: FloatArray = field(repr=False)
    steps: int
    closed: bool
    flip: bool
    input_rulings: int
