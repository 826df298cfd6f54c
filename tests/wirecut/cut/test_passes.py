"""Cut path: spacing-driven refinement, lead-in/out clearance, chord ends on the wire."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.geometry.box import Box
from ruledrobot.wirecut.cut.passes import chord_ends_in_flange, cut_path, refine_for_job
from ruledrobot.wirecut.cut.wire_geometry import chords
from ruledrobot.wirecut.job.load import load_job

from ..job.test_job import EXAMPLE


@pytest.fixture(scope="module")
def job(tmp_path_factory):
    p = tmp_path_factory.mktemp("job") / "job.toml"
    p.write_text(EXAMPLE)
    return load_job(p)


def test_cut_path_leads_in_and_out_clear_of_the_stock(job):
    cp = cut_path(job)
    assert cp.feasible
    F = cp.frames
    lead = job.cut.lead_in
    grown = Box(job.stock.centre, job.stock.size + 2 * lead, job.stock.rotation)
    # the first and last frames are clear of the stock grown by the lead distance
    hit = grown.clip_lines(F[[0, -1], :3, 3], F[[0, -1], :3, 2])[2]
    assert not hit.any()
    assert cp.motion.hit.sum() > 10
    e = chord_ends_in_flange(cp)[cp.motion.hit]
    w0, w1 = job.tool.wire_start, job.tool.wire_end
    d = (w1 - w0) / np.linalg.norm(w1 - w0)
    assert np.abs(np.cross(e - w0, d)).max() < 1e-9  # chord ends are points of the wire


def test_spacing_adds_steps_until_the_gap_holds(job):
    from dataclasses import replace

    def spaced(spacing: float):
        surface = replace(job.surface, steps=None, spacing=spacing)
        return replace(job, cuts=(replace(job.cut, surface=surface),))

    coarse, fine = spaced(0.01), spaced(0.002)
    Fc, sc = refine_for_job(coarse)
    Ff, sf = refine_for_job(fine)
    assert sf > sc
    for F, spacing in ((Fc, 0.01), (Ff, 0.002)):
        # the gap between rulings: distance of ruling i's chord ends to ruling i+1
        c0, c1, hit = chords(F, job.stock)
        o, z = F[:, :3, 3], F[:, :3, 2]
        for c in (c0, c1):
            d = o[:-1] + c[:-1, None] * z[:-1] - o[1:]
            dist = np.linalg.norm(d - (d * z[1:]).sum(1, keepdims=True) * z[1:], axis=1)
            assert dist[hit[:-1] & hit[1:]].max() <= spacing


def test_surface_far_from_stock_is_reported(job):
    from dataclasses import replace

    far = replace(job, stock=Box(job.stock.centre + np.array([2.0, 0.0, 0.0]), job.stock.size))
    with pytest.raises(ValueError, match="no refined ruling comes near the stock"):
        cut_path(far)
