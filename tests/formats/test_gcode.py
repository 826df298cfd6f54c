"""Foam-cutter G-code: reading (interpreter, rulings), writing, round trips, bad files."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.io.formats.gcode import GcodeReadOptions, read_gcode, read_gcode_moves
from ruledrobot.io.formats.gcode_write import GcodeWriteOptions, gcode_text, write_gcode
from ruledrobot.io.formats.rulings import Planes, Rulings, plane_ends

STYLE = """\
( a program in the style foam software writes: preamble, heat, dwell, feed )
%
G90 G17 G21
G92 X0 Y0 U0 V0          ; the user jogged to work zero
G0 X10 Y20 U12 V22
M3                       ; wire on
G4 P1.5                  ; pre-heat
G1 X20 Y20 U25 V22 F300
N40 G1 X20 Y30           (tower A alone: U V hold)
G1 U25 V33
X20 Y30                  ; modal G1, a move of length zero
M5
G0 X0 Y0 U0 V0
M30
G1 X999 Y999 U999 V999   ; after the end: not read
"""


def write(tmp_path, text, name="a.ngc"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_a_foam_program_reads_as_the_wire_positions_of_its_cut(tmp_path):
    r = read_gcode(write(tmp_path, STYLE), GcodeReadOptions(tower_distance=0.5))
    want = np.array([[10, 20, 12, 22], [20, 20, 25, 22], [20, 30, 25, 22], [20, 30, 25, 33]])
    np.testing.assert_allclose(r.ends[:, 0, :2], want[:, :2] * 1e-3, atol=1e-15)
    np.testing.assert_allclose(r.ends[:, 1, :2], want[:, 2:] * 1e-3, atol=1e-15)
    np.testing.assert_allclose(r.ends[:, :, 2], [[0.0, 0.5]] * 4)
    # each ruling is the line through its tower points (cutter frame)
    d = r.ends[:, 1] - r.ends[:, 0]
    np.testing.assert_allclose(r.lines.direction, d / np.linalg.norm(d, axis=1)[:, None])
    assert r.planes.distance == 0.5 and not r.closed
    assert any("length zero (line 11)" in n for n in r.notes)
    # F300 mm/min on the 4-D path (GRBL's reading): the faster tower is slower than F
    da, db = 10.0, 13.0
    np.testing.assert_allclose(r.feed[0], 5e-3 * db / np.hypot(da, db))
    np.testing.assert_allclose(r.feed[1:], 5e-3)


@pytest.mark.parametrize(("mode", "first"), [("path4d", 5e-3 * 13 / np.hypot(10, 13)),
                                             ("first_tower", 5e-3 * 13 / 10),
                                             ("faster_tower", 5e-3),
                                             # F300 as 1/min: 0.2 s for 13 mm
                                             ("inverse_time", 0.013 * 300 / 60)])
def test_feed_modes_read_f_as_their_controllers_do(tmp_path, mode, first):
    r = read_gcode(write(tmp_path, STYLE), GcodeReadOptions(0.5, feed_mode=mode))
    np.testing.assert_allclose(r.feed[0], first)


def test_modal_state_offsets_relative_moves_and_inches(tmp_path):
    text = """G20 G91
G92 X1 Y1 U1 V1
G1 X1 F10
G90
G92 X0 Y0 U0 V0
G1 X1 Y1 U1 V1
G92.1
G1 X0
"""
    mv = read_gcode_moves(write(tmp_path, text), GcodeReadOptions(1.0))
    inch = 0.0254
    np.testing.assert_allclose(mv.start[0], [inch] * 4)
    np.testing.assert_allclose(mv.end[0], [2 * inch, inch, inch, inch])
    # G92 X0 at x = 2 in: program X1 is machine 3 in
    np.testing.assert_allclose(mv.end[1], [3 * inch, 2 * inch, 2 * inch, 2 * inch])
    # G92.1 clears the offset: X0 is the first system's 0
    np.testing.assert_allclose(mv.end[2], [0.0, 2 * inch, 2 * inch, 2 * inch])
    assert mv.units == "in" and mv.units_given
    np.testing.assert_allclose(mv.duration[0], inch / (10 * inch / 60))


@pytest.mark.parametrize("axes", ["XYZA", "XYZB", "XYUV"])
def test_axis_mappings(tmp_path, axes):
    a = axes
    text = (f"G21 G90\nG0 {a[0]}0 {a[1]}0 {a[2]}0 {a[3]}0\n"
            f"G1 {a[0]}10 {a[1]}5 {a[2]}20 {a[3]}7 F100\n")
    r = read_gcode(write(tmp_path, text), GcodeReadOptions(0.8, axes=axes))
    np.testing.assert_allclose(r.ends[1], [[0.01, 0.005, 0.0], [0.02, 0.007, 0.8]])


def test_two_axis_files_copy_the_first_tower_and_refuse_u_v(tmp_path):
    r = read_gcode(write(tmp_path, "G0 X0 Y0\nG1 X10 Y5 F100\n"), GcodeReadOptions(0.3, axes="XY"))
    np.testing.assert_allclose(r.ends[:, 0, :2], r.ends[:, 1, :2])
    with pytest.raises(ValueError, match=r"line 2: axis word 'U1' is not an axis of the mapping "
                                         r"XY \(a 2-axis file"):
        read_gcode(write(tmp_path, "G0 X0 Y0\nG1 X10 U1\n"), GcodeReadOptions(0.3, axes="XY"))


def test_negative_tower_distance_mirrors(tmp_path):
    p = write(tmp_path, STYLE)
    a = read_gcode(p, GcodeReadOptions(0.5))
    b = read_gcode(p, GcodeReadOptions(-0.5))
    np.testing.assert_allclose(b.ends[..., 2], -a.ends[..., 2])
    np.testing.assert_allclose(b.ends[..., :2], a.ends[..., :2])


def test_several_cuts_need_a_choice(tmp_path):
    text = "G0 X0 Y0 U0 V0\nM3\nG1 X1 F9\nM5\nG0 X5\nM3\nG1 X6\nG1 X7 Y1\nM5\n"
    p = write(tmp_path, text)
    with pytest.raises(ValueError, match=r"holds 2 cuts \(1: lines 3-3, 2: lines 7-8\); choose"):
        read_gcode(p, GcodeReadOptions(0.5))
    r = read_gcode(p, GcodeReadOptions(0.5, cut=2))
    np.testing.assert_allclose(r.ends[:, 0, 0], [0.005, 0.006, 0.007])
    with pytest.raises(ValueError, match=r"cut = 3, but the file holds 2 cut"):
        read_gcode(p, GcodeReadOptions(0.5, cut=3))


def test_without_heat_codes_every_g1_run_cuts(tmp_path):
    r = read_gcode(write(tmp_path, "G0 X0 Y0 U0 V0\nG1 X1 F9\nG1 Y1\n"), GcodeReadOptions(0.5))
    assert len(r) == 3


@pytest.mark.parametrize(
    ("text", "options", "message"),
    [
        ("G0 X0 Y0 U0 V0\nG1 X1 Q3\n", {}, r"line 2: unknown word 'Q3'"),
        ("G0 X0 Y0 U0 V0\nG1 X1 Z3\n", {}, r"line 2: axis word 'Z3' is not an axis of the "
                                           r"mapping XYUV"),
        ("G0 X0 Y0 U0 V0\nG2 X1 Y1 I1 J0\n", {}, r"line 2: G2 is an arc"),
        ("G0 X0 Y0 U0 V0\nG1 X1 I1\n", {}, r"line 2: unknown word 'I1'"),
        ("G0 X0 Y0 U0 V0\nG2 X1 Y1\n", {}, r"line 2: G2 is an arc; arcs are not defined"),
        ("G0 X0 Y0 U0 V0\nG03 X1 Y1\n", {}, r"line 2: G3 is an arc"),
        ("G91\nG1 X1 Y1 U1 V1 F5\n", {}, r"line 2: relative move \(G91\) of X Y U V without a "
                                        r"start"),
        ("G0 X0 Y0\nG1 X1 F5\n", {}, r"line 2: cutting move \(G1\) from an unknown position of "
                                     r"U V"),
        ("G20\n", {"units": "mm"}, r"line 1: G20 says the file is in in, but units = 'mm' was "
                                   r"given \(unit mismatch\)"),
        ("G0 X0 (open comment\n", {}, r"line 1: unbalanced or nested"),
        ("G0 X0 Y0 U0 V0\nG4\n", {}, r"line 2: G4 \(dwell\) without P"),
        ("G0 X0 Y0 U0 V0\nG1 X1.2.3\n", {}, r"line 2: cannot read '\.3'"),
        ("G0 X0 Y0 U0 V0\nG1 X1 X2\n", {}, r"line 2: X given twice"),
        ("G0 X0 Y0 U0 V0\nG1 X1 F0\n", {}, r"line 2: F0: expected F > 0"),
        ("G0 X0 Y0 U0 V0\nG93\nG1 X1\n", {}, r"line 3: G1 in inverse time mode \(G93\) without F"),
        ("G0 X0 Y0 U0 V0\nG53 X1\n", {}, r"line 2: G53 is not supported"),
        ("M6\n", {}, r"line 1: M6 is not supported"),
        ("X1 Y1 U1 V1\n", {}, r"line 1: axis words without G0 or G1"),
        ("G92\n", {}, r"line 1: G92 without axis words"),
        ("G0 X0 Y0 U0 V0\nG0 X5\n", {}, r"no cutting move \(G1\)"),
        ("G0 X0 Y0 U0 V0\nM3\nG1 X0\nM5\n", {}, r"the cut at lines 3-3 does not move"),
        ("G0 X0 Y0 U0 V0\nG28\nG1 X1 F5\n", {}, r"line 3: cutting move \(G1\) from an unknown"),
        ("G0 X0 Y0 U0 V0\nG1 X1 F5 P2\n", {}, r"line 2: P without G4"),
    ],
)
def test_bad_files_name_the_line_and_what_was_expected(tmp_path, text, options, message):
    with pytest.raises(ValueError, match=message) as info:
        read_gcode(write(tmp_path, text), GcodeReadOptions(0.5, **options))
    assert str(tmp_path / "a.ngc") in str(info.value)


def test_a_wire_parallel_to_the_towers_cannot_be_written(tmp_path):
    rulings = Rulings(__import__("ruledrobot").Lines.from_point_direction(
        [[0, 0, 0], [0, 0.1, 0]], [[1, 0, 0], [0, 0, 1]]))
    with pytest.raises(ValueError, match=r"ruling 0 is parallel to the planes"):
        write_gcode(tmp_path / "b.ngc", rulings, GcodeWriteOptions(tower_distance=0.5,
                                                                   frame=np.eye(4)))
    with pytest.raises(ValueError, match=r"tower_distance: missing; these rulings come with no "
                                         r"towers"):
        write_gcode(tmp_path / "b.ngc", rulings)
    assert not (tmp_path / "b.ngc").exists()


coords = st.lists(
    st.tuples(*[st.integers(-300_000, 300_000).map(lambda k: k / 1000)] * 4),
    min_size=2, max_size=30, unique=True,
)


@given(coords, st.sampled_from(["XYUV", "XYZA"]),
       st.floats(0.2, 1.5).map(lambda d: round(d, 3)), st.sampled_from(["mm", "in"]))
def test_round_trip_reproduces_the_tower_coordinates(tmp_path_factory, pts, axes, dist, units):
    """G-code -> rulings -> G-code -> rulings: the towers' coordinates to 1e-6 mm, in the
    file's units, whatever the mapping, the tower distance and the units."""
    tmp = tmp_path_factory.mktemp("rt")
    q = np.array(pts)
    if (np.hypot(*(q[:, 2:] - q[:, :2]).T) > 1e3).any():
        q[:, 2:] = q[:, :2] + 0.5  # keep the wire from lying nearly in a tower plane
    unit_word = "G21" if units == "mm" else "G20"
    words = [" ".join(f"{a}{v}" for a, v in zip(axes, row, strict=True)) for row in q]
    lines = [f"G90 {unit_word}", "G0 " + words[0], "M3"]
    lines += ["G1 " + w + " F300" for w in words[1:]]
    src = write(tmp, "\n".join(lines) + "\nM5\n")
    first = read_gcode(src, GcodeReadOptions(dist, axes=axes))
    out = write_gcode(tmp / "b.ngc", first, GcodeWriteOptions(axes=axes, units=units))
    again = read_gcode(out, GcodeReadOptions(dist, axes=axes))
    scale = 1e-3 if units == "mm" else 0.0254
    moved = np.r_[True, np.any(q[1:] != q[:-1], axis=1)]
    want = q[moved]
    got = np.concatenate([again.ends[:, 0, :2], again.ends[:, 1, :2]], axis=1) / scale
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6 * (1e-3 / scale))
    np.testing.assert_allclose(again.ends[:, 1, 2], dist)


@pytest.mark.parametrize("mode", ["inverse_time", "path4d", "first_tower", "faster_tower"])
@pytest.mark.parametrize("where", ["towers", "faces"])
def test_written_feed_holds_where_the_user_says(tmp_path, mode, where):
    """Read back with the controller's reading of F, the faster reference point of every
    move runs at the feed."""
    rng = np.random.default_rng(3)
    q = np.cumsum(rng.uniform(-10, 10, size=(12, 4)), axis=0) * 1e-3
    ends = np.zeros((12, 2, 3))
    ends[:, 0, :2], ends[:, 1, :2], ends[:, 1, 2] = q[:, :2], q[:, 2:], 0.8
    lines = __import__("ruledrobot").Lines.from_two_points(ends[:, 0], ends[:, 1])
    rulings = Rulings(lines, ends=ends, planes=Planes(np.eye(4), 0.8, "towers"))
    faces = (0.3, 0.5)
    opts = GcodeWriteOptions(feed=0.004, feed_at=where, faces=faces, feed_mode=mode,
                             decimals=6)
    out = write_gcode(tmp_path / "f.ngc", rulings, opts)
    text = out.read_text()
    assert ("G93" in text) == (mode == "inverse_time")
    mv = read_gcode_moves(out, GcodeReadOptions(0.8, feed_mode=mode if mode != "inverse_time"
                                                else "path4d"))
    cut = ~mv.rapid
    if where == "towers":
        a, b = mv.start[cut], mv.end[cut]
        da, db = np.hypot(*(b - a)[:, :2].T), np.hypot(*(b - a)[:, 2:].T)
        speed = np.maximum(da, db) / mv.duration[cut]
    else:
        again = read_gcode(out, GcodeReadOptions(0.8))
        ref = plane_ends(again.lines, Planes(_shift(faces[0]), faces[1] - faces[0]))
        step = np.linalg.norm(np.diff(ref[..., :2], axis=0), axis=2).max(axis=1)
        speed = step / mv.duration[cut]
    np.testing.assert_allclose(speed, 0.004, rtol=2e-5)


def _shift(z):
    T = np.eye(4)
    T[2, 3] = z
    return T


def test_program_shape_heat_dwell_units(tmp_path):
    r = read_gcode(write(tmp_path, STYLE), GcodeReadOptions(0.5))
    text = gcode_text(r, GcodeWriteOptions(units="in", heat="m8", dwell=2.0, feed_mode="path4d"))
    body = [ln for ln in text.splitlines() if not ln.startswith("(")]
    assert body[:4] == ["G90 G17 G20", "G0 X0.3937 Y0.7874 U0.4724 V0.8661", "M8", "G4 P2"]
    assert body[-2:] == ["M9", "M30"] and "G93" not in text
    none = gcode_text(r, GcodeWriteOptions(heat="none"))
    assert not {"M3", "M5", "M8", "M9"} & set(none.splitlines())


def test_a_panel_is_placed_between_the_towers(tmp_path):
    """Rulings with faces (a wing panel 0.4 m wide) on a cutter with towers 0.8 m apart:
    centred by default, or block_offset from tower A; the feed at the faces defaults to
    the panel's faces.  The written towers carry the same lines."""
    from ruledrobot.io.formats.wing import WingOptions, read_wing

    from .naca import naca4, selig_text

    (tmp_path / "r.dat").write_text(selig_text("NACA 2412", naca4("2412", 41)))
    wing = read_wing(WingOptions(tmp_path / "r.dat", 0.4, 0.25, tip_chord=0.15))
    with pytest.raises(ValueError, match=r"planes that are faces, not towers"):
        gcode_text(wing, GcodeWriteOptions())
    for offset, shift in ((None, 0.2), (0.1, 0.1)):
        out = write_gcode(tmp_path / "w.ngc", wing, GcodeWriteOptions(
            tower_distance=0.8, block_offset=offset, feed_at="faces", decimals=6))
        back = read_gcode(out, GcodeReadOptions(0.8, feed_mode="path4d"))
        # the root face of the panel is the plane z = shift of the cutter frame
        moved = np.eye(4)
        moved[2, 3] = shift
        again = plane_ends(back.lines, Planes(moved, 0.4))
        np.testing.assert_allclose(again, wing.ends + np.array([0.0, 0.0, shift]), atol=2e-9)
