"""plots.png's kerf and heat panels (wirecut.report.plot_heat) on the tapered panel of issue
33: they appear exactly when the plan has a heat model (the kerf panel with a [material]),
and their lines are the verdict's own arrays -- every point drawn is a sample of
``plan.measured.faces`` / ``heat_power`` / the wire's power, whose range report.json gives --
and the wire's line is the set-point ``lag`` seconds late (np.interp, not the planner's
function)."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.outcome import plan_outcome
from ruledrobot.wirecut.report.plots import TIME_PANELS, plan_figure

from ..kerf.panel import write_panel

LAG = 0.1
CONSTANT_KERF = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 200.0, '
                 f"lag = {LAG}, preheat = 0.5 }}")  # fmt: skip
CONSTANT = ('heat = { output = "analog:0", mode = "constant", power = 50.0, '
            'full_scale = 200.0, preheat = 0.5 }')  # fmt: skip

KERF_TITLE, HEAT_TITLE = "predicted kerf", "heat (W per metre"


def _plan(folder, heat, material=True):
    plan = make_plan(load_job(write_panel(folder, heat, material=material)))
    assert plan.motion is not None, plan.reasons
    return plan


@pytest.fixture(scope="module")
def kerf_plan(tmp_path_factory):
    return _plan(tmp_path_factory.mktemp("ck"), CONSTANT_KERF)


def _titled(fig, start):
    found = [ax for ax in fig.axes if ax.get_title().startswith(start)]
    return found[0] if found else None


def _samples_of(line, t, y):
    """The line's finite points are samples (t[k], y[k]) of the array ``y`` (M,)."""
    x, v = (np.asarray(a, dtype=float) for a in line.get_data())
    keep = np.isfinite(x) & np.isfinite(v)
    k = np.searchsorted(t, x[keep])
    np.testing.assert_array_equal(t[k], x[keep])
    np.testing.assert_array_equal(v[keep], y[k])
    return v[keep]


def test_the_kerf_panel_draws_the_verdicts_arrays(kerf_plan):
    plan = kerf_plan
    fig = plan_figure(plan)
    ax = _titled(fig, KERF_TITLE)
    assert ax is not None
    t = plan.motion.timed.t
    fe = plan.measured.faces["cut"]
    lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("wire")]
    assert [ln.get_label() for ln in lines] == ["wire start side", "wire end side"]
    report, _ = plan_outcome(plan, None)
    drawn = report["cuts"][0]["predicted_kerf_mm"]
    for j, (line, side) in enumerate(zip(lines, ("wire_start_side", "wire_end_side"),
                                         strict=True)):  # fmt: skip
        y = _samples_of(line, t, fe.kerf[:, j] * 1e3)
        # the thinning keeps the extremes: the line spans report.json's range exactly
        assert [y.min(), y.max()] == pytest.approx(drawn[side], abs=0, rel=1e-12)
        assert y.size >= 100
    # the tapered panel: the slower (start) side melts wider than the cut's 0.8 mm
    assert drawn["wire_start_side"][1] > 0.9 > 0.81 > drawn["wire_end_side"][1]
    planned = [c for c in ax.collections if c.get_label() == "the cut's kerf"]
    assert len(planned) == 1
    np.testing.assert_allclose(np.asarray(planned[0].get_segments())[0][:, 1],
                               plan.job.cut.kerf * 1e3)  # fmt: skip
    assert f"{fe.worst * 1e3:.3f} mm" in ax.get_title()


def test_the_heat_panel_draws_the_set_points_and_the_wire_lag_late(kerf_plan):
    plan = kerf_plan
    ax = _titled(plan_figure(plan), HEAT_TITLE)
    assert ax is not None and "constant_kerf" in ax.get_title()
    t, hp = plan.motion.timed.t, plan.trajectory.heat_power
    set_line, wire_line = ax.get_lines()[:2]
    _samples_of(set_line, t, hp)
    y = _samples_of(wire_line, t, plan.measured.wire_power)
    x = np.asarray(wire_line.get_xdata(), dtype=float)
    np.testing.assert_allclose(y, np.interp(x - LAG, t, hp), rtol=0, atol=1e-9)
    assert np.ptp(hp) > 40.0  # the schedule, not zeros


def test_the_panels_appear_exactly_with_a_heat_model(kerf_plan, tmp_path):
    assert _titled(plan_figure(kerf_plan), KERF_TITLE) is not None
    rows = len(TIME_PANELS)
    assert len([ax for ax in plan_figure(kerf_plan).axes if ax.name != "3d"]) == rows
    # no heat model (on_off on a digital output, no [material]): neither panel
    (tmp_path / "plain").mkdir()
    plain = _plan(tmp_path / "plain", 'heat = { output = "standard:0", preheat = 0.5 }',
                  material=False)
    assert plain.trajectory.heat_power is None and plain.measured.wire_power is None
    fig = plan_figure(plain)
    assert _titled(fig, KERF_TITLE) is None and _titled(fig, HEAT_TITLE) is None
    assert len([ax for ax in fig.axes if ax.name != "3d"]) == rows - 2
    # a heat power without [material]: the heat panel, no kerf panel (the constant kerf)
    (tmp_path / "const").mkdir()
    const = _plan(tmp_path / "const", CONSTANT, material=False)
    fig = plan_figure(const)
    assert _titled(fig, KERF_TITLE) is None and _titled(fig, HEAT_TITLE) is not None
    assert len([ax for ax in fig.axes if ax.name != "3d"]) == rows - 1
