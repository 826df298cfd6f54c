"""A path program's samples matched to the plan's across a drift of the clocks (issue 32:
the wedge's movep program was refused as 54.53 mm off the plan because its transits ran
4.9 s ahead and the match looked within 1 s of the same time)."""

from __future__ import annotations

import numpy as np

from ruledrobot.export.verify_program import MATCH_WINDOW, _match


def _path(s: np.ndarray) -> np.ndarray:
    """Features (N, 6) of a wire at path parameter ``s``: a loop that comes back to its
    start (s = 0 and s = 1 meet), so that a match by pose alone would be ambiguous."""
    a = 2 * np.pi * s
    return np.stack([np.cos(a), np.sin(a), 0 * a, np.cos(a), np.sin(a), 0 * a + 0.4], 1) * 0.1


def test_a_program_that_drifts_by_many_windows_matches_its_own_samples():
    period = 0.004
    plan_t = np.arange(0.0, 100.0, period)
    # the plan: a dwell of 10 s, then the loop at a steady pace
    plan_s = np.clip((plan_t - 10.0) / 90.0, 0.0, 1.0)
    # the program: the same dwell, then the loop 4 % faster (3.5 s ahead at its end)
    t = np.arange(0.0, 10.0 + 90.0 / 1.04, period)
    s = np.clip((t - 10.0) * 1.04 / 90.0, 0.0, 1.0)
    assert 90.0 - 90.0 / 1.04 > 3 * MATCH_WINDOW
    got = _match(plan_t, _path(plan_s), t, _path(s), MATCH_WINDOW)
    moving = t > 10.5
    # the matched plan sample is where the plan is at the program's s: within a period
    assert np.abs(plan_s[got][moving] - s[moving]).max() <= 2 * period / 90.0
    # in the dwell, the sample nearest in time (the poses are equal)
    assert np.abs(plan_t[got][t < 9.0] - t[t < 9.0]).max() <= period
    # the loop's end is never matched to its start
    assert plan_t[got][-1] > 99.0
