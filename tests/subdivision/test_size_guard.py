"""Work is bounded: a refinement that would not fit is refused with its numbers, exit 2."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import ruledrobot as rr
from ruledrobot.cli import app
from ruledrobot.io.lines import save_lines
from ruledrobot.subdivision import MAX_REFINED, get_scheme, refined_count

runner = CliRunner()


def _lines(n: int) -> rr.Lines:
    u = np.linspace(0, 1, n)
    return rr.Lines.from_point_direction(np.stack([0 * u, 0 * u, u], 1),
                                         np.stack([np.cos(u), np.sin(u), 0 * u], 1))  # fmt: skip


def test_refined_count_is_exact():
    for scheme in ("chaikin", "four_point", "ternary_four_point", "six_point", "bspline3"):
        for steps in range(4):
            res = rr.refine(_lines(9), "projection", scheme, steps)
            assert len(res.lines) == refined_count(get_scheme(scheme), 9, steps, False)


def test_refine_beyond_the_limit_is_refused_before_any_work(tmp_path):
    with pytest.raises(ValueError, match=r"20 steps of four_point on 100 elements make "
                       r"103,809,025 .*use at most 15 steps"):  # fmt: skip
        rr.refine(_lines(100), "dh", "four_point", 20)
    with pytest.raises(ValueError, match="limit is 5,000,000"):
        rr.subdivide(np.zeros((100, 3)), "four_point", 20)
    assert refined_count(get_scheme("four_point"), 100, 15, False) <= MAX_REFINED
    path = tmp_path / "l.json"
    save_lines(path, _lines(100))
    out = tmp_path / "r.json"
    result = runner.invoke(app, ["refine", str(path), "--steps", "20", "--out", str(out)])
    assert result.exit_code == 2 and "use at most 15 steps" in " ".join(result.output.split())
    assert not out.exists()


def test_a_job_too_large_to_plan_is_refused_with_its_numbers(tmp_path):
    from ruledrobot.wirecut.job.demo import DEMO_JOB

    job = tmp_path / "job.toml"
    job.write_text(DEMO_JOB.replace("steps = 4", "steps = 12")
                   .replace('scheme = "four_point"', 'scheme = "ternary_four_point"'))  # fmt: skip
    result = runner.invoke(app, ["plan", str(job), "--out", str(tmp_path / "out")])
    text = " ".join(result.output.split())
    assert result.exit_code == 2 and "4,251,529" in text and "use at most 9 steps" in text
    assert not (tmp_path / "out").exists()
