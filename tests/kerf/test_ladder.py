"""The ladder's jobs: they load, cut every speed at every power, in planes through the block."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np
import pytest

import ruledrobot.kerf
from ruledrobot.kerf import fit_kerf, read_measured, write_ladder
from ruledrobot.kerf.ladder import SPACING_MIN
from ruledrobot.robot.wire.kerf import Material
from ruledrobot.wirecut import load_job

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SPEEDS = [0.002, 0.003, 0.004, 0.006]
POWERS = [15.0, 25.0, 35.0]
FULL = 60.0


def test_the_jobs_load_with_the_speeds_and_powers_asked(job_file, tmp_path):
    lad = write_ladder(job_file(), tmp_path / "lad", SPEEDS, POWERS, full_scale=FULL)
    assert [j.parent.name for j in lad.jobs] == ["power1", "power2", "power3"]
    seen = set()
    for job_path, power in zip(lad.jobs, POWERS, strict=True):
        job = load_job(job_path)
        assert sorted(c.feed_speed for c in job.cuts) == pytest.approx(SPEEDS)
        heat = job.tool.heat
        assert (heat.output, heat.mode, heat.full_scale) == ("analog:0", "constant", FULL)
        assert heat.power == pytest.approx(power)
        for c in job.cuts:
            seen.add((round(c.feed_speed, 6), power))
            assert c.keep is None  # the wire on the plane: nothing compensated
    assert len(seen) == len(SPEEDS) * len(POWERS) == len(lad.cuts)


def test_each_cut_is_a_plane_through_the_block_spaced_apart(job_file, tmp_path):
    """Rulings of a cut: parallel to the wire axis (the block's y), in the plane x = the
    cut's offset, spanning the block's height; planes spacing apart, inside the block."""
    lad = write_ladder(job_file(), tmp_path / "lad", SPEEDS, POWERS, full_scale=FULL)
    job = load_job(lad.jobs[0])
    stock = job.stock
    assert (lad.wire_axis, lad.spacing_axis) == ("y", "x")
    xs = []
    for cut in job.cuts:
        lines = cut.surface.lines()
        d, m = lines.plucker[:, :3], lines.plucker[:, 3:]
        assert np.allclose(np.abs(d[:, 1]), 1.0)
        feet = np.cross(d, m)  # the point of each line nearest the origin
        assert np.ptp(feet[:, 0]) < 1e-12 and np.ptp(feet[:, 1]) < 1e-12
        z = feet[:, 2] - stock.centre[2]
        assert z.max() >= stock.size[2] / 2 and z.min() <= -stock.size[2] / 2
        xs.append(feet[0, 0] - stock.centre[0])
    offsets = np.array([c.offset for c in lad.cuts])
    assert np.allclose(xs, offsets[: len(SPEEDS)])
    assert np.allclose(np.diff(offsets), lad.spacing) and lad.spacing >= SPACING_MIN
    assert np.all(np.abs(offsets) + lad.spacing <= stock.size[0] / 2 + 1e-12)


def test_the_template_filled_with_the_model_fits_back(job_file, tmp_path):
    """measured.csv as written lists every cut; filled with a known material's kerfs (to a
    hundredth of a mm, as read off calipers) it fits back to that material."""
    lad = write_ladder(job_file(), tmp_path / "lad", SPEEDS, POWERS, full_scale=FULL)
    truth = Material(0.4e-3, 1.1e-7, 8.0)
    path = lad.out / "measured.csv"
    with pytest.raises(ValueError, match=r"line 2, column kerf_mm: empty"):
        read_measured(path)
    rows = path.read_text().splitlines()
    head = rows[0].split(",")
    filled = [rows[0]]
    for row in rows[1:]:
        cell = dict(zip(head, row.split(","), strict=True))
        w = truth.kerf(float(cell["speed_mm_s"]) * 1e-3, float(cell["power_w_m"]))
        cell["kerf_mm"] = f"{w * 1e3:.2f}"
        filled.append(",".join(cell[h] for h in head))
    path.write_text("\n".join(filled) + "\n")
    fit = fit_kerf(read_measured(path))
    assert fit.verdict.ok
    assert fit.material.kerf_gain == pytest.approx(truth.kerf_gain, rel=0.01)
    # and the folder is not written over while it holds measurements, said as such also
    # when `kerf fit` has put its material.toml beside them (a file the ladder did not write)
    for extra in (False, True):
        if extra:
            (lad.out / "material.toml").write_text("[material]\n", encoding="utf-8")
        with pytest.raises(ValueError, match=r"measured\.csv holds measurements"):
            write_ladder(job_file(), lad.out, SPEEDS, POWERS, full_scale=FULL)


def test_a_digital_heat_output_is_refused_saying_why(job_file, tmp_path):
    with pytest.raises(ValueError, match=r"job.toml: \[tool\] heat: .*analog.*digital"):
        write_ladder(job_file("standard:0"), tmp_path / "lad", SPEEDS, POWERS,
                     full_scale=FULL)  # fmt: skip
    assert not (tmp_path / "lad").exists()


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"speeds": [0.004]}, "--speeds: expected two or more"),
    ({"powers": [20.0, 20.0]}, "--powers: expected two or more different"),
    ({"powers": [20.0, 80.0]}, "80 W/m is above the supply's full scale 60"),
    ({"full_scale": None}, r"\[tool\] heat: give full_scale"),
    ({"spacing": 0.002}, "--spacing: 2 mm; expected at least 5 mm"),
    ({"speeds": np.linspace(0.001, 0.01, 20)}, r"\[stock\] size: 60 cuts 5 mm apart"),
])  # fmt: skip
def test_bad_ladders_name_the_option_or_field(job_file, tmp_path, kwargs, match):
    args = {"speeds": SPEEDS, "powers": POWERS, "full_scale": FULL} | kwargs
    with pytest.raises(ValueError, match=match):
        write_ladder(job_file(), tmp_path / "lad", args.pop("speeds"), args.pop("powers"),
                     **args)  # fmt: skip
    assert not (tmp_path / "lad").exists()


def test_kerf_imports_only_top_level_names_of_the_planner():
    bad = []
    for path in sorted(Path(ruledrobot.kerf.__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and "wirecut" in node.module:
                if node.module != "wirecut" or node.level != 2:
                    bad.append(f"{path.name}: from {'.' * node.level}{node.module}")
    assert not bad, bad


def test_the_jobs_written_are_plain_toml(job_file, tmp_path):
    lad = write_ladder(job_file(), tmp_path / "lad", SPEEDS, POWERS, full_scale=FULL)
    doc = tomllib.loads(lad.jobs[1].read_text())
    assert set(doc) == {"stock", "robot", "tool", "cut"}
    assert [c["feed_speed"] for c in doc["cut"]] == SPEEDS
