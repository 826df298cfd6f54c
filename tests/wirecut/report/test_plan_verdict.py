"""The plan's verdict (wirecut.report.verdict) from measurements made up here: which checks
exist and gate, each failing alone, the bounds of the feed, unmeasured values, several
cuts named, and collisions in words."""

from __future__ import annotations

import dataclasses

import pytest

from ruledrobot.wirecut.report.verdict import (
    CutMeasurements,
    Measurements,
    collision_sentence,
    plan_verdict,
)

MARGIN = 0.02


def _cut(name: str = "cut", **kw) -> CutMeasurements:
    base = dict(
        name=name, feed_set_mm_s=10.0, feed_max_mm_s=10.1, feed_min_mm_s=9.9,
        feed_within_1pct=0.97, wire_deviation_mm=0.05, planned_wire_deviation_mm=0.04,
        kerf_mm=0.8, compensated=True, kept_surface_error_mm=0.02, wire_tolerance_mm=0.1,
        feed_tolerance=0.05,
    )  # fmt: skip
    base.update(kw)
    return CutMeasurements(**base)


def _meas(*cuts: CutMeasurements, **kw) -> Measurements:
    base = dict(
        reach_ok=True, reach_detail="", rulings=100, simulated=True, collisions=(),
        position_ratio=0.5, speed_ratio=0.6, acc_ratio=0.7, torque_ratio=0.3,
        singularity_min=0.1, tracking_error_mm=0.2, duration_s=30.0,
        cuts=cuts or (_cut(),),
    )  # fmt: skip
    base.update(kw)
    return Measurements(**base)


GATING_ONE_CUT = [
    "reach", "verified", "collisions", "transits", "wire_deviation", "planned_wire_deviation",
    "feed_max", "feed_min", "kept_surface", "joint_position", "joint_speed",
    "joint_acceleration", "joint_torque", "singularity",
]  # fmt: skip


def test_a_good_plan_passes_with_every_check_in_order():
    v = plan_verdict(_meas(), singularity_margin=MARGIN)
    assert v.ok and not v.failed
    names = [c.name for c in v.checks]
    assert [c.name for c in v.checks if c.gating] == GATING_ONE_CUT
    assert names[-4:] == ["tracking_error", "feed_within_1pct", "kerf", "duration"]
    assert v["kerf"].label == "kerf (compensated)" and v["kerf"].value == 0.8
    assert v["feed_max"].limit == pytest.approx(10.5) and v["feed_min"].limit == pytest.approx(9.5)


def test_an_uncompensated_cut_has_no_kept_surface_check():
    v = plan_verdict(_meas(_cut(compensated=False, kept_surface_error_mm=None)),
                     singularity_margin=MARGIN)  # fmt: skip
    assert v.ok
    assert "kept_surface" not in [c.name for c in v.checks]
    assert v["kerf"].label == "kerf (not compensated)"


def test_a_kerf_compensated_per_point_is_labelled_as_asked_not_as_compensated():
    """With [material] the wire follows the predicted kerf; the cut's kerf is what was asked."""
    v = plan_verdict(_meas(_cut(per_point=True, predicted_kerf="0.92-0.93 / 0.92-0.93 mm")),
                     singularity_margin=MARGIN)  # fmt: skip
    assert v["kerf"].label == "kerf asked (compensated per point: the predicted kerf)"
    assert v["predicted_kerf"].value == "0.92-0.93 / 0.92-0.93 mm"


@pytest.mark.parametrize(
    "check, meas",
    [
        ("wire_deviation", dict(cut=dict(wire_deviation_mm=0.11))),
        ("planned_wire_deviation", dict(cut=dict(planned_wire_deviation_mm=0.2))),
        ("feed_max", dict(cut=dict(feed_max_mm_s=10.51))),
        ("feed_min", dict(cut=dict(feed_min_mm_s=9.49))),
        ("kept_surface", dict(cut=dict(kept_surface_error_mm=0.1001))),
        ("joint_position", dict(position_ratio=1.0001)),
        ("joint_speed", dict(speed_ratio=1.01)),
        ("joint_acceleration", dict(acc_ratio=2.0)),
        ("joint_torque", dict(torque_ratio=1.2)),
        ("singularity", dict(singularity_min=0.019)),
        ("verified", dict(simulated=False)),
        ("collisions", dict(collisions=("link6 hits the stock",))),
        ("transits", dict(transits=("transit from 'top' to 'side': ... arm hits the stock",))),
    ],
)
def test_each_check_fails_alone(check, meas):
    cut_kw = meas.pop("cut", {})
    v = plan_verdict(_meas(_cut(**cut_kw), **meas), singularity_margin=MARGIN)
    assert not v.ok
    assert [c.name for c in v.failed] == [check]
    assert v[check].detail


def test_at_the_limits_the_checks_hold_and_unmeasured_values_fail():
    at = _cut(feed_max_mm_s=10.5, feed_min_mm_s=9.5, wire_deviation_mm=0.1,
              planned_wire_deviation_mm=0.1, kept_surface_error_mm=0.1)  # fmt: skip
    assert plan_verdict(_meas(at, position_ratio=1.0, singularity_min=MARGIN),
                        singularity_margin=MARGIN).ok  # fmt: skip
    v = plan_verdict(_meas(_cut(wire_deviation_mm=None, feed_within_1pct=None),
                           torque_ratio=None, tracking_error_mm=None),
                     singularity_margin=MARGIN)  # fmt: skip
    assert {c.name for c in v.failed} == {"wire_deviation", "joint_torque"}  # info never gates


def test_the_feed_min_sentence_says_what_holds_the_wire():
    v = plan_verdict(_meas(_cut(feed_min_mm_s=9.0, feed_min_limit="joint 2 sets the pace")),
                     singularity_margin=MARGIN)  # fmt: skip
    assert "slows below 10 mm/s - 5 %" in v["feed_min"].detail
    assert v["feed_min"].detail.endswith("joint 2 sets the pace")
    v = plan_verdict(_meas(_cut(feed_min_mm_s=9.0)), singularity_margin=MARGIN)
    assert v["feed_min"].detail.endswith("see the plots")


def test_several_cuts_are_named_in_their_checks():
    top, plug = _cut("top", compensated=False), _cut("plug", feed_max_mm_s=11.0, corner_stops=3)
    v = plan_verdict(_meas(top, plug), singularity_margin=MARGIN)
    names = [c.name for c in v.checks]
    for n in ("wire_deviation", "planned_wire_deviation", "feed_max", "feed_min"):
        assert f"{n}:top" in names and f"{n}:plug" in names and n not in names
    assert "kept_surface:plug" in names and "kept_surface:top" not in names
    assert [c.name for c in v.failed] == ["feed_max:plug"]
    assert v["feed_max:plug"].label.endswith("(plug)")
    assert "corner_stops:plug" in names and "corner_stops:top" not in names
    assert not v["corner_stops:plug"].gating and v["corner_stops:plug"].value == 3


def test_out_of_reach_fails_reach_and_collisions_unmeasured():
    v = plan_verdict(_meas(reach_ok=False, reach_detail="rulings 3-7 out of reach"),
                     singularity_margin=MARGIN)  # fmt: skip
    assert {c.name for c in v.failed} == {"reach", "collisions"}
    assert v["reach"].detail == "rulings 3-7 out of reach"
    assert v["collisions"].value is None


def test_many_collisions_are_listed_eight_and_counted():
    hits = tuple(f"hit {i}" for i in range(11))
    c = plan_verdict(_meas(collisions=hits), singularity_margin=MARGIN)["collisions"]
    assert c.value == 11
    assert c.detail.splitlines() == [f"hit {i}" for i in range(8)] + ["and 3 more"]


def _collision(**kw) -> dict:
    c = dict(geom1="stock", body1="world", geom2="link6_collision", body2="link6",
             start_s=1.234, end_s=2.5, max_depth_mm=3.21)  # fmt: skip
    c.update(kw)
    return c


def test_collision_sentences_put_the_robots_part_first():
    assert collision_sentence(_collision(), "cut") == (
        "link6_collision hits the stock, 3.2 mm deep, from t = 1.23 s to 2.50 s (cut)")
    assert collision_sentence(_collision(geom1="bow", body1="tool", geom2="table",
                                         body2="world", end_s=1.234), "transit") == (
        "bow of tool hits the table, 3.2 mm deep, at t = 1.23 s (transit)")  # fmt: skip
    assert collision_sentence(_collision(geom1="post", body1=""), "approach").startswith(
        "link6_collision hits post,")


def test_measurements_are_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        _cut().kerf_mm = 1.0  # type: ignore[misc]
