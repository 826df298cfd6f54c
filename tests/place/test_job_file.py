"""Job files with the block moved (place.job_file): the demo's one-cut file edited in place
(every comment and every other line kept, the moved values read back), the robot's base
written, a file the editor cannot edit written whole, the TOML writer read back by
tomllib."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.geometry import se3
from ruledrobot.io.toml_text import toml_document
from ruledrobot.place.job_file import _rebase_paths, write_job_file
from ruledrobot.place.regions import moved_job
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import load_job

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

EDITED = ("centre", "rotvec", "pose", "base")


def _turn(yaw: float, x: float, y: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = se3.pose_from_rotvec([0.0, 0.0, yaw])[:3, :3]
    T[:3, 3] = [x, y, 0.0]
    return T


def _key(line: str) -> str:
    return line.split("=")[0].strip() if "=" in line.split("#")[0] else ""


def test_the_demo_file_is_edited_in_place(tmp_path):
    src = tmp_path / "demo.toml"
    src.write_text(DEMO_JOB)
    job = load_job(src)
    T = _turn(0.7, 0.1, -0.2)
    moved = moved_job(job, T)
    out = write_job_file(moved, tmp_path / "moved.toml", note="moved by place\nsecond line")
    text = out.read_text()
    assert text.startswith("# moved by place\n# second line\n# ruledrobot demo job")
    old, new = DEMO_JOB.splitlines(), text.splitlines()[2:]
    assert len(new) == len(old)
    changed = [(a, b) for a, b in zip(old, new, strict=True) if a != b]
    assert {_key(a) for a, _ in changed} <= set(EDITED)
    assert {_key(a) for a, _ in changed} >= {"centre", "rotvec", "pose"}
    for a, b in changed:
        assert _key(a) == _key(b)
        if "#" in a:  # a comment after the value stays
            assert b.endswith("#" + a.split("#", 1)[1])
    back = load_job(out)
    np.testing.assert_allclose(back.stock.centre, T[:3, :3] @ job.stock.centre + T[:3, 3],
                               atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(back.stock.rotation, T[:3, :3] @ job.stock.rotation, atol=1e-9)
    np.testing.assert_allclose(back.cuts[0].surface.pose, T @ job.cuts[0].surface.pose,
                               atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(back.robot.base, np.eye(4), atol=1e-12)
    assert back.cuts[0].feed_speed == job.cuts[0].feed_speed
    np.testing.assert_array_equal(back.stock.size, job.stock.size)


def test_a_moved_robot_base_is_written(tmp_path):
    src = tmp_path / "demo.toml"
    src.write_text(DEMO_JOB)
    job = load_job(src)
    base = _turn(-0.3, 0.2, 0.05)
    robot = dataclasses.replace(job.robot, base=base)
    out = write_job_file(dataclasses.replace(job, robot=robot), tmp_path / "based.toml")
    np.testing.assert_allclose(load_job(out).robot.base, base, atol=1e-9)
    # and added to a file that has no [robot] base line
    src.write_text(DEMO_JOB.replace("base = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]\n", ""))
    job = load_job(src)
    out = write_job_file(dataclasses.replace(job, robot=dataclasses.replace(job.robot,
                                                                             base=base)),
                         tmp_path / "added.toml")  # fmt: skip
    np.testing.assert_allclose(load_job(out).robot.base, base, atol=1e-9)
    assert "# Copy this file" in out.read_text()


def test_a_file_the_editor_cannot_edit_is_written_whole(tmp_path):
    # the stock as an inline table: no [stock] header to edit
    text = DEMO_JOB.replace(
        "[stock]                    # the foam block\ncentre = [0.5, 0.0, 0.3]\n"
        "size = [0.2, 0.2, 0.15]\nrotvec = [0.0, 0.0, 0.0]\n",
        "",
    ).replace("[surface]\n", "stock = { centre = [0.5, 0.0, 0.3], size = [0.2, 0.2, 0.15] }\n"
              "\n[surface]\n")  # fmt: skip
    src = tmp_path / "inline.toml"
    src.write_text(text)
    job = load_job(src)
    T = _turn(0.2, -0.05, 0.1)
    out = write_job_file(moved_job(job, T), tmp_path / "whole.toml", note="placed")
    written = out.read_text()
    assert written.startswith("# placed\n# (written whole from the parsed job: the original's "
                              "comments are not kept)\n")  # fmt: skip
    back = load_job(out)
    np.testing.assert_allclose(back.stock.centre, T[:3, :3] @ job.stock.centre + T[:3, 3],
                               atol=1e-9)  # fmt: skip
    np.testing.assert_allclose(back.cuts[0].surface.pose, T @ job.cuts[0].surface.pose,
                               atol=1e-9)  # fmt: skip


def test_a_job_without_a_file_is_refused(tmp_path):
    src = tmp_path / "demo.toml"
    src.write_text(DEMO_JOB)
    job = dataclasses.replace(load_job(src), source=None)
    with pytest.raises(ValueError, match="write_job_file: the job has no source file to edit"):
        write_job_file(job, tmp_path / "x.toml")


def test_paths_are_written_for_where_the_file_will_live(tmp_path):
    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "r.json").write_text("{}")
    src = tmp_path / "job.toml"
    src.write_text(DEMO_JOB.replace('builtin = "hyperbolic_paraboloid"\nparams = { c = 0.4 }\n'
                                    "u = [-0.12, 0.12]          # rulings at x = u (m) in the "
                                    "surface frame\n", 'file = "data/r.json"\n'))  # fmt: skip
    text = _rebase_paths(src.read_text(), src, tmp_path / "a" / "b" / "moved.toml")
    assert 'file = "../../data/r.json"' in text
    text = _rebase_paths('file = "missing.json"\ncalibration = "/abs/c.json"\n', src,
                         tmp_path / "a" / "x.toml")  # fmt: skip
    assert text == 'file = "missing.json"\ncalibration = "/abs/c.json"\n'  # left as they are


_keys = st.from_regex(r"[a-z_][a-z0-9_]{0,6}", fullmatch=True)
_scalars = st.one_of(
    st.booleans(),
    st.integers(-(2**40), 2**40),
    st.floats(-1e6, 1e6).map(lambda v: round(v, 9)),
    st.text(st.characters(blacklist_categories=("Cc", "Cs")), max_size=12),
)
_values = st.one_of(_scalars, st.lists(st.floats(-10, 10).map(lambda v: round(v, 9)),
                                       max_size=6))  # fmt: skip
_tables = st.dictionaries(_keys, _values, max_size=4)
_docs = st.dictionaries(
    _keys,
    st.one_of(_values, _tables, st.lists(_tables.filter(bool), min_size=1, max_size=3),
              st.dictionaries(_keys, st.one_of(_values, _tables), max_size=3)),
    max_size=5,
)  # fmt: skip


@settings(max_examples=150, deadline=None)
@given(_docs)
def test_the_toml_writer_reads_back(doc):
    assert tomllib.loads(toml_document(doc)) == doc
