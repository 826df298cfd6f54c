"""The tables of a job file (wirecut.job.sections): the typed field reader's values and
errors (file, section, field, what was expected), and the stock, robot, heat and surface
tables against hand-made TOML tables."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from ruledrobot.geometry.lines import Lines
from ruledrobot.io.lines import save_lines
from ruledrobot.wirecut.job.sections import (
    HEAT_OUTPUTS,
    Section,
    parse_heat,
    parse_robot,
    parse_stock,
    parse_surface,
)

WHERE = "j.toml"


def _sec(table: dict, name: str = "cut") -> Section:
    return Section({name: table}, name, WHERE)


def test_missing_and_malformed_sections():
    with pytest.raises(ValueError, match=r"^j\.toml: missing section \[stock\]$"):
        Section({}, "stock", WHERE)
    assert Section({}, "tool", WHERE, required=False).raw == {}
    with pytest.raises(ValueError, match=r"^j\.toml: \[stock\] must be a table$"):
        Section({"stock": [1, 2]}, "stock", WHERE)
    s = Section.of({"a": 1}, "cut 'top'", WHERE)
    assert s.number("a") == 1.0
    assert str(s.fail("a", "bad")) == "j.toml: [cut 'top'] a: bad"


@given(st.floats(allow_nan=False, allow_infinity=False, min_value=-1e6, max_value=1e6))
def test_numbers_within_their_bounds(v):
    s = _sec({"x": v})
    if 0.0 <= v <= 1.0:
        assert s.number("x", lo=0.0, hi=1.0) == v
    else:
        with pytest.raises(ValueError, match=r"^j\.toml: \[cut\] x: expected a number"):
            s.number("x", lo=0.0, hi=1.0)


@pytest.mark.parametrize(
    "value, kw, message",
    [
        (None, {}, "x: missing; expected a number"),
        (True, {}, "x: expected a finite number, got True"),
        ("1", {}, "x: expected a finite number, got '1'"),
        (float("nan"), {}, "x: expected a finite number, got nan"),
        (0.0, dict(lo=0.0, strict_lo=True), "x: expected a number > 0, got 0.0"),
        (-1, dict(lo=0.0), "x: expected a number >= 0, got -1"),
        (2, dict(hi=1.5), "x: expected a number <= 1.5, got 2"),
    ],
)
def test_bad_numbers_name_the_field(value, kw, message):
    s = _sec({} if value is None else {"x": value})
    with pytest.raises(ValueError) as e:
        s.number("x", **kw)
    assert str(e.value) == f"j.toml: [cut] {message}"


def test_vectors_choices_flags_and_unknown_fields():
    s = _sec({"v": [1, 2.5, 3], "c": "dh", "f": False, "typo": 1, "bad": [1, True, 3],
              "nan": [1.0, float("inf"), 0.0]})  # fmt: skip
    np.testing.assert_array_equal(s.vector("v", 3), [1.0, 2.5, 3.0])
    assert s.vector("v", 3).dtype == np.float64
    np.testing.assert_array_equal(s.vector("absent", 2, [0, 1]), [0.0, 1.0])
    with pytest.raises(ValueError, match=r"\[cut\] v: expected a list of 2 numbers, got \[1"):
        s.vector("v", 2)
    with pytest.raises(ValueError, match=r"bad: expected a list of 3 numbers"):
        s.vector("bad", 3)
    with pytest.raises(ValueError, match=r"nan: contains NaN or infinity"):
        s.vector("nan", 3)
    with pytest.raises(ValueError, match=r"absent: missing; expected a list of 4 numbers"):
        s.vector("absent", 4)
    assert s.choice("c", ("dh", "projection"), "projection") == "dh"
    assert s.choice("d", ("dh", "projection"), "projection") == "projection"
    with pytest.raises(ValueError, match=r"c: expected one of a, b, got 'dh'"):
        s.choice("c", ("a", "b"), "a")
    assert s.flag("f", True) is False and s.flag("g", True) is True
    with pytest.raises(ValueError, match=r"v: expected true or false"):
        s.flag("v", False)
    with pytest.raises(ValueError) as e:
        s.done()
    assert str(e.value) == ("j.toml: [cut] unknown field(s) typo; expected some of absent, bad, "
                            "c, d, f, g, nan, v")  # fmt: skip


def test_the_stock_is_an_oriented_box():
    box = parse_stock(_sec({"centre": [0.5, 0, 0.3], "size": [0.2, 0.1, 0.15],
                            "rotvec": [0, 0, 0.5]}, "stock"))  # fmt: skip
    np.testing.assert_array_equal(box.centre, [0.5, 0.0, 0.3])
    np.testing.assert_array_equal(box.size, [0.2, 0.1, 0.15])
    np.testing.assert_allclose(box.rotation, Rotation.from_rotvec([0, 0, 0.5]).as_matrix(),
                               atol=1e-15)  # fmt: skip
    assert np.array_equal(parse_stock(_sec({"centre": [0, 0, 0], "size": [1, 1, 1]},
                                           "stock")).rotation, np.eye(3))  # fmt: skip
    with pytest.raises(ValueError, match=r"\[stock\] size: edge 1 must be positive, got 0\.0"):
        parse_stock(_sec({"centre": [0, 0, 0], "size": [1, 0, 1]}, "stock"))
    with pytest.raises(ValueError, match=r"\[stock\] unknown field\(s\) colour"):
        parse_stock(_sec({"centre": [0, 0, 0], "size": [1, 1, 1], "colour": "blue"}, "stock"))


def test_the_robot_table():
    table = {"model": "UR10e", "speed_scale": 0.5, "acceleration": 2.0,
             "base": [0.1, 0, 0, 0, 0, 3.141592653589793]}  # fmt: skip
    r = parse_robot(_sec(table, "robot"), None)
    assert r.model == "ur10e" and r.speed_scale == 0.5 and r.home is None
    np.testing.assert_array_equal(r.acceleration, np.full(6, 2.0))
    np.testing.assert_allclose(r.base[:3, 3], [0.1, 0.0, 0.0])
    np.testing.assert_allclose(r.base[:3, :3], np.diag([-1.0, -1.0, 1.0]), atol=1e-12)
    default = parse_robot(_sec({}, "robot"), None)
    assert default.model == "ur5e" and default.speed_scale == 1.0 and default.acceleration is None
    np.testing.assert_array_equal(default.base, np.eye(4))
    for table, message in (
        ({"model": "ur99"}, r"model: unknown robot 'ur99'; expected one of .*ur5e"),
        ({"speed_scale": 0}, r"speed_scale: expected a number > 0, got 0"),
        ({"speed_scale": 1.2}, r"speed_scale: expected a number <= 1, got 1\.2"),
        ({"acceleration": [1, 2, 3, 4, 5, -6]}, r"acceleration: expected positive values"),
        ({"calibration": 5}, r"calibration: expected a path string, got 5"),
    ):
        with pytest.raises(ValueError, match=r"^j\.toml: \[robot\] " + message):
            parse_robot(_sec(table, "robot"), None)


def test_heat_outputs():
    h = parse_heat(_sec({"output": "tool:1", "preheat": 0.5}, "tool.heat"))
    assert (h.kind, h.index, h.preheat, h.value) == ("tool", 1, 0.5, 1.0)
    a = parse_heat(_sec({"output": "analog:1", "value": 0.25}, "tool.heat"))
    assert (a.kind, a.index, a.preheat, a.value) == ("analog", 1, 2.0, 0.25)
    for kind, n in HEAT_OUTPUTS.items():
        parse_heat(_sec({"output": f"{kind}:{n - 1}"}, "tool.heat"))
        with pytest.raises(ValueError, match=rf"{kind} outputs are numbered 0\.\.{n - 1}"):
            parse_heat(_sec({"output": f"{kind}:{n}"}, "tool.heat"))
    for table, message in (
        ({"output": "standard"}, r'output: expected "KIND:N"'),
        ({"output": "relay:0"}, r"output: unknown output kind 'relay'"),
        ({"output": "standard:x"}, r"output: standard outputs are numbered 0\.\.7, got 'x'"),
        ({"output": "standard:0", "value": 0.5}, r"value: only for an analog output"),
        ({"output": "standard:0", "preheat": 61}, r"preheat: expected a number <= 60"),
        ({"output": "analog:0", "value": 1.5}, r"value: expected a number <= 1"),
    ):
        with pytest.raises(ValueError, match=r"^j\.toml: \[tool\.heat\] " + message):
            parse_heat(_sec(table, "tool.heat"))


def test_a_builtin_surface_and_its_defaults():
    s = parse_surface(_sec({"builtin": "hyperbolic_paraboloid", "params": {"c": 0.4},
                            "u": [-0.1, 0.2], "rulings": 12, "spacing": 0.002},
                           "surface"), None)  # fmt: skip
    assert (s.builtin, s.params, s.u, s.rulings) == ("hyperbolic_paraboloid", {"c": 0.4},
                                                     (-0.1, 0.2), 12)  # fmt: skip
    assert s.steps is None and s.spacing == 0.002
    assert (s.algorithm, s.scheme, s.closed, s.kind, s.file) == ("dh", "four_point", None,
                                                                 None, None)  # fmt: skip
    d = parse_surface(_sec({"builtin": "hyperboloid"}, "surface"), None)
    assert d.steps == 4 and d.spacing is None and d.rulings == 9 and d.u is None
    np.testing.assert_array_equal(d.pose, np.eye(4))


@pytest.mark.parametrize(
    "table, message",
    [
        ({}, r"builtin/file/gcode/airfoil/dxf/rhino: give exactly one of"),
        ({"builtin": "helicoid", "file": "x.json"}, r"builtin/file/gcode/airfoil/dxf/rhino: give"),
        ({"builtin": "torus"}, r"builtin: unknown surface 'torus'; expected one of"),
        ({"builtin": "helicoid", "params": 3}, r"params: expected a table of parameters"),
        ({"builtin": "helicoid", "u": [1.0, 1.0]}, r"u: expected \[start, stop\] with stop > "
                                                   r"start, got \[1\.0, 1\.0\]"),
        ({"builtin": "helicoid", "rulings": 3}, r"rulings: expected an integer 4 <= rulings"),
        ({"builtin": "helicoid", "rulings": 9.0}, r"rulings: expected an integer"),
        ({"builtin": "helicoid", "steps": 2, "spacing": 0.01}, r"steps/spacing: give steps "
                                                               r"or spacing, not both"),
        ({"builtin": "helicoid", "steps": 13}, r"steps: expected an integer 0 <= steps <= 12"),
        ({"builtin": "helicoid", "spacing": 0}, r"spacing: expected a number > 0"),
        ({"builtin": "helicoid", "closed": "yes"}, r"closed: expected true or false"),
        ({"builtin": "helicoid", "algorithm": "fast"}, r"algorithm: expected one of "
                                                       r"projection, combined, dh"),
        ({"file": 3}, r"file: expected a path string, got 3"),
    ],
)  # fmt: skip
def test_bad_surfaces_name_the_field(table, message):
    with pytest.raises(ValueError, match=r"^j\.toml: \[surface\] " + message):
        parse_surface(_sec(table, "surface"), None)


def test_a_lines_file_is_found_next_to_the_job_and_takes_no_builtin_fields(tmp_path):
    rulings = Lines.from_point_direction(np.c_[np.linspace(0, 0.1, 5), np.zeros((5, 2))],
                                         np.tile([0.0, 0.0, 1.0], (5, 1)))  # fmt: skip
    save_lines(tmp_path / "r.json", rulings)
    s = parse_surface(_sec({"file": "r.json"}, "surface"), tmp_path)
    assert s.file == tmp_path / "r.json" and s.kind == "lines" and s.builtin is None
    np.testing.assert_allclose(s.read_lines.plucker, rulings.plucker)  # read when parsed
    with pytest.raises(ValueError, match=r"\[surface\] u: only for a builtin surface"):
        parse_surface(_sec({"file": "r.json", "u": [0, 1]}, "surface"), tmp_path)
    with pytest.raises(ValueError, match=r"\[surface\] params: only for a builtin surface"):
        parse_surface(_sec({"file": "r.json", "params": {"c": 1}}, "surface"), tmp_path)
    with pytest.raises(ValueError, match=r"\[surface\] file: "):
        parse_surface(_sec({"file": "missing.json"}, "surface"), tmp_path)
