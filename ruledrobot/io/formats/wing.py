"""A wing panel from two airfoil files: the ruled surface between a root and a tip.

Wing frame (metres): x along the root chord from the leading edge to the
trailing edge, y up (the airfoil's y), z along the span; the root profile lies
in ``z = 0``, the tip in ``z = span`` — the foam cutter's frame with the root at
tower A (:class:`~.rulings.Planes` ``z = 0`` and ``z = span``).

* root: the root airfoil scaled by ``root_chord``;
* tip: the tip airfoil (default: the root's) scaled by ``tip_chord`` (default
  ``root_chord``), turned by ``twist`` (rad, positive = leading edge up;
  ``washout = w`` is ``twist = -w``) about the point at ``twist_axis`` of its
  chord (default 0.25), then moved by ``span * tan(sweep)`` along x (leading-edge
  sweep, positive = swept back) and ``span * tan(dihedral)`` along y — both faces
  stay parallel, as a panel is cut from a block;
* rulings: point pairs by ``match`` (:mod:`.profiles`): ``"parameter"`` resamples
  both profiles with the leading edges matched to each other (``points`` rulings,
  made odd; ``spacing`` cosine by default, dense at the edges), ``"index"`` pairs
  the files' points one by one.  The rulings run from the trailing edge over the
  upper surface, round the leading edge, back along the lower surface.

Not done: kerf compensation (offset the profiles, or let your foam software do
it), a panel with root and tip faces that are not parallel.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...geometry._arrays import FloatArray
from .airfoil import leading_edge_index, read_airfoil
from .options import Options
from .profiles import MATCH_RULES, SPACINGS, match_profiles
from .rulings import Planes, Rulings, rulings_from_ends

__all__ = ["WingOptions", "read_wing", "wing_profiles"]


@dataclass(frozen=True)
class WingOptions:
    """A wing panel (lengths m, angles rad)."""

    root: Path
    span: float
    root_chord: float
    tip: Path | None = None
    tip_chord: float | None = None
    sweep: float = 0.0
    dihedral: float = 0.0
    twist: float = 0.0
    twist_axis: float = 0.25
    match: str = "parameter"
    points: int | None = None
    spacing: str = "cosine"

    @classmethod
    def parse(cls, o: Options) -> WingOptions:
        """The wing panel's options from ``o``; unknown options are refused.

        ``root`` (an airfoil file) and ``span`` [m] are required; ``twist`` [rad] or
        ``washout`` [rad] (``twist = -washout``, not both) lies in [-pi/2, pi/2],
        ``sweep`` and ``dihedral`` [rad] in [-1.4, 1.4], ``twist_axis`` (a fraction of the
        chord, dimensionless) in [0, 1].

        Raises
        ------
        ValueError
            When an option is missing, out of range, given twice or unknown, naming it.
        """
        root = o.path("root", kind="airfoil")
        tip = o.path("tip", required=False, kind="airfoil")
        if o.has("twist") and o.has("washout"):
            raise o.fail("twist", "give twist or washout, not both (washout = -twist)")
        twist = o.number("twist", 0.0, lo=-np.pi / 2, hi=np.pi / 2)
        washout = o.number("washout", lo=-np.pi / 2, hi=np.pi / 2)
        opts = cls(
            root=root,
            tip=tip,
            span=float(o.number("span", nonzero=True, required="the panel's span (m)")),
            root_chord=float(o.number("root_chord", positive=True, required="the root chord")),
            tip_chord=o.number("tip_chord", positive=True),
            sweep=float(o.number("sweep", 0.0, lo=-1.4, hi=1.4)),
            dihedral=float(o.number("dihedral", 0.0, lo=-1.4, hi=1.4)),
            twist=float(-washout if washout is not None else twist),
            twist_axis=float(o.number("twist_axis", 0.25, lo=0.0, hi=1.0)),
            match=o.choice("match", MATCH_RULES, "parameter"),
            points=o.integer("points", lo=5, hi=100_000),
            spacing=o.choice("spacing", SPACINGS, "cosine"),
        )
        o.done()
        return opts


def wing_profiles(opts: WingOptions) -> tuple[FloatArray, FloatArray, str]:
    """Matched root and tip points (K, 3) in the wing frame, and a description."""
    root = read_airfoil(opts.root)
    tip = read_airfoil(opts.tip) if opts.tip is not None else root
    where = f"{opts.root}" + (f" and {opts.tip}" if opts.tip is not None else "")
    a, b = match_profiles(
        root.points, tip.points, opts.match, opts.points, where,
        breaks=(leading_edge_index(root.points), leading_edge_index(tip.points)),
        spacing=opts.spacing,
        names=(f"root ({opts.root.name})", f"tip ({(opts.tip or opts.root).name})"),
    )  # fmt: skip
    ct = opts.tip_chord if opts.tip_chord is not None else opts.root_chord
    c, s = np.cos(-opts.twist), np.sin(-opts.twist)
    pivot = np.array([opts.twist_axis, 0.0])
    tip2 = (b - pivot) @ np.array([[c, s], [-s, c]]) + pivot  # rotation by -twist
    n = len(a)
    root3 = np.zeros((n, 3))
    root3[:, :2] = a * opts.root_chord
    tip3 = np.zeros((n, 3))
    tip3[:, :2] = tip2 * ct
    tip3 += [opts.span * np.tan(opts.sweep), opts.span * np.tan(opts.dihedral), opts.span]
    name = f"wing panel {root.name or opts.root.name} -> {tip.name or (opts.tip or opts.root).name}"
    return root3, tip3, name


def read_wing(opts: WingOptions) -> Rulings:
    """The rulings of the panel (see the module doc), ends on the root and tip faces."""
    root3, tip3, name = wing_profiles(opts)
    lines = rulings_from_ends(root3, tip3, str(opts.root))
    ends = np.stack([root3, tip3], axis=1)
    return Rulings(lines, False, ends, Planes(np.eye(4), opts.span, "faces"), None, name)
