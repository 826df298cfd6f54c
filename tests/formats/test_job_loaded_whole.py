"""Every file a job names is read when the job is loaded, of every format (issue 34): with
the job's folder moved away after ``load_job``, the cut stage refines each cut from the
rulings the job carries and opens no file (an audit hook watches both folders)."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.wirecut.cut.order import check_cut_order
from ruledrobot.wirecut.cut.passes import refine_cut
from ruledrobot.wirecut.job.load import load_job
from tests.support.file_reads import opened_under

from .test_job_paths import SURFACES, _job_in_subfolder, inputs  # noqa: F401 (a fixture)


@pytest.mark.parametrize("kind", list(SURFACES))
def test_the_cut_stage_opens_no_file_of_any_format(tmp_path, inputs, kind):  # noqa: F811
    job_file = _job_in_subfolder(tmp_path, inputs, kind)
    folder = job_file.parent
    job = load_job(job_file)
    ref = [refine_cut(c, job.stock, "job", job.tool.wire_length).frames for c in job.cuts]
    moved = folder.rename(tmp_path / "moved")
    with opened_under(folder) as here, opened_under(moved) as there:
        again = [refine_cut(c, job.stock, "job", job.tool.wire_length).frames for c in job.cuts]
        check_cut_order(job)
        model = job.robot_model()
    assert here == [] and there == []
    assert model.calibration is not None  # the calibration file's data, read at load
    for a, b in zip(ref, again, strict=True):
        np.testing.assert_array_equal(a, b)
