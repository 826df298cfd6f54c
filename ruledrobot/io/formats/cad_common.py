"""What the CAD readers and writers share: segments to draw, profile pairs to rulings."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...geometry import se3
from ...geometry._arrays import FloatArray
from .options import Options
from .profiles import MATCH_RULES, SPACINGS, check_simple, match_profiles
from .rulings import Planes, Rulings, fit_planes, plane_ends, rulings_from_ends

__all__ = ["CadWriteOptions", "MatchOptions", "pair_to_rulings", "segments"]


@dataclass(frozen=True)
class MatchOptions:
    """How two profiles make rulings (:mod:`.profiles`).

    ``match`` None: ``"parameter"``, or ``"index"`` for ruledrobot's own files (their points
    are matched already)."""

    match: str | None = None
    points: int | None = None
    spacing: str = "uniform"

    @classmethod
    def parse(cls, o: Options) -> MatchOptions:
        """The options ``match``, ``points`` (3 to 100 000) and ``spacing`` read from ``o``.

        Does not call :meth:`.options.Options.done`, the caller's reader does.
        """
        return cls(o.choice("match", MATCH_RULES, None),
                   o.integer("points", lo=3, hi=100_000),
                   o.choice("spacing", SPACINGS, "uniform"))  # fmt: skip


@dataclass(frozen=True)
class CadWriteOptions:
    """How to draw rulings in a CAD file.

    ``units`` of the file (default mm); the segments end on the source's ends or planes, or on
    the planes ``length`` apart (m) of ``frame`` (a pose, default fitted) when those are given."""

    units: str = "mm"
    length: float | None = None
    frame: FloatArray | None = field(default=None, repr=False)
    surface: bool = True  # 3DM: also the ruled surface between the two end curves

    @classmethod
    def parse(cls, o: Options, surface: bool = False) -> CadWriteOptions:
        """Read the options ``units``, ``length``, ``frame`` (and ``surface``) from ``o``.

        ``length`` [m] (non-zero), ``frame`` (a UR pose vector, shape (6,): position [m],
        rotation vector [rad]) and, when ``surface`` is true, the option ``surface``;
        unknown options are refused.
        """
        frame = o.vector("frame", 6)
        opts = cls(
            units=o.unit("units", "mm"),
            length=o.number("length", nonzero=True),
            frame=None if frame is None else se3.pose_from_ur_vector(frame),
            surface=o.boolean("surface", True) if surface else True,
        )
        o.done()
        return opts


def segments(rulings: Rulings, opts: CadWriteOptions, where: str) -> FloatArray:
    """End points (N, 2, 3) m of the segments to draw (see :class:`CadWriteOptions`)."""
    if opts.length is None and opts.frame is None:
        if rulings.ends is not None:
            return rulings.ends
        if rulings.planes is not None:
            return plane_ends(rulings.lines, rulings.planes, where)
        raise ValueError(f"{where}: length: missing; these rulings are infinite lines (a "
                         "lines file): give the length of the segments to draw (m), e.g. 0.4")
    src = rulings.planes
    length = opts.length if opts.length is not None else (src.distance if src else None)
    if length is None:
        raise ValueError(f"{where}: length: missing; give the distance between the planes the "
                         "segments end on (m)")  # fmt: skip
    if opts.frame is not None:
        planes = Planes(opts.frame, length)
    elif src is not None:
        planes = Planes(src.pose, length)
    else:
        planes = fit_planes(rulings.lines, length)
    return plane_ends(rulings.lines, planes, where)


def _crossed(a: FloatArray, b: FloatArray) -> bool:
    """Do the ends of open profile b lie nearer the opposite ends of a (in xy)?"""
    d = lambda p, q: float(np.linalg.norm(p[:2] - q[:2]))  # noqa: E731
    return d(a[0], b[-1]) + d(a[-1], b[0]) < d(a[0], b[0]) + d(a[-1], b[-1])


def _area(p: FloatArray) -> float:
    """Twice the signed xy area of the polygon through p (closed up)."""
    q = np.concatenate([p, p[:1]])
    return float(np.sum(q[:-1, 0] * q[1:, 1] - q[1:, 0] * q[:-1, 1]))


def _flat_z(p: FloatArray) -> float | None:
    z = p[:, 2]
    return float(z.mean()) if np.ptp(z) <= 1e-9 * max(1.0, float(np.abs(p).max())) else None


def pair_to_rulings(a: FloatArray, b: FloatArray, closed: bool, m: MatchOptions,
                    distance: float | None, where: str, names: tuple[str, str],
                    source: str, profiles: bool = True) -> Rulings:  # fmt: skip
    """Return the rulings between profile ``a`` and ``b``.

    Profiles: points (N, 3) m, a closed profile without its repeated first point.
    ``distance`` puts two flat profiles (both in one plane z = c) that far apart along z.  A
    profile ``b`` that runs the other way round than ``a``, or whose seam (first point) is
    elsewhere, is turned to match (noted).  ``profiles=False`` (ruledrobot's own end curves:
    wire paths, matched already, which may cross themselves) skips the profile checks and
    turns.
    """
    notes = []
    za, zb = _flat_z(a), _flat_z(b)
    if distance is not None:
        if za is None or zb is None:
            raise ValueError(f"{where}: distance places two flat profiles drawn in one plane "
                             "z = c, but the profiles are not flat in z (drawn in 3-D): remove "
                             "distance")  # fmt: skip
        if abs(za - zb) > 1e-9 * max(1.0, abs(za)):
            raise ValueError(f"{where}: distance places two flat profiles drawn in one plane, "
                             f"but these lie apart already (z = {za:g} and {zb:g} m): remove "
                             "distance")  # fmt: skip
        b = b + np.array([0.0, 0.0, distance])
        zb = za + distance
    elif za is not None and zb is not None and abs(za - zb) <= 1e-12 * max(1.0, abs(za)):
        raise ValueError(f"{where}: both profiles lie in the plane z = {za:g}; give distance "
                         "(m): how far apart they are (span, or tower distance)")  # fmt: skip
    if profiles:
        for name, p in zip(names, (a, b), strict=True):
            check_simple(p, f"{where}: {name}", closed)
    if profiles and za is not None and zb is not None:
        ext = float(np.ptp(np.concatenate([a, b])[:, :2], axis=0).max()) ** 2
        aa, ab = _area(a), _area(b)
        if min(abs(aa), abs(ab)) > 1e-6 * ext:  # profiles that enclose an area: by its sign
            flip = aa * ab < 0
        else:  # nearly straight open profiles: by their ends
            flip = not closed and _crossed(a, b)
        if flip:
            b = b[::-1].copy()
            notes.append(f"the {names[1]} runs the other way; reversed it to match the "
                         f"{names[0]}")  # fmt: skip
        if closed:
            k = int(np.argmin(np.linalg.norm(b[:, :2] - a[0, :2], axis=1)))
            if k:
                b = np.roll(b, -k, axis=0)
                notes.append(f"the {names[1]} starts at its point {k}, the one nearest the start "
                             f"of the {names[0]}")  # fmt: skip
    if closed:
        a, b = np.concatenate([a, a[:1]]), np.concatenate([b, b[:1]])
    n = (m.points + 1) if closed and m.points else m.points
    pa, pb = match_profiles(a, b, m.match or "parameter", n,
                            where, spacing=m.spacing, names=names)  # fmt: skip
    if closed:
        pa, pb = pa[:-1], pb[:-1]
    lines = rulings_from_ends(pa, pb, where)
    planes = None
    if za is not None and zb is not None:
        T = np.eye(4)
        T[2, 3] = za
        planes = Planes(T, zb - za, "profiles")
    return Rulings(lines, closed, np.stack([pa, pb], axis=1), planes, None, source, tuple(notes))
