"""The ``convert`` command: the file formats of hot-wire cutting and CAD, in and out
(``docs/formats.md``)."""

from __future__ import annotations

import inspect
from pathlib import Path
from typing import Any, NamedTuple

import typer

from ._common import app, console, err, fail, numbers

_IN_GCODE = "Input: G-code"
_IN_WING = "Input: airfoil panel"
_IN_PAIR = "Input: profile pairs (airfoil, DXF, 3DM)"
_IN_DXF = "Input: DXF"
_IN_3DM = "Input: 3DM"
_IN = "Input"
_OUT_GCODE = "Output: G-code"
_OUT_CAD = "Output: DXF and 3DM"
_OUT = "Output"


class _Opt(NamedTuple):
    """One option of a format: its reader's or writer's key, type, help panel and text; the
    command's parameter is the key (input) or ``out_`` + key (output)."""

    key: str
    kind: Any
    panel: str
    help: str
    decls: tuple[str, ...] = ()


# The reader's options, in the order of ``convert --help``.
_READ = (
    _Opt("tower_distance", float, _IN_GCODE, "G-code in: distance between the towers (m), a "
         "machine setting."),
    _Opt("axes", str, _IN_GCODE, "G-code in: axis letters A-horizontal, A-vertical, "
         "B-horizontal, B-vertical (XYUV, XYZA; XY)."),
    _Opt("units", str, _IN, "In: units of a file that does not say (mm, cm, m, in)."),
    _Opt("distance_mode", str, _IN_GCODE, "G-code in: absolute or relative before any "
         "G90/G91."),
    _Opt("feed_mode", str, _IN_GCODE, "G-code in: how F is meant (path4d, first_tower, "
         "faster_tower, inverse_time)."),
    _Opt("cut", int, _IN_GCODE, "G-code in: which cut (1-based) of several."),
    _Opt("tip", Path, _IN_WING, "Airfoil: the tip profile (.dat)."),
    _Opt("span", float, _IN_WING, "Airfoil: span of the panel (m)."),
    _Opt("root_chord", float, _IN_WING, "Airfoil: root chord (m)."),
    _Opt("tip_chord", float, _IN_WING, "Airfoil: tip chord (m)."),
    _Opt("sweep", float, _IN_WING, "Airfoil: leading-edge sweep (rad)."),
    _Opt("dihedral", float, _IN_WING, "Airfoil: dihedral (rad)."),
    _Opt("twist", float, _IN_WING, "Airfoil: tip twist, + nose up (rad)."),
    _Opt("washout", float, _IN_WING, "Airfoil: washout (rad) = -twist."),
    _Opt("twist_axis", float, _IN_WING, "Airfoil: twist axis, fraction of chord."),
    _Opt("match", str, _IN_PAIR, "Profiles: pair points by 'parameter' or 'index'."),
    _Opt("points", int, _IN_PAIR, "Profiles: number of rulings."),
    _Opt("spacing", str, _IN_PAIR, "Profiles: uniform or cosine resampling."),
    _Opt("layers", list[str], _IN_DXF, "DXF in: the two layers of the profiles (give twice).",
         ("--layers",)),
    _Opt("distance", float, _IN_DXF, "DXF in: put two flat profiles this far apart (m)."),
    _Opt("tolerance", float, _IN_DXF, "DXF in: flattening tolerance (m)."),
    _Opt("layer", str, _IN_3DM, "3DM in: only objects on this layer."),
    _Opt("use", str, _IN_3DM, "3DM in: auto, lines, curves or surface."),
    _Opt("direction", str, _IN_3DM, "3DM in: surface direction of the rulings (u or v)."),
)

# The writer's options (``--out-`` + key), in the order of ``convert --help``.
_WRITE = (
    _Opt("units", str, _OUT, "Out: units (mm default; G-code mm/in)."),
    _Opt("tower_distance", float, _OUT_GCODE, "G-code out: distance between the towers (m)."),
    _Opt("frame", str, _OUT, "Out: cutter frame in the rulings' frame, 'x,y,z,rx,ry,rz' "
         "(m, rad)."),
    _Opt("block_offset", float, _OUT_GCODE, "G-code out: from tower A to the source's first "
         "face (m); default centred."),
    _Opt("axes", str, _OUT_GCODE, "G-code out: axis letters (XYUV, XYZA...)."),
    _Opt("feed_mode", str, _OUT_GCODE, "G-code out: how the controller reads F (inverse_time, "
         "path4d, first_tower, faster_tower)."),
    _Opt("feed", float, _OUT_GCODE, "G-code out: feed (m/s), default 0.005."),
    _Opt("feed_at", str, _OUT_GCODE, "G-code out: where the feed holds: towers or faces."),
    _Opt("faces", str, _OUT_GCODE, "G-code out: z of the block faces in the cutter frame "
         "'z0,z1' (m)."),
    _Opt("heat", str, _OUT_GCODE, "G-code out: M3 (M3/M5), M8 (M8/M9) or none."),
    _Opt("dwell", float, _OUT_GCODE, "G-code out: pre-heat dwell (s)."),
    _Opt("decimals", int, _OUT_GCODE, "G-code out: decimals of coordinates."),
    _Opt("length", float, _OUT_CAD, "DXF/3DM out: length of the drawn rulings (m), for rulings "
         "without ends."),
    _Opt("surface", bool, _OUT_CAD, "3DM out: also the ruled surface.",
         ("--out-surface/--out-no-surface",)),
)

# Values the command line gives in another form than the reader or writer takes.
_READ_AS = {"tip": str, "layers": lambda layers: list(layers) or None}
_WRITE_AS = {"frame": lambda text: numbers(text, "--out-frame", 6),
             "faces": lambda text: numbers(text, "--out-faces", 2)}


def _given(table: tuple[_Opt, ...], values: dict[str, Any], prefix: str,
           convert: dict[str, Any]) -> dict[str, Any]:
    """The options given on the command line (not None), by the format's key."""
    given = {}
    for opt in table:
        value = values[prefix + opt.key]
        if value is not None and opt.key in convert:
            value = convert[opt.key](value)
        if value is not None:
            given[opt.key] = value
    return given


def _with_format_options(command):
    """``command(source, to, out_format, in_format, **options)`` with the reader's and the
    writer's options of the tables as typer options (after its own parameters)."""
    own = list(inspect.signature(command, eval_str=True).parameters.values())[:-1]
    options = [inspect.Parameter(prefix + opt.key, inspect.Parameter.KEYWORD_ONLY,
                                 annotation=opt.kind | None,
                                 default=typer.Option(None, *opt.decls, rich_help_panel=opt.panel,
                                                      help=opt.help))
               for prefix, table in (("", _READ), ("out_", _WRITE)) for opt in table]
    params = own + options
    command.__signature__ = inspect.Signature(params, return_annotation=None)
    command.__annotations__ = {p.name: p.annotation for p in params} | {"return": None}
    return command


@app.command(
    "convert",
    epilog="Examples:  ruledrobot convert wing.ngc --to wing.json --tower-distance 0.8\n\n"
    "ruledrobot convert root.dat --tip tip.dat --span 0.3 --root-chord 0.2 --to panel.dxf\n\n"
    "ruledrobot convert out/cut/refined.json --to cut.ngc --out-tower-distance 0.8   "
    "(formats and options: docs/formats.md)",
)
@_with_format_options
def convert_cmd(
    source: Path = typer.Argument(..., help="Input: .json/.csv lines, .ngc/.gcode G-code, .dat "
                                  "airfoil (root), .dxf, .3dm; or an .stl/.obj mesh (to .3dm)."),
    to: Path = typer.Option(..., "--to", "-o", help="Output file; its suffix chooses the format "
                            "(.json .csv .ngc .gcode .nc .tap .dxf .3dm)."),
    out_format: str | None = typer.Option(None, "--format", help="Output kind when the suffix "
                                          "does not say: lines, gcode, dxf, rhino."),
    in_format: str | None = typer.Option(None, "--from", help="Input kind when the suffix "
                                         "does not say: lines, gcode, airfoil, dxf, rhino."),
    **options: Any,
) -> None:
    """Convert rulings between formats (G-code, airfoil, DXF, Rhino 3DM, lines files).

    The formats: foam-cutter G-code, airfoil .dat pairs, DXF, Rhino 3DM and lines files (and
    a mesh to 3DM).  Options of the input are plain, options of the
    output start with --out-.  Lengths in metres, angles in radians.
    """
    from ..io.formats.convert import convert

    try:
        done = convert(source, to, source_kind=in_format, target_kind=out_format,
                       read_options=_given(_READ, options, "", _READ_AS),
                       write_options=_given(_WRITE, options, "out_", _WRITE_AS),
                       cli=True)  # fmt: skip
    except ValueError as exc:
        raise fail(str(exc)) from None
    for note in done.notes:
        err.print(f"note: {note}", highlight=False, markup=False)
    what = "triangles" if done.source_kind == "mesh" else "rulings"
    shape = " (closed)" if done.closed else ""
    console.print(f"{done.source} ({done.source_kind}): {done.count} {what}{shape}",
                  highlight=False, markup=False)  # fmt: skip
    console.print(f"wrote {done.target}  ({done.target_kind})", highlight=False, markup=False)
