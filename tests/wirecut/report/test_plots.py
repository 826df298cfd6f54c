"""plots.png (wirecut.report.plots, plot3d) on a small plan: the artists a reader needs
are there — the phases named in the legend, the block, the part shaded, the wire at a few
samples only, equal scales, every title and label inside the figure — and a time panel
added to the tuple gets its own row.  No pixel comparisons."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgb
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from ruledrobot.io.axes3d import coarse_mesh
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job
from ruledrobot.wirecut.plan import make_plan
from ruledrobot.wirecut.report.files import surface_mesh
from ruledrobot.wirecut.report.part_mesh import part_mesh
from ruledrobot.wirecut.report.plot3d import PART_COLOUR, PHASE_WORDS, WIRES_PER_PASS
from ruledrobot.wirecut.report.plots import TIME_PANELS, ShownWhen, plan_figure, plot_plan

#: the demo's saddle keeping the block below it: a part to draw
KEPT = DEMO_JOB.replace("kerf = 0.0008", "kerf = 0.0008\nkeep = [0.5, 0.0, 0.2]")


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    job_file = tmp_path_factory.mktemp("job") / "kept.toml"
    job_file.write_text(KEPT)
    plan = make_plan(load_job(job_file))
    assert plan.motion is not None
    return plan, part_mesh(plan.job, plan.passes, 0.005), surface_mesh(plan)


def _scene(fig):
    return next(ax for ax in fig.axes if ax.name == "3d")


def test_the_legend_names_every_phase_of_the_motion_and_the_part(planned):
    plan, part, surface = planned
    fig = plan_figure(plan, part, surface)
    words = " / ".join(t.get_text() for t in _scene(fig).get_legend().get_texts()).split(" / ")
    phases = set(np.unique(plan.motion.labels.astype(str)))
    assert {"lead_in", "cut", "lead_out"} <= phases
    assert {PHASE_WORDS[p] for p in phases} <= set(words)
    assert {"part", "block"} <= set(words)


def test_every_title_and_label_lies_inside_the_figure(planned):
    plan, part, surface = planned
    fig = plan_figure(plan, part, surface)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    box = fig.bbox
    for ax in fig.axes:
        t = ax.title.get_window_extent(r)
        assert ax.get_title() and box.x0 <= t.x0 and t.x1 <= box.x1 and t.y1 <= box.y1
        b = ax.get_tightbbox(r)  # ticks, labels, legends, titles
        assert box.x0 - 1 <= b.x0 and b.x1 <= box.x1 + 1 and box.y0 - 1 <= b.y0
        assert b.y1 <= box.y1 + 1, ax.get_title()
    scene = _scene(fig)
    t, a = scene.title.get_window_extent(r), scene.get_window_extent(r)
    assert a.x0 <= t.x0 and t.x1 <= a.x1  # the 3-D title over its own panel


def test_the_scene_shows_the_block_the_shaded_part_and_a_few_wires(planned):
    plan, part, surface = planned
    fig = plan_figure(plan, part, surface)
    fig.canvas.draw()
    scene = _scene(fig)
    polys = [c for c in scene.collections if isinstance(c, Poly3DCollection)]
    assert len(polys) == 2  # the block's faces, the part
    assert len(polys[1].get_paths()) == len(coarse_mesh(part.vertices, part.faces)[1])
    # shaded: one hue (the part's colour) at several brightnesses
    rgb = polys[1].get_facecolor()[:, :3]
    hue = rgb / rgb.sum(axis=1, keepdims=True)
    want = np.array(to_rgb(PART_COLOUR)) / sum(to_rgb(PART_COLOUR))
    np.testing.assert_allclose(hue, np.broadcast_to(want, hue.shape), atol=1e-9)
    assert np.ptp(rgb.sum(axis=1)) > 0.1
    lines = [c for c in scene.collections if isinstance(c, Line3DCollection)]
    edges, wires = lines[0], lines[1:]
    assert len(edges.get_segments()) == 12
    drawn = sum(len(w.get_segments()) for w in wires)
    assert 0 < drawn <= len(plan.passes) * sum(WIRES_PER_PASS.values())
    assert drawn < len(plan.motion.labels) / 100  # a few samples, not every sample
    lims = np.array([scene.get_xlim(), scene.get_ylim(), scene.get_zlim()])
    np.testing.assert_allclose(np.ptp(lims, axis=1), np.ptp(lims[0]))
    np.testing.assert_allclose(scene.get_box_aspect(), scene.get_box_aspect()[0])
    # the block's centre (mm) at the view's centre
    np.testing.assert_allclose(lims.mean(axis=1), plan.job.stock.centre * 1e3)


def test_without_a_part_the_cut_surfaces_are_drawn(planned):
    plan, _, surface = planned
    scene = _scene(plan_figure(plan, None, surface))
    words = [t.get_text() for t in scene.get_legend().get_texts()]
    assert "cut surfaces" in words and "part" not in words
    assert sum(isinstance(c, Poly3DCollection) for c in scene.collections) == 2


def test_a_time_panel_added_gets_its_own_row(planned, tmp_path):
    plan, part, surface = planned
    seen = []

    def heat_panel(ax, p):
        seen.append(p)
        ax.plot(p.motion.timed.t, p.motion.heat.astype(float))
        ax.set_title("heat")

    fig = plan_figure(plan, part, surface, (*TIME_PANELS, heat_panel))
    flat = [ax for ax in fig.axes if ax.name != "3d" and ax.get_title()]
    assert [ax.get_title() for ax in flat][-1] == "heat" and seen == [plan]
    assert len({round(ax.get_position().x0, 6) for ax in flat}) == 1  # one column
    ys = [ax.get_position().y0 for ax in flat]
    # the demo has no heat model: the kerf and heat panels (ShownWhen) take no row
    shown = [p for p in TIME_PANELS if not isinstance(p, ShownWhen) or p.rule(plan)]
    assert len(shown) == len(TIME_PANELS) - 2
    assert ys == sorted(ys, reverse=True) and len(flat) == len(shown) + 1
    out = plot_plan(tmp_path / "plots.png", plan, part, surface)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert isinstance(fig.canvas, FigureCanvasAgg)
