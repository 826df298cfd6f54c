"""The next best for a face the arm cannot make: the block turned a quarter turn (issue 32).

:func:`next_best` asks the robot check again with the cut and the block turned about the
block's own axes; here the check is a stand-in that accepts horizontal rulings only (the
robot's answer is tested with the planner in tests/carve/test_robot_check*.py), so that the
turn, the words and the cell fields they name can be checked exactly."""

from __future__ import annotations

import re

import numpy as np
import tomllib

from ruledrobot.carve.cell import parse_cell
from ruledrobot.carve.model import CarveCut
from ruledrobot.carve.robotcheck import TURNS, next_best, quarter_turns
from ruledrobot.geometry import se3
from ruledrobot.geometry.box import Box
from ruledrobot.geometry.lines import Lines
from ruledrobot.io.demo_cell import DEMO_CELL

STOCK = Box(np.array([0.5, 0.1, 0.3]), np.array([0.2, 0.15, 0.1]))
PART = se3.pose_from_ur_vector([0.5, 0.1, 0.3, 0.0, 0.0, 0.3])


class _Horizontal:
    """A robot check that makes a cut only when its rulings are horizontal."""

    def __init__(self) -> None:
        self.calls, self.stocks, self.exhausted = 0, [], False

    def __call__(self, cut: CarveCut, stock=None) -> str:
        self.calls += 1
        self.stocks.append(stock)
        return "" if np.abs(cut.lines.direction[:, 2]).max() < 1e-9 else "vertical: no"


def _vertical_cut() -> CarveCut:
    p = STOCK.centre + np.c_[np.linspace(-0.05, 0.05, 5), np.zeros(5), np.zeros(5)]
    keep = STOCK.centre + np.array([0.0, 0.03, 0.0])
    return CarveCut("face0", "exact", Lines.from_point_direction(p, np.tile([0, 0, 1.0], (5, 1))),
                    False, keep, "region 0: plane, open", 0)  # fmt: skip


def test_turns_are_rigid_quarter_turns_about_the_blocks_centre():
    for turn, (axis, deg) in zip(quarter_turns(STOCK, PART), TURNS, strict=True):
        R = turn.T[:3, :3]
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(turn.T @ np.r_[STOCK.centre, 1.0], np.r_[STOCK.centre, 1.0])
        assert np.isclose(np.degrees(np.linalg.norm(se3.rotvec_from_matrix(R))), abs(deg))
        np.testing.assert_allclose(R @ STOCK.rotation[:, axis], STOCK.rotation[:, axis])
        np.testing.assert_allclose(turn.stock.corners, (R @ (STOCK.corners - STOCK.centre).T).T
                                   + STOCK.centre, atol=1e-12)  # fmt: skip
        np.testing.assert_allclose(turn.part_pose, turn.T @ PART)


def test_the_first_turn_the_check_accepts_is_offered_with_the_fields_to_write():
    check = _Horizontal()
    words = next_best(check, _vertical_cut(), STOCK, PART, {"stock": {"size": [0.2, 0.15, 0.1]}})
    assert check.calls == 1  # a quarter turn about x lays vertical rulings down
    assert words.startswith("with the block turned +90° about its x axis the arm can make it")
    rv = [float(x) for x in re.search(r"rotvec = \[([^\]]*)\]", words).group(1).split(",")]
    pose = [float(x) for x in re.search(r"pose = \[([^\]]*)\]", words).group(1).split(",")]
    turn = quarter_turns(STOCK, PART)[0]
    np.testing.assert_allclose(se3.pose_from_rotvec(rv)[:3, :3], turn.stock.rotation, atol=1e-5)
    np.testing.assert_allclose(se3.pose_from_ur_vector(pose), turn.part_pose, atol=1e-5)
    assert check.stocks[0]["size"] == [0.2, 0.15, 0.1]  # the cell's table, turned
    np.testing.assert_allclose(check.stocks[0]["rotvec"], rv, atol=1e-5)


def test_no_turn_tried_in_a_cell_with_a_robot_base_and_every_turn_named_when_none_helps():
    check = _Horizontal()
    assert next_best(check, _vertical_cut(), STOCK, PART,
                     {"robot": {"base": [0.1, 0, 0, 0, 0, 0]}}) == ""  # fmt: skip
    assert check.calls == 0
    lying = _vertical_cut()
    refuse = lambda cut, stock=None: "no"  # noqa: E731
    refuse.exhausted = False  # type: ignore[attr-defined]
    words = next_best(refuse, lying, STOCK, PART, {})
    assert words == ("the block turned +90° about x, -90° about x, +90° about y, -90° about y "
                     "does not let the arm make it either")  # fmt: skip


def test_turns_is_a_boolean_of_the_part_table(tmp_path):
    (tmp_path / "p.stl").write_text("solid p\nendsolid p\n")
    text = f'[part]\nfile = "p.stl"\nunits = "mm"\nturns = "no"\n{DEMO_CELL}'
    doc = tomllib.loads(text)
    try:
        parse_cell(doc, "cell.toml", base_dir=tmp_path)
    except ValueError as exc:
        assert str(exc) == "cell.toml: [part] turns: expected true or false, got 'no'"
    else:
        raise AssertionError("turns = 'no' accepted")
    doc["part"]["turns"] = False
    assert parse_cell(doc, "cell.toml", base_dir=tmp_path).part.turns is False
