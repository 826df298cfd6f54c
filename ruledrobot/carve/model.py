"""The value types of a carving: a cut as carve makes it, and its measures."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..geometry.checks import FloatArray
from ..geometry.lines import Lines

__all__ = ["CarveCut", "CutMeasure"]


@dataclass(frozen=True)
class CarveCut:
    """One cut.

    ``lines`` its rulings (base frame, m), ``closed`` a loop round the part, ``keep`` the
    part's side (``"inside"`` or a point (3,) of the part), ``kind`` ``"exact"`` (the rulings
    of a ruled face of the part) or ``"rough"`` (a loop that stands off the part), ``what`` in
    words (``"region 1: ruled quadric"``), ``region`` the face it cuts (exact cuts) or None."""

    name: str
    kind: str
    lines: Lines
    closed: bool
    keep: str | FloatArray = field(repr=False)
    what: str = ""
    region: int | None = None


@dataclass(frozen=True)
class CutMeasure:
    """A cut measured against the part (metres).

    ``gouge`` the deepest ruling point inside the part beyond the tolerance (0: none),
    ``closest`` the nearest any ruling point in the block comes to the part, ``farthest``
    (rough) the largest of the rulings' nearest approaches to the part, ``deviation`` (exact)
    the largest distance from the face's vertices to the cut's surface, ``ok`` the cut's
    checks."""

    gouge: float
    closest: float
    farthest: float
    deviation: float
    ok: bool

    def as_dict(self) -> dict[str, float | bool]:
        """The measures for ``carve.json``, in millimetres.

        Returns
        -------
        dict
            ``gouge_mm``, ``closest_mm``, ``farthest_mm``, ``deviation_mm`` [mm], rounded
            to 4 decimals (None where the measure is not finite, e.g. a measure that does
            not apply to the cut's kind), and ``ok`` (bool).
        """
        mm = {k: round(float(getattr(self, k)) * 1e3, 4) if np.isfinite(getattr(self, k))
              else None for k in ("gouge", "closest", "farthest", "deviation")}  # fmt: skip
        return {"gouge_mm": mm["gouge"], "closest_mm": mm["closest"],
                "farthest_mm": mm["farthest"], "deviation_mm": mm["deviation"],
                "ok": bool(self.ok)}  # fmt: skip
