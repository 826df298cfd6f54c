"""Wire lag as information (docs/kerf.md, "Wire lag"): ``[material] drag`` and ``[tool]
wire_tension`` in a job file (bad values named by file, table and field), and per cut in
report.json and the verdict's table the wire's bow at the feed on the longest chord -- the
taut string's closed form ``drag v c (2L - c) / (8T)``, written out here -- and the corner
dwell ``bow / v``; without both fields the report says what to give."""

from __future__ import annotations

import dataclasses

import pytest

from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import LAG_NEEDS, plan_outcome
from tests.wirecut.job.test_job import EXAMPLE, write

from .panel import FEED, write_panel

DRAG, TENSION = 400.0, 50.0  # N/m per m/s, N


def _job_text(tool: str = "", material: str = "") -> str:
    return (EXAMPLE.replace("mass = 1.2", f"mass = 1.2\n{tool}")
            + "\n[material]\nkerf_base = 0.0003\nkerf_gain = 1.5e-8\n" + material)


def test_drag_and_wire_tension_parse_and_are_optional(tmp_path):
    job = load_job(write(tmp_path, _job_text("wire_tension = 60.0", "drag = 2.5\n")))
    assert (job.material.drag, job.tool.wire_tension) == (2.5, 60.0)
    job = load_job(write(tmp_path, _job_text()))
    assert (job.material.drag, job.tool.wire_tension) == (None, None)


@pytest.mark.parametrize("tool, material, message", [
    ("", "drag = -1.0\n", r"\[material\] drag: expected a number >= 0, got -1"),
    ("", 'drag = "high"\n', r"\[material\] drag: expected a finite number, got .high."),
    ("wire_tension = 0", "", r"\[tool\] wire_tension: expected a number > 0, got 0"),
    ("wire_tension = -5.0", "", r"\[tool\] wire_tension: expected a number > 0"),
    ('wire_tension = "taut"', "", r"\[tool\] wire_tension: expected a finite number, got .taut."),
])  # fmt: skip
def test_bad_drag_or_wire_tension_is_named(tmp_path, tool, material, message):
    p = write(tmp_path, _job_text(tool, material))
    with pytest.raises(ValueError, match=rf"^{p}: " + message):
        load_job(p)


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    plan = make_plan(load_job(write_panel(tmp_path_factory.mktemp("lag"))))
    assert plan.motion is not None, plan.reasons
    return plan


def _with_lag(plan, drag=DRAG, tension=TENSION):
    job = plan.job
    job = dataclasses.replace(job, material=dataclasses.replace(job.material, drag=drag),
                              tool=dataclasses.replace(job.tool, wire_tension=tension))
    return dataclasses.replace(plan, job=job)


def test_the_bow_is_the_taut_string_at_the_feed_on_the_longest_chord(panel):
    report, verdict = plan_outcome(_with_lag(panel), None)
    lag = report["cuts"][0]["wire_lag"]
    assert lag["information"] is True and "needs" not in lag
    c, L = lag["chord_mm"] * 1e-3, 0.4  # the panel's wire: -0.2 .. 0.2 m in the flange
    # the wire spans the 200 mm block in y, leaning 10 mm in x over it: its chord is 200.25 mm
    assert c == pytest.approx((0.2**2 + 0.01**2) ** 0.5, abs=5e-4)
    assert lag["wire_length_mm"] == pytest.approx(L * 1e3)
    assert lag["speed_mm_s"] == pytest.approx(FEED * 1e3)
    bow = DRAG * FEED * c * (2 * L - c) / (8 * TENSION)
    assert lag["bow_mm"] == pytest.approx(bow * 1e3, rel=1e-12)
    assert lag["corner_dwell_s"] == pytest.approx(bow / FEED, rel=1e-12)
    info = {ch.name: ch for ch in verdict.checks}
    assert not info["wire_lag"].gating
    assert info["wire_lag"].value == f"{bow * 1e3:.3g} mm / {bow / FEED:.3g} s"
    # a stiffer wire bows less, in proportion
    stiff, _ = plan_outcome(_with_lag(panel, tension=2 * TENSION), None)
    assert stiff["cuts"][0]["wire_lag"]["bow_mm"] == pytest.approx(bow * 1e3 / 2, rel=1e-12)


@pytest.mark.parametrize("drag, tension", [(None, TENSION), (DRAG, None), (None, None)])
def test_without_drag_and_tension_the_report_says_what_to_give(panel, drag, tension):
    report, verdict = plan_outcome(_with_lag(panel, drag, tension), None)
    lag = report["cuts"][0]["wire_lag"]
    assert lag["bow_mm"] is None and lag["corner_dwell_s"] is None
    assert lag["needs"] == LAG_NEEDS
    assert "[material] drag" in LAG_NEEDS and "[tool] wire_tension" in LAG_NEEDS
    check = next(ch for ch in verdict.checks if ch.name == "wire_lag")
    assert not check.gating and check.value == LAG_NEEDS
