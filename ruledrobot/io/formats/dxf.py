"""DXF profile pairs in, rulings out (ezdxf, the ``cad`` extra).

Reading: two curves — ``LWPOLYLINE``, ``POLYLINE`` (2-D or 3-D), ``SPLINE``,
``LINE``, ``ARC``... anything ezdxf makes a path of, flattened to within
``tolerance`` (m) — are the two profiles; which ones: the two layers named in
``layers`` (one curve each, the first is profile A), else ruledrobot's own
layers ``END_A``/``END_B``, else the only two curves of the model space.  Two
flat profiles drawn in one plane (the usual foam-cutting drawing: root and tip
in XY) are put ``distance`` (m) apart along z; profiles drawn in place in 3-D
need no distance.  Points are matched by ``match`` (:mod:`.profiles`).  Units:
the file's ``$INSUNITS`` (mm, cm, m, inches); a file without them is read in
``units`` (default mm, with a note); ``units`` given and contradicted by the
file is a unit mismatch.

Writing: every ruling as a ``LINE`` on layer ``RULINGS`` between its two ends,
and the ends as two 3-D polylines on layers ``END_A`` and ``END_B`` (which this
reader reads back), in ``units`` (default mm, ``$INSUNITS`` set).
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ...geometry._arrays import FloatArray
from ..atomic import atomic_write_text
from ..units import unit_scale
from .cad_common import CadWriteOptions, MatchOptions, pair_to_rulings, segments
from .extras import require
from .options import Options
from .rulings import Rulings

__all__ = ["DxfOptions", "read_dxf", "write_dxf"]

#: $INSUNITS codes of the units we read and write
_INSUNITS = {1: "in", 4: "mm", 5: "cm", 6: "m"}
_CODES = {v: k for k, v in _INSUNITS.items()}
OWN_LAYERS = ("END_A", "END_B")


@dataclass(frozen=True)
class DxfOptions:
    """How to read a DXF profile pair (lengths m)."""

    layers: tuple[str, str] | None = None
    distance: float | None = None
    units: str | None = None
    tolerance: float = 1e-5
    pairing: MatchOptions = field(default_factory=MatchOptions)

    @classmethod
    def parse(cls, o: Options) -> DxfOptions:
        """Read the DXF reader's options from ``o``; unknown options are refused.

        ``layers`` (two names), ``distance`` [m] (non-zero), ``units``, ``tolerance`` (> 0,
        default 1e-5) and those of :meth:`.cad_common.MatchOptions.parse`.
        """
        layers = o.strings("layers", 2)
        opts = cls(layers=layers, distance=o.number("distance", nonzero=True),
                   units=o.unit("units"), tolerance=float(o.number("tolerance", 1e-5,
                                                                   positive=True)),
                   pairing=MatchOptions.parse(o))  # fmt: skip
        o.done()
        return opts


def _open(path: Path):
    ezdxf = require("ezdxf", "reading DXF files")
    if not path.is_file():
        raise ValueError(f"{path}: no such DXF file")
    try:
        return ezdxf.readfile(str(path))
    except (OSError, UnicodeDecodeError, ezdxf.DXFError) as exc:
        raise ValueError(f"{path}: not a readable DXF file ({exc})") from None


def _points(entity, tol_units: float, where: str) -> tuple[FloatArray, bool]:
    from ezdxf import path as dxf_path

    try:
        p = dxf_path.make_path(entity)
    except TypeError:
        raise ValueError(f"{where}: a {entity.dxftype()} is not a curve") from None
    pts = np.array([tuple(v) for v in p.flattening(tol_units)], dtype=np.float64).reshape(-1, 3)
    kind = entity.dxftype()
    if kind == "LWPOLYLINE" or kind == "SPLINE":
        closed = bool(entity.closed)
    elif kind == "POLYLINE":
        closed = bool(entity.is_closed)
    else:  # a full circle or ellipse closes; lines and arcs do not
        closed = kind == "CIRCLE" or (kind == "ELLIPSE" and bool(p.is_closed))
    if closed and len(pts) > 1 and np.allclose(pts[0], pts[-1], rtol=0, atol=1e-12):
        pts = pts[:-1]
    return pts, closed


def read_dxf(path: str | os.PathLike[str], opts: DxfOptions | None = None) -> Rulings:
    """The rulings between the two profiles of a DXF file (see the module doc)."""
    opts = opts or DxfOptions()
    p = Path(path)
    doc = _open(p)
    where = str(p)
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    notes = []
    if code in _INSUNITS:
        units = _INSUNITS[code]
        if opts.units is not None and opts.units != units:
            raise ValueError(f"{where}: the file says its units are {units} ($INSUNITS = {code}), "
                             f"but units = {opts.units!r} was given (unit mismatch)")  # fmt: skip
    elif code == 0:
        units = opts.units or "mm"
        if opts.units is None:
            notes.append("the file does not say its units ($INSUNITS): read as mm")
    else:
        raise ValueError(f"{where}: $INSUNITS = {code} is not supported; expected 1 (in), 4 (mm), "
                         "5 (cm), 6 (m) or 0 with units given")  # fmt: skip
    scale = unit_scale(units, where)
    curves = [e for e in doc.modelspace() if e.dxftype() in (
        "LWPOLYLINE", "POLYLINE", "SPLINE", "LINE", "ARC", "CIRCLE", "ELLIPSE")]  # fmt: skip
    by_layer: dict[str, list] = {}
    for e in curves:
        by_layer.setdefault(e.dxf.layer, []).append(e)
    summary = ", ".join(f"{k} ({len(v)})" for k, v in by_layer.items()) or "none"
    layers = opts.layers
    pairing = opts.pairing
    own = layers is None and all(k in by_layer for k in OWN_LAYERS)
    if own:
        layers = OWN_LAYERS  # ruledrobot's own file: its points are matched already
        if pairing.match is None:
            pairing = MatchOptions("index", pairing.points, pairing.spacing)
    if layers is not None:
        chosen = []
        for name in layers:
            ents = by_layer.get(name, [])
            if len(ents) != 1:
                raise ValueError(f"{where}: layer {name!r} holds {len(ents)} curves; expected "
                                 f"one profile (curves by layer: {summary})")  # fmt: skip
            chosen.append(ents[0])
        names = (f"profile on layer {layers[0]}", f"profile on layer {layers[1]}")
    elif len(curves) == 2:
        chosen = curves
        names = (f"first curve (layer {curves[0].dxf.layer})",
                 f"second curve (layer {curves[1].dxf.layer})")  # fmt: skip
    else:
        raise ValueError(f"{where}: {len(curves)} curves (by layer: {summary}); expected two "
                         "profiles: give layers = [\"A\", \"B\"] naming two layers with one "
                         "curve each")  # fmt: skip
    tol_units = opts.tolerance / scale
    (a, ca), (b, cb) = (_points(e, tol_units, f"{where}: {n}") for e, n in
                        zip(chosen, names, strict=True))  # fmt: skip
    if ca != cb:
        kinds = ["closed" if c else "open" for c in (ca, cb)]
        raise ValueError(f"{where}: the {names[0]} is {kinds[0]} and the {names[1]} "
                         f"{kinds[1]}; expected both alike")
    for pts, name in ((a, names[0]), (b, names[1])):
        if len(pts) < 2:
            raise ValueError(f"{where}: the {name} has {len(pts)} point(s); expected at least 2")
    r = pair_to_rulings(a * scale, b * scale, ca, pairing, opts.distance, where, names,
                        where, profiles=not own)  # fmt: skip
    return Rulings(r.lines, r.closed, r.ends, r.planes, None, where, tuple(notes) + r.notes)


def write_dxf(path: str | os.PathLike[str], rulings: Rulings,
              opts: CadWriteOptions | None = None) -> Path:  # fmt: skip
    """Write the rulings as lines and their ends as two polylines (see the module doc)."""
    opts = opts or CadWriteOptions()
    ezdxf = require("ezdxf", "writing DXF files")
    ends = segments(rulings, opts, str(path)) / unit_scale(opts.units, str(path))
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = _CODES[opts.units]
    for name, color in (("RULINGS", 8), (OWN_LAYERS[0], 1), (OWN_LAYERS[1], 5)):
        doc.layers.add(name, color=color)
    msp = doc.modelspace()
    for a, b in ends.tolist():
        msp.add_line(a, b, dxfattribs={"layer": "RULINGS"})
    for k, layer in enumerate(OWN_LAYERS):
        msp.add_polyline3d(ends[:, k].tolist(), close=rulings.closed, dxfattribs={"layer": layer})
    buf = io.StringIO()
    doc.write(buf)
    return atomic_write_text(path, buf.getvalue())
