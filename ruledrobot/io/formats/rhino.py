"""Rhino ``.3dm`` models in: line curves, a pair of curves, or a ruled surface
(rhino3dm, the ``cad`` extra).

What the model holds decides (``use = "auto"``), after the ``layer`` filter:

* ruledrobot's own layout (a layer ``rulings``): the line curves on it;
* ``"surface"`` — one surface (a NURBS surface, an extrusion, a one-face brep;
  trims are ignored): its rulings are the iso-curves along the parameter
  direction in which the surface is straight (``direction = "u"``/``"v"``, or
  found: iso-curves sampled at five points must lie on a line within 1e-6 of the
  surface's size); ``points`` rulings at equal parameter steps, default one per
  knot span boundary (polyline-based surfaces: exactly at their vertices), at
  least 21;
* ``"curves"`` — two curves: the profiles of a ruled surface (polylines by their
  vertices, other curves sampled at 32 points per span), matched like a DXF pair
  (:mod:`.profiles`; ``match``, ``points``, ``spacing``);
* ``"lines"`` — line curves (any curve that is straight): one ruling each, from
  its start to its end, in the order of the model's object table.

Units: the model's unit system (mm, cm, m, inches); a model without one is read
in ``units`` (default mm, with a note); ``units`` given and contradicted by the
model is a unit mismatch.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...geometry._arrays import FloatArray
from ..units import unit_scale
from .cad_common import MatchOptions, pair_to_rulings
from .extras import require
from .options import Options
from .rulings import Rulings, rulings_from_ends

if TYPE_CHECKING:
    import rhino3dm

__all__ = ["RhinoOptions", "model_units", "read_rhino"]

_UNIT_NAMES = {"Millimeters": "mm", "Centimeters": "cm", "Meters": "m", "Inches": "in"}


@dataclass(frozen=True)
class RhinoOptions:
    """How to read a 3DM model (see the module doc)."""

    use: str = "auto"
    layer: str | None = None
    units: str | None = None
    direction: str | None = None
    pairing: MatchOptions = field(default_factory=MatchOptions)

    @classmethod
    def parse(cls, o: Options) -> RhinoOptions:
        """Read the Rhino reader's options from ``o``; unknown options are refused.

        ``use``, ``layer``, ``units``, ``direction`` and those of
        :meth:`.cad_common.MatchOptions.parse`.
        """
        opts = cls(use=o.choice("use", ("auto", "lines", "curves", "surface"), "auto"),
                   layer=o.string("layer"), units=o.unit("units"),
                   direction=o.choice("direction", ("u", "v"), None),
                   pairing=MatchOptions.parse(o))  # fmt: skip
        o.done()
        return opts


def model_units(
    model: rhino3dm.File3dm, rhino, where: str, given: str | None
) -> tuple[str, list[str]]:
    """The model's length unit name and notes (see the module doc)."""
    us = model.Settings.ModelUnitSystem
    name = getattr(us, "name", str(us))
    if name in _UNIT_NAMES:
        units = _UNIT_NAMES[name]
        if given is not None and given != units:
            raise ValueError(f"{where}: the model's unit system is {name}, but units = {given!r} "
                             "was given (unit mismatch)")  # fmt: skip
        return units, []
    if name in ("None", "Unset"):
        return given or "mm", [] if given else ["the model has no unit system: read as mm"]
    raise ValueError(f"{where}: the model's unit system {name} is not supported; expected "
                     "millimeters, centimeters, meters or inches")  # fmt: skip


def _xyz(p) -> list[float]:
    return [p.X, p.Y, p.Z]


def _curve_points(curve) -> tuple[FloatArray, bool]:
    closed = bool(curve.IsClosed)
    poly = curve.TryGetPolyline()
    if poly is not None and poly.Count >= 2:
        pts = np.array([_xyz(p) for p in poly], dtype=np.float64)
    else:
        dom = curve.Domain
        n = 32 * max(1, int(curve.SpanCount)) + 1
        pts = np.array([_xyz(curve.PointAt(t)) for t in np.linspace(dom.T0, dom.T1, n)])
    if closed and np.allclose(pts[0], pts[-1], rtol=0, atol=1e-12):
        pts = pts[:-1]
    return pts, closed


def _surface_rulings(srf, opts: RhinoOptions, where: str) -> tuple[FloatArray, FloatArray]:
    """End points (K, 3) of the rulings of a surface, in model units."""
    doms = [srf.Domain(0), srf.Domain(1)]
    corners = np.array([_xyz(srf.PointAt(u, v)) for u in (doms[0].T0, doms[0].T1)
                        for v in (doms[1].T0, doms[1].T1)])  # fmt: skip
    size = max(1e-12, float(np.ptp(corners, axis=0).max()))

    def deviation(d: int) -> float:
        """Largest distance of iso-curve samples from their chord; rulings along d."""
        o = 1 - d
        worst = 0.0
        for s in np.linspace(doms[o].T0, doms[o].T1, 7):
            ts = np.linspace(doms[d].T0, doms[d].T1, 5)
            pts = np.array([_xyz(srf.PointAt(*((s, t) if d == 1 else (t, s)))) for t in ts])
            a, b = pts[0], pts[-1]
            ab = (b - a) / max(np.linalg.norm(b - a), 1e-300)
            rel = pts - a
            worst = max(worst, float(np.linalg.norm(rel - np.outer(rel @ ab, ab), axis=1).max()))
        return worst

    if opts.direction is not None:
        d = 0 if opts.direction == "u" else 1
        dev = deviation(d)
        if dev > 1e-6 * size:
            raise ValueError(f"{where}: the surface is not ruled along {opts.direction}: its "
                             f"iso-curves leave their chords by {dev:.3g} model units")  # fmt: skip
    else:
        devs = [deviation(1), deviation(0)]
        if min(devs) > 1e-6 * size:
            raise ValueError(f"{where}: the surface is not ruled: its iso-curves leave their "
                             f"chords by {min(devs):.3g} model units in either direction; "
                             "expected a ruled surface (a loft of two curves)")  # fmt: skip
        d = 1 if devs[0] <= 1e-6 * size else 0
    o = 1 - d
    if opts.pairing.points is not None:
        params = np.linspace(doms[o].T0, doms[o].T1, opts.pairing.points)
    else:
        knots = np.unique(np.asarray(srf.GetSpanVector(o), dtype=np.float64))
        params = knots
        while len(params) < 21:  # refine evenly between the knots
            params = np.unique(np.r_[params, 0.5 * (params[1:] + params[:-1])])
    ends = []
    for s in params:
        uv0 = (s, doms[d].T0) if d == 1 else (doms[d].T0, s)
        uv1 = (s, doms[d].T1) if d == 1 else (doms[d].T1, s)
        ends.append([_xyz(srf.PointAt(*uv0)), _xyz(srf.PointAt(*uv1))])
    e = np.asarray(ends, dtype=np.float64)
    return e[:, 0], e[:, 1]


def read_rhino(path: str | os.PathLike[str], opts: RhinoOptions | None = None) -> Rulings:
    """The rulings of a 3DM model (see the module doc)."""
    opts = opts or RhinoOptions()
    rhino = require("rhino3dm", "reading Rhino .3dm files")
    p = Path(path)
    where = str(p)
    if not p.is_file():
        raise ValueError(f"{where}: no such Rhino file")
    model = rhino.File3dm.Read(str(p))
    if model is None:
        raise ValueError(f"{where}: not a readable Rhino .3dm file")
    units, notes = model_units(model, rhino, where, opts.units)
    scale = unit_scale(units, where)
    layer_names = {}
    for k, layer in enumerate(model.Layers):
        layer_names[layer.Index if layer.Index >= 0 else k] = (layer.Name, layer.FullPath)
    layer = opts.layer
    own = any(n == "rulings" for n, _ in layer_names.values())
    if layer is None and opts.use == "auto" and own:
        layer = "rulings"
        use = "lines"
    else:
        use = opts.use
    if layer is not None and not any(layer in names for names in layer_names.values()):
        known = ", ".join(sorted({n for n, _ in layer_names.values()})) or "none"
        raise ValueError(f"{where}: no layer {layer!r}; the model's layers: {known}")
    lines, curves, surfaces, other = [], [], [], 0
    for obj in model.Objects:
        if layer is not None and layer not in layer_names.get(obj.Attributes.LayerIndex, ()):
            continue
        g = obj.Geometry
        if isinstance(g, rhino.Brep):
            if len(g.Faces) != 1:
                other += 1
                continue
            g = g.Faces[0]
        if isinstance(g, rhino.Curve):
            (lines if g.IsLinear(1e-9) else curves).append(g)
        elif isinstance(g, rhino.Surface):
            surfaces.append(g)
        else:
            other += 1
    summary = (f"{len(lines)} line(s), {len(curves)} other curve(s), {len(surfaces)} surface(s), "
               f"{other} other object(s)" + (f" on layer {layer!r}" if layer else ""))  # fmt: skip
    if use == "auto":
        if len(surfaces) == 1:
            use = "surface"
        elif len(curves) + len(lines) == 2 and curves:
            use = "curves"
        elif len(lines) >= 2 and not curves and not surfaces:
            use = "lines"
        else:
            raise ValueError(f"{where}: the model holds {summary}; expected one ruled surface, "
                             "two curves (profiles) or line curves (rulings): choose with use "
                             "and layer")  # fmt: skip
    if use == "surface":
        if len(surfaces) != 1:
            raise ValueError(f"{where}: use = surface, but the model holds {summary}")
        a, b = _surface_rulings(surfaces[0], opts, where)
        ruled = rulings_from_ends(a * scale, b * scale, where)
        return Rulings(ruled, False, np.stack([a, b], axis=1) * scale, None, None, where,
                       tuple(notes))  # fmt: skip
    if use == "curves":
        pair = curves + lines
        if len(pair) != 2:
            raise ValueError(f"{where}: use = curves needs two curves; the model holds {summary}")
        (a, ca), (b, cb) = (_curve_points(c) for c in pair)
        if ca != cb:
            raise ValueError(f"{where}: one curve is closed and the other open; expected both "
                             "alike")  # fmt: skip
        r = pair_to_rulings(a * scale, b * scale, ca, opts.pairing, None, where,
                            ("first curve", "second curve"), where)  # fmt: skip
        return Rulings(r.lines, r.closed, r.ends, r.planes, None, where, tuple(notes) + r.notes)
    if len(lines) < 2:
        raise ValueError(f"{where}: use = lines needs at least two line curves; the model holds "
                         f"{summary}")  # fmt: skip
    ends = np.array([[_xyz(c.PointAtStart), _xyz(c.PointAtEnd)] for c in lines]) * scale
    ruled = rulings_from_ends(ends[:, 0], ends[:, 1], where)
    return Rulings(ruled, False, ends, None, None, where, tuple(notes))
