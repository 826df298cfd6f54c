"""DXF and Rhino 3DM: NACA wing round trips, profile pairs drawn in CAD, bad files."""

from __future__ import annotations

import sys

import ezdxf
import numpy as np
import pytest
import rhino3dm

import ruledrobot as rr
from ruledrobot.io.formats import Rulings
from ruledrobot.io.formats.cad_common import CadWriteOptions, MatchOptions
from ruledrobot.io.formats.dxf import DxfOptions, read_dxf, write_dxf
from ruledrobot.io.formats.rhino import RhinoOptions, read_rhino
from ruledrobot.io.formats.rhino_write import write_mesh_3dm, write_rhino
from ruledrobot.io.formats.rulings import fit_planes, plane_ends
from ruledrobot.io.formats.wing import WingOptions, read_wing

from .naca import naca4, selig_text


@pytest.fixture
def wing(tmp_path):
    (tmp_path / "root.dat").write_text(selig_text("NACA 2412", naca4("2412", 81)))
    (tmp_path / "tip.dat").write_text(selig_text("NACA 0012", naca4("0012", 61)))
    return read_wing(WingOptions(tmp_path / "root.dat", 0.3, 0.2, tip=tmp_path / "tip.dat",
                                 tip_chord=0.12, sweep=0.15, twist=-0.03, points=121))


@pytest.mark.parametrize("units", ["mm", "m", "in", "cm"])
def test_naca_wing_round_trips_through_dxf(tmp_path, wing, units):
    out = write_dxf(tmp_path / "w.dxf", wing, CadWriteOptions(units=units))
    doc = ezdxf.readfile(out)
    assert doc.header["$INSUNITS"] == {"in": 1, "mm": 4, "cm": 5, "m": 6}[units]
    assert len(doc.modelspace().query('LINE[layer=="RULINGS"]')) == len(wing)
    back = read_dxf(out)
    np.testing.assert_allclose(back.ends, wing.ends, atol=1e-15)
    np.testing.assert_allclose(back.lines.plucker, wing.lines.plucker, atol=1e-14)
    assert back.planes.distance == pytest.approx(0.3) and not back.notes


def test_naca_wing_round_trips_through_3dm(tmp_path, wing):
    out = write_rhino(tmp_path / "w.3dm", wing)
    model = rhino3dm.File3dm.Read(str(out))
    assert model.Settings.ModelUnitSystem == rhino3dm.UnitSystem.Millimeters
    assert sorted(layer.Name for layer in model.Layers) == ["end_a", "end_b", "rulings",
                                                            "surface"]
    for opts in (RhinoOptions(), RhinoOptions(layer="surface"),
                 RhinoOptions(layer="end_a", use="lines")):
        if opts.layer == "end_a":
            with pytest.raises(ValueError, match=r"use = lines needs at least two line curves"):
                read_rhino(out, opts)
            continue
        back = read_rhino(out, opts)
        np.testing.assert_allclose(back.ends, wing.ends, atol=1e-15)
        np.testing.assert_allclose(back.lines.plucker, wing.lines.plucker, atol=1e-14)


def test_two_layers_drawn_flat_in_ezdxf_make_a_panel(tmp_path):
    """The usual foam drawing: root and tip on two layers, both in XY, in mm."""
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    root = naca4("2412", 41) * 200.0
    tip = naca4("0012", 41) * 120.0 + [40.0, 0.0]
    msp.add_lwpolyline(root.tolist(), dxfattribs={"layer": "ROOT"})
    msp.add_lwpolyline(tip[::-1].tolist(), dxfattribs={"layer": "TIP"})  # drawn the other way
    msp.add_line((0, 0), (300, 0), dxfattribs={"layer": "FRAME"})
    doc.saveas(tmp_path / "pair.dxf")
    with pytest.raises(ValueError, match=r"3 curves \(by layer: ROOT \(1\), TIP \(1\), FRAME "
                                         r"\(1\)\); expected two profiles"):
        read_dxf(tmp_path / "pair.dxf")
    with pytest.raises(ValueError, match=r"both profiles lie in the plane z = 0; give distance"):
        read_dxf(tmp_path / "pair.dxf", DxfOptions(layers=("ROOT", "TIP")))
    r = read_dxf(tmp_path / "pair.dxf", DxfOptions(layers=("ROOT", "TIP"), distance=0.3,
                                                   pairing=MatchOptions("index")))
    assert any("other way; reversed" in n for n in r.notes)
    np.testing.assert_allclose(r.ends[:, 0, :2], root * 1e-3)
    np.testing.assert_allclose(r.ends[:, 1, :2], tip * 1e-3)
    np.testing.assert_allclose(r.ends[:, 1, 2], 0.3)


def test_closed_profiles_match_seam_and_direction(tmp_path):
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 6
    msp = doc.modelspace()
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    msp.add_lwpolyline(sq.tolist(), close=True, dxfattribs={"layer": "A"})
    msp.add_lwpolyline((np.roll(sq, 2, axis=0)[::-1] * 0.5 + 0.25).tolist(), close=True,
                       dxfattribs={"layer": "B"})
    doc.saveas(tmp_path / "sq.dxf")
    r = read_dxf(tmp_path / "sq.dxf", DxfOptions(layers=("A", "B"), distance=1.0,
                                                 pairing=MatchOptions("index")))
    assert r.closed and len(r) == 4
    np.testing.assert_allclose(r.ends[:, 1, :2], sq * 0.5 + 0.25)  # corner with corner
    assert len(r.path_lines()) == 5


def test_a_3dm_ruled_surface_and_a_pair_of_curves(tmp_path):
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Meters
    a = rhino3dm.NurbsCurve.Create(False, 3, [rhino3dm.Point3d(x, np.sin(x), 0)
                                              for x in np.linspace(0, 3, 7)])
    b = rhino3dm.NurbsCurve.Create(False, 3, [rhino3dm.Point3d(x, 0.5 * np.cos(x), 1)
                                              for x in np.linspace(0, 3, 7)])
    srf = rhino3dm.NurbsSurface.CreateRuledSurface(a, b)
    model.Objects.AddSurface(srf)
    model.Write(str(tmp_path / "s.3dm"), 7)
    r = read_rhino(tmp_path / "s.3dm", RhinoOptions(pairing=MatchOptions(points=40)))
    assert len(r) == 40
    # the iso-curves of a ruled surface are its rulings: midpoints on the surface's lines
    dom0 = srf.Domain(0)
    for k, u in enumerate(np.linspace(dom0.T0, dom0.T1, 40)):
        mid = srf.PointAt(u, 0.5)
        p = np.array([mid.X, mid.Y, mid.Z])
        dist = np.linalg.norm(np.cross(p - r.ends[k, 0], r.lines.direction[k]))
        assert dist < 1e-9
    with pytest.raises(ValueError, match=r"not ruled along u"):
        read_rhino(tmp_path / "s.3dm", RhinoOptions(direction="u"))
    two = rhino3dm.File3dm()
    two.Settings.ModelUnitSystem = getattr(rhino3dm.UnitSystem, "None")
    two.Objects.AddCurve(a)
    two.Objects.AddCurve(b)
    two.Write(str(tmp_path / "c.3dm"), 7)
    r = read_rhino(tmp_path / "c.3dm", RhinoOptions(pairing=MatchOptions(points=25)))
    assert len(r) == 25 and any("no unit system: read as mm" in n for n in r.notes)
    np.testing.assert_allclose(r.ends[:, 1, 2], 1e-3)


def test_a_mesh_goes_to_3dm(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float) * 0.1
    f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    out = write_mesh_3dm(tmp_path / "m.3dm", v, f, units="mm")
    mesh = next(o.Geometry for o in rhino3dm.File3dm.Read(str(out)).Objects)
    got = np.array([[p.X, p.Y, p.Z] for p in (mesh.Vertices[i] for i in range(len(mesh.Vertices)))])
    np.testing.assert_allclose(got, v * 1000, atol=1e-4)  # rhino3dm keeps float32 vertices
    assert mesh.Faces.Count == 4


def test_lines_files_need_a_length_to_be_drawn(tmp_path):
    lines = rr.Lines.from_point_direction([[0, 0, 0], [0.1, 0, 0], [0.2, 0, 0.01]],
                                          [[0, 0, 1], [0, 0.1, 1], [0, 0.2, 1]])
    with pytest.raises(ValueError, match=r"length: missing; these rulings are infinite"):
        write_dxf(tmp_path / "l.dxf", Rulings(lines))
    out = write_dxf(tmp_path / "l.dxf", Rulings(lines), CadWriteOptions(length=0.4))
    back = read_dxf(out)
    planes = fit_planes(lines, 0.4)
    np.testing.assert_allclose(back.ends, plane_ends(lines, planes), atol=1e-15)
    np.testing.assert_allclose(back.lines.plucker, lines.plucker, atol=1e-14)
    np.testing.assert_allclose((back.ends[:, 1] - back.ends[:, 0]) @ planes.pose[:3, 2], 0.4)
    local = (back.ends.reshape(-1, 3) - planes.pose[:3, 3]) @ planes.pose[:3, :3]
    assert local[:, :2].min() > -1e-12  # fitted: every end at x, y >= 0


def dxf_with(tmp_path, build, units=4):
    doc = ezdxf.new("R2010")
    if units is not None:
        doc.header["$INSUNITS"] = units
    build(doc.modelspace())
    doc.saveas(tmp_path / "bad.dxf")
    return tmp_path / "bad.dxf"


@pytest.mark.parametrize(
    ("build", "units", "options", "message"),
    [
        (lambda m: m.add_lwpolyline([(0, 0), (1, 0)], dxfattribs={"layer": "A"}), 4,
         {"layers": ("A", "B")}, r"layer 'B' holds 0 curves; expected one profile"),
        (lambda m: (m.add_lwpolyline([(0, 0), (1, 0), (1, 1)], close=True),
                    m.add_lwpolyline([(0, 0, 1), (1, 0, 1), (1, 1, 1)])), 4, {},
         r"the first curve \(layer 0\) is closed and the second curve \(layer 0\) open"),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 0, 0), (1, 1, 0)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1), (1, 1, 1)])), 4, {"units": "in"},
         r"says its units are mm \(\$INSUNITS = 4\), but units = 'in' was given \(unit mismatch"),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 1, 0), (1, 0, 0), (0, 1, 0)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)])), 4, {},
         r"first curve \(layer 0\): the profile crosses itself"),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 0, 0), (1, 1, 0)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1)])), 4, {"match": "index"},
         r"has 3 points and the second curve \(layer 0\) 2; match = \"index\""),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 0, 0)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1)])), 2, {},
         r"\$INSUNITS = 2 is not supported"),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 0, 0)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1)])), 4, {"distance": 0.3},
         r"but these lie apart already \(z = 0 and 0\.001 m\): remove distance"),
        (lambda m: (m.add_polyline3d([(0, 0, 0), (1, 0, 0.5)]),
                    m.add_polyline3d([(0, 0, 1), (1, 0, 1)])), 4, {"distance": 0.3},
         r"the profiles are not flat in z"),
    ],
)
def test_bad_dxf_files(tmp_path, build, units, options, message):
    p = dxf_with(tmp_path, build, units)
    pairing = {k: options.pop(k) for k in ("match",) if k in options}
    with pytest.raises(ValueError, match=message) as info:
        read_dxf(p, DxfOptions(pairing=MatchOptions(**pairing), **options))
    assert str(p) in str(info.value)


def test_a_file_that_is_not_dxf_or_3dm(tmp_path):
    (tmp_path / "x.dxf").write_text("this is not a drawing\n")
    with pytest.raises(ValueError, match=r"x\.dxf: not a readable DXF file"):
        read_dxf(tmp_path / "x.dxf")
    (tmp_path / "x.3dm").write_bytes(b"\x00" * 100)
    with pytest.raises(ValueError, match=r"x\.3dm: not a readable Rhino \.3dm file"):
        read_rhino(tmp_path / "x.3dm")


def test_bad_3dm_models(tmp_path):
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Feet
    model.Objects.AddSphere(rhino3dm.Sphere(rhino3dm.Point3d(0, 0, 0), 1.0))
    model.Write(str(tmp_path / "feet.3dm"), 7)
    with pytest.raises(ValueError, match=r"unit system Feet is not supported"):
        read_rhino(tmp_path / "feet.3dm")
    model.Settings.ModelUnitSystem = rhino3dm.UnitSystem.Millimeters
    model.Write(str(tmp_path / "sphere.3dm"), 7)
    with pytest.raises(ValueError, match=r"the surface is not ruled"):
        read_rhino(tmp_path / "sphere.3dm")
    with pytest.raises(ValueError, match=r"unit system is Millimeters, but units = 'm' was "
                                         r"given \(unit mismatch\)"):
        read_rhino(tmp_path / "sphere.3dm", RhinoOptions(units="m"))
    with pytest.raises(ValueError, match=r"no layer 'walls'"):
        read_rhino(tmp_path / "sphere.3dm", RhinoOptions(layer="walls"))
    empty = rhino3dm.File3dm()
    empty.Objects.AddPoint(0, 0, 0)
    empty.Write(str(tmp_path / "empty.3dm"), 7)
    with pytest.raises(ValueError, match=r"holds 0 line\(s\), 0 other curve\(s\), 0 surface\(s\), "
                                         r"1 other object\(s\); expected one ruled surface"):
        read_rhino(tmp_path / "empty.3dm")


def test_missing_extra_names_it(tmp_path, monkeypatch, wing):
    """Without ezdxf / rhino3dm the error says which extra to install."""
    monkeypatch.setitem(sys.modules, "ezdxf", None)
    monkeypatch.setitem(sys.modules, "rhino3dm", None)
    with pytest.raises(ValueError, match=r"writing DXF files needs the Python package 'ezdxf', "
                                         r"which is not installed; install the CAD extra: pip "
                                         r"install 'ruledrobot\[cad\]'"):
        write_dxf(tmp_path / "w.dxf", wing)
    with pytest.raises(ValueError, match=r"reading Rhino \.3dm files needs the Python package "
                                         r"'rhino3dm'"):
        read_rhino(tmp_path / "w.3dm")
    assert not (tmp_path / "w.dxf").exists()
