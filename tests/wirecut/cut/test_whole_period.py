"""A closed built-in surface given over a whole period (``u = [0.0, 6.2832]``, ``closed =
true``) is sampled without its repeated end: the same rulings as the periodic default,
planned, not refused as "consecutive rulings coincide: 16 and 0" (issue 22, item 4)."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.wirecut.cut.passes import cut_paths
from ruledrobot.wirecut.job.demo import PART_JOB
from ruledrobot.wirecut.job.load import load_job

PLUG = '''builtin = "hyperboloid"
params = { a = 0.06, c = 0.3 }
rulings = 16
'''


@pytest.mark.parametrize("u", ["[0.0, 6.2832]", "[0.0, 6.283185307179586]", "[1.0, 7.2832]"])
def test_a_whole_period_is_sampled_without_its_repeated_end(tmp_path, u):
    assert PLUG in PART_JOB
    (tmp_path / "default.toml").write_text(PART_JOB)
    (tmp_path / "range.toml").write_text(PART_JOB.replace(PLUG, PLUG + f"u = {u}\nclosed = true\n"))
    plug = load_job(tmp_path / "default.toml").cuts[-1]
    ranged = load_job(tmp_path / "range.toml").cuts[-1]
    job = load_job(tmp_path / "range.toml")
    assert cut_paths(job, job.cuts[-1])  # refined and cut, not refused
    lines, ref = ranged.surface.lines(), plug.surface.lines()
    assert len(lines) == 16 and ranged.surface.document().closed
    if u.startswith("[0.0"):  # the same rulings as the periodic default
        np.testing.assert_allclose(lines.plucker, ref.plucker, atol=1e-12)
    assert ranged.surface.whole_period


def test_a_partial_range_stays_open(tmp_path):
    (tmp_path / "j.toml").write_text(PART_JOB.replace(PLUG, PLUG + "u = [0.0, 3.0]\n")
                                     .replace('keep = "inside"', "keep = [0.5, 0.0, 0.3]"))
    s = load_job(tmp_path / "j.toml").cuts[-1].surface
    assert not s.document().closed and len(s.lines()) == 16
