"""Orders of cuts a wire can make (wirecut.cut.order): the part demo as it is, reordered,
with a hole, with the later cut moved outside the loop; the crossing-number test against
half-planes (convex polygons) and a union of rectangles (an L)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.wirecut.cut.order import _points_in_polygon, check_cut_order
from ruledrobot.wirecut.job.demo import PART_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job


def _doc() -> dict:
    return job_document(PART_JOB, "part.toml")


def _job(doc: dict):
    return parse_job(doc, "part.toml")


def _plug_first(doc: dict) -> dict:
    doc["cut"] = [doc["cut"][2], *doc["cut"][:2]]
    return doc


def test_the_part_demo_order_is_accepted():
    check_cut_order(_job(_doc()))


def test_a_cut_after_the_plug_closes_is_refused_naming_both():
    with pytest.raises(ValueError, match=r"job: cut 'top' comes after cut 'plug', a "
                       r"closed cut that keeps its inside.*list 'top' before 'plug'"):  # fmt: skip
        check_cut_order(_job(_plug_first(_doc())))


def test_a_later_cut_outside_the_loop_is_accepted():
    doc = _plug_first(_doc())
    doc["cut"] = [doc["cut"][0], doc["cut"][2]]  # plug, then side
    # the side face 4.5 cm from the axis cuts through the band (its waist is 6 cm) ...
    with pytest.raises(ValueError, match="cut 'side' comes after cut 'plug'"):
        _check_with_side_at(doc, 0.545)
    _check_with_side_at(doc, 0.58)  # 8 cm from the axis: outside the band, accepted


def _check_with_side_at(doc: dict, x: float) -> None:
    doc["cut"][1]["surface"]["pose"] = [x, 0.0, 0.3, 0.0, 1.5707963267948966, 0.0]
    check_cut_order(_job(doc))


def test_a_hole_is_refused():
    doc = _doc()
    doc["cut"][2]["keep"] = "outside"
    with pytest.raises(ValueError, match=r"cut 'plug': keep = \"outside\" \(a hole\) cannot "
                       "be cut with a wire"):  # fmt: skip
        check_cut_order(_job(doc))


@pytest.mark.parametrize("keep", [None, [0.5, 0.0, 0.3]])
def test_a_loop_that_does_not_keep_its_inside_frees_nothing(keep):
    doc = _plug_first(_doc())
    if keep is None:
        del doc["cut"][0]["keep"]
    else:
        doc["cut"][0]["keep"] = keep
    check_cut_order(_job(doc))


@settings(max_examples=60, deadline=None)
@given(
    st.integers(3, 12),
    st.floats(0.0, 2 * np.pi),
    st.lists(st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5)), min_size=1, max_size=30),
)
def test_points_in_a_convex_polygon_agree_with_its_half_planes(k, phase, pts):
    th = phase + 2 * np.pi * np.arange(k) / k
    poly = np.c_[np.cos(th), np.sin(th)]  # counter-clockwise
    p = np.asarray(pts, dtype=float)
    a, b = poly, np.roll(poly, -1, axis=0)
    side = ((b - a)[None, :, 0] * (p[:, None, 1] - a[None, :, 1])
            - (b - a)[None, :, 1] * (p[:, None, 0] - a[None, :, 0]))  # fmt: skip
    clear = np.abs(side).min(axis=1) > 1e-9  # not on an edge's line
    inside = (side > 0).all(axis=1)
    got = _points_in_polygon(p, poly)
    np.testing.assert_array_equal(got[clear], inside[clear])
    np.testing.assert_array_equal(_points_in_polygon(p, poly[::-1])[clear], inside[clear])


def test_points_in_an_l_shaped_polygon():
    L = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    rng = np.random.default_rng(5)
    p = rng.uniform(-0.5, 2.5, size=(2000, 2))
    inside = (((p[:, 0] > 0) & (p[:, 0] < 2) & (p[:, 1] > 0) & (p[:, 1] < 1))
              | ((p[:, 0] > 0) & (p[:, 0] < 1) & (p[:, 1] > 0) & (p[:, 1] < 2)))  # fmt: skip
    np.testing.assert_array_equal(_points_in_polygon(p, L), inside)
    assert 0.2 < inside.mean() < 0.5
