"""Per-point kerf compensation (wirecut.cut.kerf, docs/kerf.md) against closed forms: on the
tapered panel the tip end moves 0.8 times as fast as the root, so with the supply set for
the nominal kerf at the feed it melts ``kerf_base + (kerf - kerf_base) / 0.8`` there."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from ruledrobot.robot.wire.kerf import Material
from ruledrobot.wirecut.cut.heat_power import held_kerf
from ruledrobot.wirecut.cut.kerf import cut_offsets, kerf_offsets
from ruledrobot.wirecut.cut.passes import refine_cut
from ruledrobot.wirecut.cut.wire_geometry import chords
from ruledrobot.wirecut.job.load import load_job

from .panel import KERF, MATERIAL, ROOT, TIP, Z0, write_panel


@given(st.floats(0.05, 1.0), st.floats(0.0004, 0.003), st.floats(0.001, 0.05))
def test_constant_kerf_ends_agree_with_the_model(ratio, kerf, feed):
    """``constant_kerf``'s shortcut equals the model at the power that melts ``kerf`` at
    the reference point's speed, evaluated at the end's speed."""
    m = Material(**MATERIAL)
    job_cut = type("C", (), {"kerf": kerf, "feed_speed": feed})
    heat = type("H", (), {"mode": "constant_kerf", "kind": "analog", "full_scale": None})
    p = m.power_for_kerf(kerf, feed)
    assert held_kerf(ratio, job_cut, heat, m) == pytest.approx(m.kerf(feed * ratio, p), rel=1e-12)


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    job = load_job(write_panel(tmp_path_factory.mktemp("panel")))
    rc = refine_cut(job.cut, job.stock, "panel", job.tool.wire_length)
    return job, rc


def _end_offsets(job, rc, k):
    """(M, 2) the wire's height above the plane at the root (y = -0.1) and tip (y = 0.1)."""
    F = k.moved(rc.frames)
    o, z = F[:, :3, 3], F[:, :3, 2]
    out = []
    for y in (-0.1, 0.1):
        t = (y - o[:, 1]) / z[:, 1]
        out.append(o[:, 2] + t * z[:, 2] - Z0)
    return np.stack(out, axis=1)


def test_tapered_panel_ends_get_their_own_offsets(panel):
    job, rc = panel
    k = cut_offsets(rc.frames, job.stock, job.cut, job.tool.heat, job.material, False)
    c0, c1, hit = chords(rc.frames, job.stock)
    full = hit & (np.abs(c1 - c0) > 0.99 * 0.2)  # chords from the root face to the tip face
    assert full.sum() > 20
    h = _end_offsets(job, rc, k)[full]
    kb = MATERIAL["kerf_base"]
    tip_kerf = kb + (KERF - kb) / (TIP / ROOT)
    np.testing.assert_allclose(h[:, 0], KERF / 2, atol=2e-7)  # root: the reference end
    np.testing.assert_allclose(h[:, 1], tip_kerf / 2, atol=2e-7)
    np.testing.assert_allclose(k.end_kerf[full][:, [0, -1]].min(), KERF, atol=1e-9)
    assert np.nanmax(k.end_kerf) == pytest.approx(tip_kerf, rel=1e-6)
    # between the ends the kerf follows 1/v, v affine along the wire: the straight wire
    # misses its half by the chord-to-curve gap of kb + (kerf - kb) / (1 - 0.2 lam)
    lam = np.linspace(0.0, 1.0, 9)
    half = 0.5 * (kb + (KERF - kb) / (1.0 - (1.0 - TIP / ROOT) * lam))
    gap = np.abs(half[0] + lam * (half[-1] - half[0]) - half).max()
    np.testing.assert_allclose(k.error[full], gap, rtol=1e-3)


def test_without_material_the_constant_kerf_is_unchanged(panel):
    job, rc = panel
    plain = dataclasses.replace(job, material=None)
    k = cut_offsets(rc.frames, job.stock, job.cut, job.tool.heat, plain.material, False)
    ref = kerf_offsets(rc.frames, job.stock, KERF, job.cut.keep, False)
    np.testing.assert_array_equal(k.offset, ref.offset)
    assert k.turn is None
    np.testing.assert_allclose(_end_offsets(job, rc, k)[10:-10], KERF / 2, atol=1e-12)


def test_clipped_power_the_compensation_uses_what_the_schedule_sets(tmp_path):
    """constant_kerf with full_scale below the power the kerf asks at the feed (50 W/m):
    the schedule sets 45 W/m on the held stretch and the compensation moves the reference
    end by half the kerf 45 W/m melts there, not half the cut's kerf; the plan says so."""
    from ruledrobot.wirecut.cut.passes import cut_paths

    heat = ('heat = { output = "analog:0", mode = "constant_kerf", full_scale = 45.0, '
            "preheat = 0.5 }")
    job = load_job(write_panel(tmp_path, heat))
    rc = refine_cut(job.cut, job.stock, "panel", job.tool.wire_length)
    k = cut_offsets(rc.frames, job.stock, job.cut, job.tool.heat, job.material, False)
    c0, c1, hit = chords(rc.frames, job.stock)
    full = hit & (np.abs(c1 - c0) > 0.99 * 0.2)
    m = Material(**MATERIAL)
    clipped = m.kerf(job.cut.feed_speed, 45.0)  # 0.7375 mm
    assert clipped < KERF
    np.testing.assert_allclose(_end_offsets(job, rc, k)[full][:, 0], clipped / 2, atol=2e-7)
    notes = " ".join(n for cp in cut_paths(job) for n in cp.notes)
    assert "full_scale 45 W/m clips" in notes and "face_error judges" in notes
