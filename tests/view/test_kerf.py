"""The predicted kerf and the heat in the viewer (view.kerf, docs/view.md "Kerf and heat"),
on issue 33's tapered panel and its corner: the timeline's kerf is the verdict's own
(``plan.measured.faces``, the widest since the frame before, computed here by a loop), the
heat the trajectory's set-points and the wire's power the set-point ``lag`` late
(np.interp); the trace's colours run along the scale; a burn between frames is shown; a
plan without a heat model shows none of it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ruledrobot.view import build_scene, read_plan_folder
from ruledrobot.view.draw import caption, figures_markdown
from ruledrobot.view.export import overlay_html
from ruledrobot.view.kerf import (
    BURN_COLOUR,
    STOPS,
    burn_points,
    kerf_colours,
    kerf_legend_html,
    kerf_range,
    kerf_trace,
)
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.planner import plan
from tests.wirecut.kerf.panel import write_corner, write_panel

LAG = 0.1
CONSTANT_KERF = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 200.0, '
                 f"lag = {LAG}, preheat = 0.5 }}")  # fmt: skip
CONSTANT = ('heat = { output = "analog:0", mode = "constant", power = 50.0, '
            'full_scale = 200.0, preheat = 0.5 }')  # fmt: skip


def _scene(folder, job_path):
    """The scene of the job's plan folder, with the plan's own trajectory (heat_power and
    all) -- the folder of a plan that is not verified in MuJoCo holds none."""
    result = plan(load_job(job_path), folder / "out", simulate=False)
    p = result.plan
    assert p is not None and p.trajectory is not None
    pf = dataclasses.replace(read_plan_folder(folder / "out"), trajectory=p.trajectory)
    return p, build_scene(pf)


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    d = tmp_path_factory.mktemp("kerf-view")
    return _scene(d, write_panel(d, CONSTANT_KERF))


def _widest_since_last_frame(kerf, frames):
    out = np.full((len(frames), 2), np.nan)
    prev = -1
    for i, k in enumerate(frames):
        rows = kerf[prev + 1 : k + 1]
        for j in range(2):
            col = rows[:, j][~np.isnan(rows[:, j])]
            if col.size:
                out[i, j] = col.max()
        prev = k
    return out


def test_the_timeline_carries_the_verdicts_kerf_and_the_heat(panel):
    p, scene = panel
    tl = scene.timeline
    fe = p.measured.faces["cut"]
    want = _widest_since_last_frame(fe.kerf, tl.sample)
    np.testing.assert_array_equal(np.isnan(tl.kerf), np.isnan(want))
    np.testing.assert_allclose(tl.kerf, want, rtol=1e-6, atol=0)
    # the tapered panel: the slow end melts wider than the fast one, as report.json says
    on = ~np.isnan(tl.kerf).any(axis=1)
    assert on.sum() > 30
    assert np.nanmax(tl.kerf[:, 0]) > 0.9e-3 > 0.81e-3 > np.nanmax(tl.kerf[:, 1])
    t, hp = p.trajectory.t, p.trajectory.heat_power
    np.testing.assert_array_equal(tl.heat_power, hp[tl.sample])
    np.testing.assert_allclose(tl.wire_power, np.interp(tl.t - LAG, t, hp), atol=1e-9)
    k = int(np.flatnonzero(on)[on.sum() // 2])
    words = f"{tl.kerf[k, 0] * 1e3:.3f} / {tl.kerf[k, 1] * 1e3:.3f} mm"
    assert f"kerf {words}" in caption(scene, k)
    assert f"| kerf | {words} (predicted at the wire's start / end side) |" in \
        figures_markdown(scene, k)
    assert f"heat {tl.heat_power[k]:.1f} W/m" in caption(scene, k)


def test_the_trace_is_coloured_along_the_scale(panel):
    _, scene = panel
    tl = scene.timeline
    lo, hi = kerf_range(scene)
    finite = tl.kerf[np.isfinite(tl.kerf)]
    assert lo <= min(finite.min(), 0.8e-3) and hi >= finite.max()
    seg, w = kerf_trace(tl)
    assert seg.shape[1:] == (2, 3) and w.shape == seg.shape[:2]
    assert np.isfinite(seg).all() and np.isfinite(w).all()
    # the chord ends' paths lie on the block's faces (60 x 200 x 100 mm about (0.5, 0, 0.3)):
    # mostly those the wire spans (y = -0.1, 0.1), across a corner where it enters
    off = np.abs(np.abs(seg - [0.5, 0.0, 0.3]) - [0.03, 0.1, 0.05])
    assert off.min(axis=-1).max() < 1e-6
    assert np.mean(off[..., 1] < 1e-6) > 0.8
    rgb = kerf_colours(np.array([lo, hi, np.inf]), lo, hi)
    np.testing.assert_array_equal(rgb, [STOPS[0], STOPS[-1], BURN_COLOUR])
    legend = kerf_legend_html(scene)
    assert f"{lo * 1e3:.3f} mm" in legend and f"{hi * 1e3:.3f} mm" in legend
    assert "the cut's kerf 0.800 mm" in legend and "burn" not in legend
    assert legend in overlay_html(scene)


def test_a_burn_between_frames_is_shown(tmp_path):
    p, scene = _scene(tmp_path, write_corner(tmp_path, CONSTANT))
    assert p.measured.faces["cut"].burn
    tl = scene.timeline
    assert np.isinf(tl.kerf).any() and len(burn_points(tl)) >= 1
    assert "burn" in kerf_legend_html(scene)


def test_without_a_heat_model_the_viewer_shows_no_kerf_or_heat(scene):
    tl = scene.timeline  # the demo: heat switched, no [material]
    assert tl.kerf is None and tl.heat_power is None and tl.wire_power is None
    assert kerf_range(scene) is None and kerf_trace(tl) is None and len(burn_points(tl)) == 0
    assert kerf_legend_html(scene) == ""
    assert "kerf" not in caption(scene, tl.t.size // 2)
