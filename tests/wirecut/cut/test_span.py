"""Surfaces span what they cut (issue 21, item 5): inside the block the wire follows the
surface's own rulings; extrapolation only leads in and out, outside it, unless the job
asks for it (``extend = true``, noted).  A source with too few rulings for the scheme is
refused by ``plan`` as by ``refine``.  Path stage only (``cut_paths``, ``refine_for_job``)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import ruledrobot as rr
from ruledrobot.cli import app
from ruledrobot.wirecut.cut.passes import cut_paths, refine_for_job
from ruledrobot.wirecut.cut.wire_geometry import chords
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import load_job

#: the demo's hyperbolic paraboloid stops in the middle of the block (x = 0.5 of 0.4..0.6)
SHORT = "u = [-0.12, 0.0]"
DATA = Path(__file__).parents[2] / "formats" / "data"
#: the cutter frame of tests/formats/data/wedge.ngc in the demo cell (tests/formats)
WEDGE_POSE = "[0.4, 0.4, 0.25, 1.5707963267948966, 0.0, 0.0]"
DEMO_SURFACE = '''builtin = "hyperbolic_paraboloid"
params = { c = 0.4 }
u = [-0.12, 0.12]          # rulings at x = u (m) in the surface frame
rulings = 9                # input rulings, refined below
'''


def _job(tmp_path: Path, text: str, name: str = "job.toml"):
    p = tmp_path / name
    p.write_text(text)
    return load_job(p)


def _short(extra_cut: str = "") -> str:
    assert "u = [-0.12, 0.12]" in DEMO_JOB and "kerf = 0.0008" in DEMO_JOB
    return DEMO_JOB.replace("u = [-0.12, 0.12]", SHORT).replace(
        "kerf = 0.0008", "kerf = 0.0008" + extra_cut)


def _flat(message: str) -> str:
    return " ".join(message.split())


def _extrapolated_in_block(cp, stock) -> int:
    a, b = cp.extended
    c0, c1, hit = chords(cp.target_frames, stock)
    inside = hit & (np.nan_to_num(c1 - c0) > 1e-6)
    return int(inside[:a].sum() + inside[len(inside) - b :].sum())


def test_a_surface_that_stops_in_the_block_is_refused_saying_where(tmp_path):
    job = _job(tmp_path, _short())
    with pytest.raises(ValueError) as info:
        cut_paths(job)
    msg = _flat(str(info.value))
    assert msg.startswith(f"{tmp_path / 'job.toml'}: [cut] the surface (hyperbolic_paraboloid) "
                          "stops short of the block")  # fmt: skip
    # where the surface ends (its last input ruling, x = 0.5) and where the block ends (0.6)
    assert "its last input ruling (index 8 of 9, from 0) passes [0.500, 0.000, 0.300]" in msg
    assert "100.0 mm short of the block's end at [0.600, 0.000, 0.300]" in msg
    assert re.search(r"on \d{3} rulings extrapolated from the surface", msg)
    assert "extend = true" in msg and "first input ruling" not in msg


def test_a_named_cut_that_stops_short_names_its_section(tmp_path):
    text = PART_JOB.replace("u = [-0.12, 0.12]", "u = [0.0, 0.12]", 1)  # 'top' starts mid-block
    job = _job(tmp_path, text, "part.toml")
    with pytest.raises(ValueError, match=r"part\.toml: \[cut 'top'\] the surface .* its first "
                       r"input ruling \(index 0 of 9"):  # fmt: skip
        cut_paths(job, job.cuts[0])


def test_the_cli_exits_2_on_a_short_surface_and_writes_nothing(tmp_path):
    job = tmp_path / "short.toml"
    job.write_text(_short())
    result = CliRunner().invoke(app, ["plan", str(job), "--out", str(tmp_path / "out")])
    assert result.exit_code == 2, result.output
    assert "stops short of the block" in _flat(result.output)
    assert not (tmp_path / "out").exists()


def test_extend_true_cuts_on_along_the_extrapolation_and_says_how_far(tmp_path):
    job = _job(tmp_path, _short("\nextend = true"))
    assert job.cut.extend
    (cp,) = cut_paths(job)
    assert cp.feasible
    n = _extrapolated_in_block(cp, job.stock)
    assert n > 90  # the half of the block past x = 0.5, ~1.6 mm between rulings
    (note,) = cp.notes
    assert note.startswith("[cut] extend = true: the surface stops short of the block")
    m = re.search(r"up to ([\d.]+) mm past its last input ruling on (\d+) rulings", note)
    assert m is not None and int(m[2]) == n
    assert 100.0 <= float(m[1]) < 110.0  # the last ruling at x = 0.5, the block ends at 0.6


def test_extend_is_only_for_open_surfaces(tmp_path):
    text = DEMO_JOB.replace(DEMO_SURFACE, 'builtin = "hyperboloid"\nparams = { a = 0.06, '
                            "c = 0.3 }\nrulings = 16\nclosed = true\n").replace(
        "kerf = 0.0008", "kerf = 0.0008\nextend = true")  # fmt: skip
    with pytest.raises(ValueError, match=r"\[cut\] extend: only for an open surface"):
        _job(tmp_path, text)
    with pytest.raises(ValueError, match=r"\[cut\] extend: expected true or false"):
        _job(tmp_path, _short('\nextend = "yes"'))


def test_a_surface_ending_on_the_block_face_or_within_the_wire_tolerance_of_it_plans(tmp_path):
    """The demo block spans x = 0.4 .. 0.6: a surface over u = [-0.1, 0.1] ends on its faces,
    one 0.1 mm short is within the wire tolerance (0.5 mm), one 1 mm short (less than the
    gap to the first extrapolated ruling, 1.6 mm) is refused."""
    for u in ("[-0.1, 0.1]", "[-0.1, 0.0999]"):
        job = _job(tmp_path, DEMO_JOB.replace("u = [-0.12, 0.12]", f"u = {u}"))
        (cp,) = cut_paths(job)
        assert cp.extended[1] > 0 and not cp.notes
        assert _extrapolated_in_block(cp, job.stock) == 0
    job = _job(tmp_path, DEMO_JOB.replace("u = [-0.12, 0.12]", "u = [-0.1, 0.099]"))
    with pytest.raises(ValueError, match=r"1\.0 mm short of the block's end .* between that "
                       "ruling and the first extrapolated one"):  # fmt: skip
        cut_paths(job)


def _two_rulings(tmp_path: Path, scheme: str) -> Path:
    """A lines file of 2 rulings 5 cm apart (x = 0.475, 0.525) through the demo block."""
    lines = rr.Lines.from_point_direction([[0.475, 0.0, 0.3], [0.525, 0.0, 0.3]],
                                          [[0.0, 1.0, 0.0], [0.0, 1.0, 0.1]])  # fmt: skip
    rr.save_lines(tmp_path / "two.json", lines)
    return tmp_path / "two.json"


def test_a_lines_file_too_short_for_the_scheme_is_refused_as_refine_refuses_it(tmp_path):
    _two_rulings(tmp_path, "four_point")
    text = DEMO_JOB.replace(DEMO_SURFACE, 'file = "two.json"\n').replace(
        "pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]", "pose = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]")
    job = _job(tmp_path, text)
    with pytest.raises(ValueError) as planned:
        refine_for_job(job)
    with pytest.raises(ValueError) as refined:
        rr.refine(job.input_lines(), "dh", "four_point", 4)
    tail = "scheme 'four_point' needs at least 4 elements, got 2"
    assert str(refined.value).endswith(tail) and str(planned.value).endswith(tail)
    assert str(planned.value).startswith(f"{tmp_path / 'job.toml'}: [surface] ")
    # a scheme that takes 2: then the 5 cm strip is refused for stopping short of the block
    job = _job(tmp_path, text.replace('scheme = "four_point"', 'scheme = "linear"'))
    with pytest.raises(ValueError, match=r"stops short of the block: its first input ruling "
                       r"\(index 0 of 2.*; its last input ruling \(index 1 of 2"):  # fmt: skip
        cut_paths(job)


def test_a_foam_cutter_file_is_cut_as_written_and_refused_when_it_stops_short(tmp_path):
    """wedge.ngc leads in and out inside the file: unchanged.  Cut off at X100 (the middle
    of the block) it stops short."""
    full = (DATA / "wedge.ngc").read_text()
    (tmp_path / "short.ngc").write_text(full[: full.index("N220")] + "M5\nM30\n%\n")
    (tmp_path / "wedge.ngc").write_text(full)
    for name in ("wedge", "short"):
        text = DEMO_JOB.replace(DEMO_SURFACE + "pose = [0.5, 0.0, 0.3, 0.0, 0.0, 0.0]",
                                f'gcode = {{ file = "{name}.ngc", tower_distance = 0.8 }}\n'
                                f"pose = {WEDGE_POSE}")  # fmt: skip
        job = _job(tmp_path, text, f"{name}.toml")
        if name == "wedge":
            (cp,) = cut_paths(job)
            assert not cp.notes and _extrapolated_in_block(cp, job.stock) == 0
        else:
            with pytest.raises(ValueError, match=r"short\.toml: \[cut\] the surface \(gcode "
                               r".*short\.ngc\) stops short of the block: its last input"):
                cut_paths(job)


def test_the_demo_and_part_jobs_still_plan(tmp_path):
    for name, text in (("demo", DEMO_JOB), ("part", PART_JOB)):
        job = _job(tmp_path, text, f"{name}.toml")
        for cut in job.cuts:
            for cp in cut_paths(job, cut):
                assert cp.feasible and not any("extend" in n for n in cp.notes)
                if not cp.closed:
                    assert _extrapolated_in_block(cp, job.stock) == 0
