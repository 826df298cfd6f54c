"""Airfoil .dat files (Selig, Lednicer) and wing panels, against NACA 4-digit truth."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.io.formats.airfoil import read_airfoil
from ruledrobot.io.formats.options import Options
from ruledrobot.io.formats.profiles import check_simple, resample
from ruledrobot.io.formats.wing import WingOptions, read_wing

from .naca import distance_to_polyline, lednicer_text, naca4, selig_text


@pytest.fixture
def files(tmp_path):
    (tmp_path / "n2412.dat").write_text(selig_text("NACA 2412", naca4("2412", 81)))
    (tmp_path / "n0012.dat").write_text(lednicer_text("NACA 0012", naca4("0012", 61)))
    return tmp_path


def test_selig_and_lednicer_read_to_one_order(tmp_path):
    pts = naca4("4412", 41)
    (tmp_path / "s.dat").write_text(selig_text("NACA 4412", pts))
    (tmp_path / "l.dat").write_text(lednicer_text("NACA 4412", pts))
    (tmp_path / "r.dat").write_text(selig_text("lower surface first", pts[::-1]))
    (tmp_path / "p.dat").write_text(selig_text("", pts).lstrip("\n"))  # XFOIL's plain file
    s, led = read_airfoil(tmp_path / "s.dat"), read_airfoil(tmp_path / "l.dat")
    assert (s.name, s.format, led.format) == ("NACA 4412", "selig", "lednicer")
    for a in (led, read_airfoil(tmp_path / "r.dat"), read_airfoil(tmp_path / "p.dat")):
        np.testing.assert_allclose(a.points, s.points, atol=1e-9)
    # counter-clockwise: trailing edge, upper surface (y > 0 near mid chord), leading edge
    mid = len(s.points) // 4
    assert s.points[mid, 1] > 0 and np.argmin(s.points[:, 0]) == len(pts) // 2


def test_wing_panel_rulings_end_on_the_analytic_profiles(files):
    """Root NACA 2412 (chord 0.2 m) and tip NACA 0012 (0.12 m, 2 deg washout about the
    quarter chord, 0.05 m sweep, 0.02 m dihedral offset): every ruling's ends lie on the
    exact profiles; leading edge meets leading edge."""
    span, cr, ct, w = 0.3, 0.2, 0.12, np.radians(2.0)
    sweep, dihedral = np.arctan(0.05 / span), np.arctan(0.02 / span)
    r = read_wing(WingOptions(files / "n2412.dat", span, cr, tip=files / "n0012.dat",
                              tip_chord=ct, sweep=sweep, dihedral=dihedral, twist=-w, points=201))
    assert len(r) == 201 and r.planes.distance == span
    c, s = np.cos(w), np.sin(w)  # washout = nose down = counter-clockwise about the pivot
    pivot = np.array([0.25 * ct, 0.0])

    def place_tip(p):
        return (p * ct - pivot) @ np.array([[c, s], [-s, c]]) + pivot + [0.05, 0.02]

    dense_root, dense_tip = naca4("2412", 4001) * cr, place_tip(naca4("0012", 4001))

    def chord_error(poly, dense):  # how far the file's own polyline is from the truth
        return distance_to_polyline(0.5 * (poly[1:] + poly[:-1]), dense).max()

    err_root = chord_error(naca4("2412", 81) * cr, dense_root)
    err_tip = chord_error(place_tip(naca4("0012", 61)), dense_tip)
    assert 1e-6 < err_tip < 1e-4
    root, tip = r.ends[:, 0], r.ends[:, 1]
    np.testing.assert_allclose(root[:, 2], 0.0)
    np.testing.assert_allclose(tip[:, 2], span)
    # resampling the file's polyline: within the polyline's own chord error of the truth
    assert distance_to_polyline(root[:, :2], dense_root).max() < 1.05 * err_root
    assert distance_to_polyline(tip[:, :2], dense_tip).max() < 1.05 * err_tip
    np.testing.assert_allclose(root[100, :2], [0.0, 0.0], atol=1e-12)  # leading edges
    np.testing.assert_allclose(tip[100, :2], pivot + (-pivot) @ np.array([[c, s], [-s, c]])
                               + [0.05, 0.02], atol=1e-12)
    # the washout lowers the tip's leading edge and raises its trailing edge
    assert tip[100, 1] < 0.02 < tip[0, 1]
    # the rulings are the lines through the ends
    d = tip - root
    np.testing.assert_allclose(r.lines.direction, d / np.linalg.norm(d, axis=1)[:, None])


def test_index_matching_pairs_the_files_points(files):
    r = read_wing(WingOptions(files / "n2412.dat", 0.3, 0.2, match="index"))
    np.testing.assert_allclose(r.ends[:, 0, :2], read_airfoil(files / "n2412.dat").points * 0.2)
    with pytest.raises(ValueError, match=r"the root \(n2412\.dat\) has 161 points and the tip "
                                         r"\(n0012\.dat\) 121; match = \"index\""):
        read_wing(WingOptions(files / "n2412.dat", 0.3, 0.2, tip=files / "n0012.dat",
                              match="index"))


def test_wing_options_from_a_job_table(files):
    o = Options({"root": "n2412.dat", "tip": "n0012.dat", "span": 0.3, "root_chord": 0.2,
                 "washout": 0.03}, "job.toml: [surface.airfoil]", base_dir=files)
    w = WingOptions.parse(o)
    assert w.twist == -0.03 and w.tip == files / "n0012.dat"
    bad = [({"root": "n2412.dat", "span": 0.3}, r"\[surface.airfoil\] root_chord: missing"),
           ({"root": "x.dat", "span": 0.3, "root_chord": 0.2}, r"root: no such airfoil file"),
           ({"root": "n2412.dat", "span": 0.3, "root_chord": 0.2, "twist": 0.1,
             "washout": 0.1}, r"twist: give twist or washout, not both"),
           ({"root": "n2412.dat", "span": 0.3, "root_chord": 0.2, "chord": 1},
            r"unknown option\(s\) chord"),
           ({"root": "n2412.dat", "span": 0.3, "root_chord": -0.2}, r"root_chord: expected a "
                                                                    r"number > 0")]
    for raw, message in bad:
        with pytest.raises(ValueError, match=message):
            WingOptions.parse(Options(raw, "job.toml: [surface.airfoil]", base_dir=files))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("NACA\n1 0\n0.5 0.1\nx y\n", r"line 4: expected two numbers 'x y', got 'x y'"),
        ("NACA\n5. 5.\n\n0 0\n0.5 0.1\n1 0\n\n0 0\n0.5 -0.1\n1 0\n",
         r"line 2: Lednicer counts say 5 upper and 5 lower points, the file has 6"),
        ("NACA\n1 0\n0.5 0.1\n0 0\n0.5 -0.1\n", r"4 points; expected at least 5"),
        ("mm\n200 0\n100 20\n0 0\n100 -20\n200 0\n", r"x runs from 0 to 200: not in chord units "
                                                     r"\(unit mismatch"),
        ("bow tie\n1 0\n0.5 0.1\n0 -0.1\n0 0.1\n0.5 -0.1\n1 0\n",
         r"crosses itself: the segment line 3 to line 4 crosses the segment line 5 to line 6"),
        ("", r"empty file"),
        ("just a name\n", r"no coordinates after the name line"),
    ],
)
def test_bad_airfoil_files(tmp_path, text, message):
    p = tmp_path / "bad.dat"
    p.write_text(text)
    with pytest.raises(ValueError, match=message) as info:
        read_airfoil(p)
    assert str(p) in str(info.value)


@given(st.integers(3, 400), st.sampled_from(["uniform", "cosine"]), st.integers(0, 2**31))
def test_resampling_keeps_the_ends_and_stays_on_the_polyline(n, spacing, seed):
    rng = np.random.default_rng(seed)
    poly = np.cumsum(rng.normal(size=(rng.integers(2, 30), 3)), axis=0)
    out = resample(poly, n, spacing)
    assert out.shape == (n, 3)
    np.testing.assert_array_equal(out[[0, -1]], poly[[0, -1]])
    assert distance_to_polyline(out, poly).max() < 1e-9
    steps = np.linalg.norm(np.diff(out, axis=0), axis=1)
    if spacing == "uniform":  # equal arc length: the chords cannot be longer than the steps
        length = np.linalg.norm(np.diff(poly, axis=0), axis=1).sum()
        assert steps.max() <= length / (n - 1) + 1e-9


def test_check_simple_finds_crossings_in_space():
    square = np.array([[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)
    check_simple(square, "ok", closed=True)
    with pytest.raises(ValueError, match=r"crosses itself"):
        check_simple(square[[0, 2, 1, 3]], "bow", closed=True)


def test_missing_file_names_it(tmp_path):
    with pytest.raises(ValueError, match=r"no such airfoil file"):
        read_airfoil(Path(tmp_path) / "none.dat")


def _crosses_brute_force(p: np.ndarray) -> bool:
    def orient(o, q, r):
        return np.sign((q[0] - o[0]) * (r[1] - o[1]) - (q[1] - o[1]) * (r[0] - o[0]))

    m = len(p) - 1
    for i in range(m):
        for j in range(i + 2, m):
            a, b, c, d = p[i], p[i + 1], p[j], p[j + 1]
            if orient(a, b, c) * orient(a, b, d) < 0 and orient(c, d, a) * orient(c, d, b) < 0:
                return True
    return False


@given(st.integers(0, 2**31), st.integers(4, 40), st.floats(0.01, 10.0))
def test_the_grid_finds_the_same_crossings_as_all_pairs(seed, n, step):
    """Random walks, some crossing themselves, some not: the grid-pruned check agrees
    with comparing every pair of segments."""
    rng = np.random.default_rng(seed)
    p = np.cumsum(rng.normal(size=(n, 2)) * rng.uniform(0.05, 1.0, size=(n, 1)) * step, axis=0)
    expected = _crosses_brute_force(p)
    try:
        check_simple(p, "walk")
        found = False
    except ValueError:
        found = True
    assert found == expected


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 120), dim=st.sampled_from([2, 3]),
       scale=st.floats(0.001, 1.0))  # fmt: skip
def test_the_polyline_distance_is_the_least_over_every_segment(seed, n, dim, scale):
    """The test helper's k-d tree shortcut (tests/formats/naca.py) against every point
    with every segment, a segment of zero length among them."""
    rng = np.random.default_rng(seed)
    poly = np.cumsum(rng.normal(size=(n, dim)) * scale, axis=0)
    poly[n // 2] = poly[n // 2 - 1]
    q = rng.normal(size=(50, dim)) * scale * np.sqrt(n)
    a, ab = poly[:-1], np.diff(poly, axis=0)
    t = np.clip(np.einsum("kni,ni->kn", q[:, None] - a[None], ab)
                / (ab * ab).sum(1).clip(1e-30), 0, 1)  # fmt: skip
    every = np.linalg.norm(q[:, None] - (a[None] + t[..., None] * ab[None]), axis=2).min(axis=1)
    np.testing.assert_allclose(distance_to_polyline(q, poly), every, rtol=0.0, atol=1e-12)
