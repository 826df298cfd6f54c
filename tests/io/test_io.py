"""Lines files: JSON and CSV round trips, errors naming file and item, atomic writes."""

from __future__ import annotations

import json

import numpy as np
import pytest

import ruledrobot as rr


@pytest.fixture
def lines(rng):
    return rr.Lines.from_point_direction(rng.normal(size=(7, 3)), rng.normal(size=(7, 3)))


def test_json_round_trip(tmp_path, lines):
    p = rr.save_lines(tmp_path / "a.json", lines, closed=True)
    doc = rr.read_lines_document(p)
    assert doc.closed
    np.testing.assert_allclose(doc.lines.plucker, lines.plucker, atol=1e-15)
    raw = json.loads(p.read_text())
    assert raw["format"] == "ruledrobot.lines/1" and raw["units"] == "m"


def test_json_plucker_rows_frames_striction(tmp_path, lines):
    res = rr.refine(lines, "dh", "four_point", 1)
    p = rr.save_lines(
        tmp_path / "r.json", res.lines, frames=res.frames, striction=res.striction, plucker=True
    )
    doc = rr.read_lines_document(p)
    np.testing.assert_allclose(doc.lines.plucker, res.lines.plucker, atol=1e-15)
    np.testing.assert_allclose(doc.frames, res.frames)
    np.testing.assert_allclose(doc.striction, res.striction)


def test_csv_round_trip(tmp_path, lines):
    p = rr.save_lines(tmp_path / "a.csv", lines, closed=True)
    assert p.read_text().splitlines()[1] == "px,py,pz,dx,dy,dz"
    doc = rr.read_lines_document(p)
    assert doc.closed
    np.testing.assert_allclose(doc.lines.plucker, lines.plucker, atol=1e-15)


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("a.json", '{\n  "lines": [1, 2,\n', r"a\.json: line \d+: not valid JSON"),
        ("a.json", '{"lines": [{"point": [0, 0, 0]}]}', r"lines\[0\] lacks \['direction'\]"),
        (
            "a.json",
            '{"lines": [{"point": [0,0,0], "direction": [1,0,0]},'
            ' {"point": [0,0,0], "direction": [0,0,0]}]}',
            r"lines\[1\]\.direction is the zero",
        ),
        ("a.json", '{"lines": [[1, 0, 0, 0, 1, 0], [1, 0, 0, 1, 0, 0]]}', r"lines\[1\]: l \. m"),
        ("a.json", '{"format": "other/2", "lines": []}', r"format 'other/2' is not supported"),
        ("a.json", '{"units": "furlong", "lines": []}', r"'units': unknown length unit 'furlong'"),
        ("a.csv", "px,py,pz,dx,dy,dz\n# units: mm\n0,0,0,1,0,0\n", r"line 2: '# units:' must come"),
        ("a.csv", "# units: ft\npx,py,pz,dx,dy,dz\n", r"a\.csv: line 1: units: unknown length"),
        (
            "a.json",
            '{"lines": [{"point": [0, "x", 0], "direction": [1, 0, 0]}]}',
            r"lines\[0\]\.point: expected numbers",
        ),
        (
            "a.csv",
            "px,py,pz,dx,dy,dz\n0,0,0,1,0,0\n0,0,0,1,0\n",
            r"a\.csv: line 3: expected 6 values",
        ),
        ("a.csv", "x,y,z\n", r"line 1: expected the header"),
        ("a.csv", "px,py,pz,dx,dy,dz\n0,0,nan,1,0,0\n", r"line 2: contains NaN"),
        ("a.csv", "px,py,pz,dx,dy,dz\n0,0,0,0,0,0\n", r"line 2: direction is the zero vector"),
        ("a.txt", "whatever", r"unknown file type '\.txt'"),
    ],
)
def test_bad_files_name_file_and_item(tmp_path, name, content, message):
    p = tmp_path / name
    p.write_text(content)
    with pytest.raises(ValueError, match=message):
        rr.load_lines(p)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(ValueError, match="no such file"):
        rr.load_lines(tmp_path / "missing.json")
    p = tmp_path / "bin.json"
    p.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(ValueError, match="cannot read"):
        rr.load_lines(p)


def test_failed_write_leaves_nothing(tmp_path, lines):
    target = tmp_path / "out.json"
    with pytest.raises(ValueError, match="frames must have shape"):
        rr.save_lines(target, lines, frames=np.zeros((2, 4, 4)))
    assert list(tmp_path.iterdir()) == []
    # an existing file survives a failing overwrite
    rr.save_lines(target, lines)
    before = target.read_text()
    from ruledrobot.io.atomic import atomic_open

    with pytest.raises(RuntimeError), atomic_open(target) as fh:
        fh.write("partial")
        raise RuntimeError("boom")
    assert target.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["out.json"]


def test_written_files_get_ordinary_permissions(tmp_path, lines):
    import os

    umask = os.umask(0o022)
    try:
        p = rr.save_lines(tmp_path / "a.json", lines)
        assert p.stat().st_mode & 0o777 == 0o644
        os.chmod(p, 0o640)
        rr.save_lines(p, lines)
        assert p.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(umask)


@pytest.mark.parametrize(
    ("unit", "scale"),
    [("m", 1.0), ("mm", 1e-3), ("cm", 1e-2), ("in", 0.0254), ("inches", 0.0254),
     ("millimetres", 1e-3)],
)
def test_lines_files_in_other_units_read_in_metres(tmp_path, unit, scale):
    """JSON "units" and the CSV "# units:" comment scale points, moments, frames and
    striction points to metres; directions are unchanged."""
    pts = np.array([[10.0, 20.0, 30.0], [40.0, -5.0, 2.5]])
    dirs = np.array([[0.0, 0.0, 1.0], [0.0, 0.6, 0.8]])
    frames = np.repeat(np.eye(4)[None], 2, axis=0)
    frames[:, :3, 3] = pts
    doc = {"format": "ruledrobot.lines/1", "units": unit,
           "lines": [{"point": p.tolist(), "direction": d.tolist()}
                     for p, d in zip(pts, dirs, strict=True)],
           "frames": frames.reshape(2, 16).tolist(), "striction": pts.tolist()}  # fmt: skip
    (tmp_path / "a.json").write_text(json.dumps(doc))
    got = rr.io.read_lines_document(tmp_path / "a.json")
    want = rr.Lines.from_point_direction(pts * scale, dirs)
    np.testing.assert_allclose(got.lines.plucker, want.plucker, atol=1e-15)
    np.testing.assert_allclose(got.frames[:, :3, 3], pts * scale)
    np.testing.assert_allclose(got.striction, pts * scale)
    rows = "\n".join(",".join(map(str, np.r_[p, d])) for p, d in zip(pts, dirs, strict=True))
    (tmp_path / "a.csv").write_text(f"# units: {unit}\npx,py,pz,dx,dy,dz\n{rows}\n")
    np.testing.assert_allclose(rr.load_lines(tmp_path / "a.csv").plucker, want.plucker, atol=1e-15)
