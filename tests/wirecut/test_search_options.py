"""The wire-pose search's options as one frozen value (issue 23: no untyped ``**search``
from make_plan through cut_paths, loop_paths and closed._pass to the search)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import ruledrobot as rr
from ruledrobot.wirecut.cut.passes import cut_paths, job_search
from ruledrobot.wirecut.cut.wire_pose import SearchOptions, search_wire_pose, solve_redundancy
from ruledrobot.wirecut.job.demo import DEMO_JOB, PART_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job


def _job(text: str = DEMO_JOB):
    return parse_job(job_document(text, "job"))


def test_solve_redundancy_takes_the_options_fields_and_nothing_else():
    # its keywords are SearchOptions' fields (the defaults live there alone)
    job = _job()
    model = rr.robot.load("ur5e")
    F = np.repeat(np.eye(4)[None], 3, axis=0)
    with pytest.raises(TypeError, match="rols"):
        solve_redundancy(F, job.stock, job.tool, model, rols=12)
    with pytest.raises(ValueError, match="strategy: expected auto, constant or varying"):
        solve_redundancy(F, job.stock, job.tool, model, strategy="greedy")


def test_the_options_are_frozen_and_checked():
    with pytest.raises(dataclasses.FrozenInstanceError):
        SearchOptions().rolls = 12  # type: ignore[misc]
    with pytest.raises(ValueError, match="strategy: expected auto, constant or varying"):
        SearchOptions(strategy="greedy")


def test_solve_redundancy_is_the_search_with_its_options():
    job = _job()
    model = job.robot_model()
    F = rr.refine(job.input_lines(), "dh", "four_point", 3).frames
    options = SearchOptions(rolls=12, sample=40)
    a = solve_redundancy(F, job.stock, job.tool, model, rolls=12, sample=40)
    b = search_wire_pose(F, job.tool, options.cell(model, job.tool, job.stock), options)
    assert a.feasible and b.feasible and a.candidates == b.candidates
    for name in ("roll", "slide", "flange", "q", "chord"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_the_job_home_is_where_the_motion_starts_unless_the_options_say():
    job = _job()
    assert job_search(job).q_start is None
    home = np.array([0.0, -1.5, 1.5, -1.5, -1.5, 0.0])
    homed = dataclasses.replace(job, robot=dataclasses.replace(job.robot, home=home))
    np.testing.assert_array_equal(job_search(homed).q_start, home)
    own = np.zeros(6)
    np.testing.assert_array_equal(job_search(homed, SearchOptions(q_start=own)).q_start, own)
    assert job_search(homed, SearchOptions(rolls=12)).rolls == 12


def _same_motion(a, b) -> None:
    assert a.feasible == b.feasible and a.candidates == b.candidates
    for name in ("roll", "slide", "flange", "q"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_the_options_reach_the_passes_of_an_open_and_a_closed_cut():
    """``rolls`` travels make_plan -> cut_paths -> (loop_paths -> closed._pass) -> the
    search: each pass's motion is the search's with those options on its frames."""
    job = _job()
    model = job.robot_model()
    (cp,) = cut_paths(job, search=SearchOptions(rolls=12))
    _same_motion(cp.motion, solve_redundancy(cp.frames, job.stock, job.tool, model, rolls=12))
    assert cp.motion.candidates != cut_paths(job)[0].motion.candidates  # 36 rolls by default
    part = _job(PART_JOB)
    plug = next(c for c in part.cuts if c.name == "plug")
    passes = cut_paths(part, plug, search=SearchOptions(rolls=12))
    assert passes and all(cp.closed and cp.cut is plug for cp in passes)
    for cp in passes:
        _same_motion(cp.motion, solve_redundancy(cp.frames, part.stock, part.tool,
                                                 part.robot_model(), rolls=12))  # fmt: skip
