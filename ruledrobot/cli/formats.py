"""The ``convert`` command: the file formats of hot-wire cutting and CAD, in and out
(``docs/formats.md``)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import app, console, err, fail

_IN_GCODE = "Input: G-code"
_IN_WING = "Input: airfoil panel"
_IN_PAIR = "Input: profile pairs (airfoil, DXF, 3DM)"
_IN_DXF = "Input: DXF"
_IN_3DM = "Input: 3DM"
_IN = "Input"
_OUT_GCODE = "Output: G-code"
_OUT_CAD = "Output: DXF and 3DM"
_OUT = "Output"


def _numbers(text: str | None, n: int, option: str) -> list[float] | None:
    """``"a,b,c"`` -> n floats, or None; a ValueError names the option."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.replace(" ", "").split(",")]
    except ValueError:
        values = []
    if len(values) != n:
        raise ValueError(f"{option}: expected {n} comma-separated numbers, got {text!r}")
    return values


@app.command(
    "convert",
    epilog="Examples:  ruledrobot convert wing.ngc --to wing.json --tower-distance 0.8\n\n"
    "ruledrobot convert root.dat --tip tip.dat --span 0.3 --root-chord 0.2 --to panel.dxf\n\n"
    "ruledrobot convert out/cut/refined.json --to cut.ngc --out-tower-distance 0.8   "
    "(formats and options: docs/formats.md)",
)
def convert_cmd(
    source: Path = typer.Argument(..., help="Input: .json/.csv lines, .ngc/.gcode G-code, .dat "
                                  "airfoil (root), .dxf, .3dm; or an .stl/.obj mesh (to .3dm)."),
    to: Path = typer.Option(..., "--to", "-o", help="Output file; its suffix chooses the format "
                            "(.json .csv .ngc .gcode .nc .tap .dxf .3dm)."),
    out_format: str | None = typer.Option(None, "--format", help="Output kind when the suffix "
                                          "does not say: lines, gcode, dxf, rhino."),
    in_format: str | None = typer.Option(None, "--from", help="Input kind when the suffix "
                                         "does not say: lines, gcode, airfoil, dxf, rhino."),
    tower_distance: float | None = typer.Option(None,
        rich_help_panel=_IN_GCODE, help="G-code in: distance between the "
                                                "towers (m), a machine setting."),
    axes: str | None = typer.Option(None,
        rich_help_panel=_IN_GCODE, help="G-code in: axis letters A-horizontal, "
                                    "A-vertical, B-horizontal, B-vertical (XYUV, XYZA; XY)."),
    units: str | None = typer.Option(None,
        rich_help_panel=_IN, help="In: units of a file that does not say "
                                     "(mm, cm, m, in)."),
    distance_mode: str | None = typer.Option(None,
        rich_help_panel=_IN_GCODE, help="G-code in: absolute or relative "
                                             "before any G90/G91."),
    feed_mode: str | None = typer.Option(None,
        rich_help_panel=_IN_GCODE, help="G-code in: how F is meant (path4d, "
                                         "first_tower, faster_tower, inverse_time)."),
    cut: int | None = typer.Option(None,
        rich_help_panel=_IN_GCODE, help="G-code in: which cut (1-based) of several."),
    tip: Path | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: the tip profile (.dat)."),
    span: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: span of the panel (m)."),
    root_chord: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: root chord (m)."),
    tip_chord: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: tip chord (m)."),
    sweep: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: leading-edge sweep (rad)."),
    dihedral: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: dihedral (rad)."),
    twist: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: tip twist, + nose up (rad)."),
    washout: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: washout (rad) = -twist."),
    twist_axis: float | None = typer.Option(None,
        rich_help_panel=_IN_WING, help="Airfoil: twist axis, fraction of chord."),
    match: str | None = typer.Option(None,
        rich_help_panel=_IN_PAIR, help="Profiles: pair points by 'parameter' or "
                                     "'index'."),
    points: int | None = typer.Option(None,
        rich_help_panel=_IN_PAIR, help="Profiles: number of rulings."),
    spacing: str | None = typer.Option(None,
        rich_help_panel=_IN_PAIR, help="Profiles: uniform or cosine resampling."),
    layers: list[str] | None = typer.Option(None, "--layers",
        rich_help_panel=_IN_DXF, help="DXF in: the two layers "
                                            "of the profiles (give twice)."),
    distance: float | None = typer.Option(None,
        rich_help_panel=_IN_DXF, help="DXF in: put two flat profiles this far "
                                          "apart (m)."),
    tolerance: float | None = typer.Option(None,
        rich_help_panel=_IN_DXF, help="DXF in: flattening tolerance (m)."),
    layer: str | None = typer.Option(None,
        rich_help_panel=_IN_3DM, help="3DM in: only objects on this layer."),
    use: str | None = typer.Option(None,
        rich_help_panel=_IN_3DM, help="3DM in: auto, lines, curves or surface."),
    direction: str | None = typer.Option(None,
        rich_help_panel=_IN_3DM, help="3DM in: surface direction of the "
                                         "rulings (u or v)."),
    out_units: str | None = typer.Option(None,
        rich_help_panel=_OUT, help="Out: units (mm default; G-code mm/in)."),
    out_tower_distance: float | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: distance between "
                                                    "the towers (m)."),
    out_frame: str | None = typer.Option(None,
        rich_help_panel=_OUT, help="Out: cutter frame in the rulings' frame, "
                                         "'x,y,z,rx,ry,rz' (m, rad)."),
    out_block_offset: float | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: from tower A to the "
                                                  "source's first face (m); default centred."),
    out_axes: str | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: axis letters (XYUV, XYZA...)."),
    out_feed_mode: str | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: how the controller reads F "
                                             "(inverse_time, path4d, first_tower, "
                                             "faster_tower)."),
    out_feed: float | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: feed (m/s), default 0.005."),
    out_feed_at: str | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: where the feed holds: "
                                           "towers or faces."),
    out_faces: str | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: z of the block faces in the "
                                         "cutter frame 'z0,z1' (m)."),
    out_heat: str | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: M3 (M3/M5), M8 (M8/M9) or "
                                        "none."),
    out_dwell: float | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: pre-heat dwell (s)."),
    out_decimals: int | None = typer.Option(None,
        rich_help_panel=_OUT_GCODE, help="G-code out: decimals of coordinates."),
    out_length: float | None = typer.Option(None,
        rich_help_panel=_OUT_CAD, help="DXF/3DM out: length of the drawn "
                                            "rulings (m), for rulings without ends."),
    out_surface: bool | None = typer.Option(None, "--out-surface/--out-no-surface",

        rich_help_panel=_OUT_CAD, help="3DM out: also the ruled surface."),
) -> None:
    """Convert rulings between formats: foam-cutter G-code, airfoil .dat pairs, DXF, Rhino
    3DM and lines files (and a mesh to 3DM).  Options of the input are plain, options of
    the output start with --out-.  Lengths in metres, angles in radians."""
    from ..io.formats.convert import convert

    try:
        read = {"tower_distance": tower_distance, "axes": axes, "units": units,
                "distance_mode": distance_mode, "feed_mode": feed_mode, "cut": cut,
                "tip": None if tip is None else str(tip), "span": span,
                "root_chord": root_chord, "tip_chord": tip_chord, "sweep": sweep,
                "dihedral": dihedral, "twist": twist, "washout": washout,
                "twist_axis": twist_axis, "match": match, "points": points, "spacing": spacing,
                "layers": list(layers) if layers else None, "distance": distance,
                "tolerance": tolerance, "layer": layer, "use": use, "direction": direction}
        write = {"units": out_units, "tower_distance": out_tower_distance,
                 "frame": _numbers(out_frame, 6, "--out-frame"), "axes": out_axes,
                 "block_offset": out_block_offset,
                 "feed_mode": out_feed_mode, "feed": out_feed, "feed_at": out_feed_at,
                 "faces": _numbers(out_faces, 2, "--out-faces"), "heat": out_heat,
                 "dwell": out_dwell, "decimals": out_decimals, "length": out_length,
                 "surface": out_surface}
        done = convert(source, to, source_kind=in_format, target_kind=out_format,
                       read_options={k: v for k, v in read.items() if v is not None},
                       write_options={k: v for k, v in write.items() if v is not None},
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
