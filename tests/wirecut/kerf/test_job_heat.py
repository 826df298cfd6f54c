"""The heat model in a job file (docs/kerf.md): ``[material]``, ``[tool] heat``'s ``mode``,
``power``, ``full_scale``, ``lag`` and a cut's ``tolerance``; every error names the file,
the table and the field."""

from __future__ import annotations

import pytest

from ruledrobot.robot.wire.kerf import Material
from ruledrobot.wirecut.job.load import load_job
from tests.wirecut.job.test_job import EXAMPLE, write

MATERIAL = """
[material]
kerf_base = 0.0003
kerf_gain = 1.5e-8
power_threshold = 20.0
max_speed = 0.002
"""


def job_text(heat: str = "", material: str = MATERIAL, cut: str = "") -> str:
    text = EXAMPLE.replace("mass = 1.2", f"mass = 1.2\n{heat}") + cut + material
    return text


def test_defaults_keep_todays_job(tmp_path):
    job = load_job(write(tmp_path, EXAMPLE))
    assert job.material is None and job.cut.tolerance == 1e-4 and job.tool.heat is None
    job = load_job(write(tmp_path, job_text('heat = { output = "standard:0" }', "")))
    h = job.tool.heat
    assert (h.mode, h.power, h.full_scale, h.lag) == ("on_off", None, None, 0.0)


def test_material_and_heat_model_parse(tmp_path):
    heat = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 400.0, '
            "lag = 0.25 }")
    job = load_job(write(tmp_path, job_text(heat, cut="tolerance = 0.00005\n")))
    assert job.material == Material(0.0003, 1.5e-8, 20.0, 0.002)
    h = job.tool.heat
    assert (h.kind, h.mode, h.full_scale, h.lag) == ("analog", "constant_kerf", 400.0, 0.25)
    assert job.cut.tolerance == 5e-5
    assert job.source is not None  # load_job keeps the material when it sets the source
    job = load_job(write(tmp_path, job_text(
        'heat = { output = "standard:1", mode = "constant", power = 80.0 }')))
    assert (job.tool.heat.mode, job.tool.heat.power) == ("constant", 80.0)


@pytest.mark.parametrize(
    "heat, material, cut, message",
    [
        ('heat = { output = "standard:0", mode = "warm" }', MATERIAL, "",
         r"\[tool\.heat\] mode: expected one of on_off, constant, constant_kerf, got 'warm'"),
        ('heat = { output = "standard:0", mode = "constant" }', MATERIAL, "",
         r"\[tool\.heat\] power: missing"),
        ('heat = { output = "analog:0", mode = "constant", power = 50.0 }', MATERIAL, "",
         r"\[tool\.heat\] full_scale: missing"),
        ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 400.0 }', "", "",
         r"\[tool\.heat\] mode: \"constant_kerf\" needs a \[material\]"),
        ('heat = { output = "standard:0", lag = -1 }', MATERIAL, "",
         r"\[tool\.heat\] lag: expected a number >= 0"),
        ("", MATERIAL.replace("kerf_gain = 1.5e-8", "kerf_gain = 0"), "",
         r"\[material\] kerf_gain: expected a number > 0, got 0"),
        ("", MATERIAL.replace("kerf_base = 0.0003\n", ""), "",
         r"\[material\] kerf_base: missing"),
        ("", MATERIAL + "colour = 1\n", "", r"\[material\] unknown field\(s\) colour"),
        ("", MATERIAL, "tolerance = 0\n", r"\[cut\] tolerance: expected a number > 0"),
        ("", MATERIAL.replace("kerf_gain", "kerf_gian"), "",
         r"\[material\] unknown field\(s\) kerf_gian; expected some of .*kerf_gain"),
        ('heat = { output = "standard:0", mode = "constant_kerf" }', MATERIAL, "",
         r"\[tool\.heat\] mode: \"constant_kerf\" sets the power .* needs an analog output"),
        ('heat = { output = "tool:1", mode = "constant", power = 50.0, full_scale = 90.0 }',
         MATERIAL, "", r"\[tool\.heat\] full_scale: only for an analog output, got output = "
         r'"tool:1"'),
        ('heat = { output = "analog:0", mode = "constant", power = 90.0, full_scale = 60.0 }',
         MATERIAL, "", r"\[tool\.heat\] power: 90 W/m is above full_scale 60 W/m"),
        ('heat = { output = "standard:0", mode = "constant", power = 20.0 }', MATERIAL, "",
         r"\[tool\.heat\] power: 20 W/m is at or below \[material\] power_threshold 20 W/m"),
    ],
)
def test_bad_heat_model_names_file_table_field(tmp_path, heat, material, cut, message):
    p = write(tmp_path, job_text(heat, material, cut))
    with pytest.raises(ValueError, match=rf"^{p}: " + message):
        load_job(p)


@pytest.mark.parametrize("heat", [
    'heat = { output = "analog:0", mode = "constant_kerf", full_scale = 400.0 }',
    'heat = { output = "standard:0" }',  # on_off without power: the kerf sets the power
    "",  # no heat output: on_off, the same
])
def test_a_kerf_that_sets_the_power_below_the_wire_is_refused(tmp_path, heat):
    text = job_text(heat).replace("kerf = 0.0008", "kerf = 0.0002")
    p = write(tmp_path, text)
    with pytest.raises(ValueError, match=rf"^{p}: \[cut\] kerf: 0.2 mm is below \[material\] "
                       r"kerf_base 0.3 mm: .*\(expected a kerf >= kerf_base\)"):
        load_job(p)


def test_a_given_power_makes_the_kerf_below_the_wire_harmless(tmp_path):
    """With ``power`` given (on_off or constant) the cut's kerf sets nothing: it loads."""
    heat = 'heat = { output = "standard:0", mode = "constant", power = 50.0 }'
    job = load_job(write(tmp_path, job_text(heat).replace("kerf = 0.0008", "kerf = 0.0002")))
    assert job.cut.kerf == 0.0002 and job.tool.heat.power == 50.0
