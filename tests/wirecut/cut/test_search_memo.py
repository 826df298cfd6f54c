"""The wire-pose search's memo (``wirecut/cut/search_memo.py``): the same inputs, one
search; any change of any input's content, another."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ruledrobot.wirecut.cut import search_memo, wire_pose
from ruledrobot.wirecut.cut.passes import job_search, refine_cut
from ruledrobot.wirecut.cut.search_memo import value_digest
from ruledrobot.wirecut.job.demo import DEMO_JOB
from ruledrobot.wirecut.job.load import job_document, parse_job


@dataclasses.dataclass(frozen=True)
class _Inner:
    a: np.ndarray
    x: float


@dataclasses.dataclass(frozen=True)
class _Outer:
    inner: _Inner
    name: str
    q: tuple | None


def _value(rng: np.random.Generator) -> _Outer:
    return _Outer(_Inner(rng.normal(size=(3, 4)), float(rng.normal())), "cell", (1.0, None))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), which=st.sampled_from(["a", "x", "name", "q", "shape",
                                                          "dtype"]))  # fmt: skip
def test_equal_content_one_digest_any_change_another(seed, which):
    rng = np.random.default_rng(seed)
    v = _value(rng)
    copy = _Outer(_Inner(v.inner.a.copy(), v.inner.x), str(v.name), tuple(v.q))
    assert value_digest(v) == value_digest(copy)  # content, not identity
    a = v.inner.a.copy()
    changed = {
        "a": lambda: _Outer(_Inner(np.where(np.arange(12).reshape(3, 4) == 5,
                                            np.nextafter(a, np.inf), a), v.inner.x),
                            v.name, v.q),  # one element, one ulp
        "x": lambda: _Outer(_Inner(a, np.nextafter(v.inner.x, np.inf)), v.name, v.q),
        "name": lambda: dataclasses.replace(v, name="cell "),
        "q": lambda: dataclasses.replace(v, q=(1.0,)),
        "shape": lambda: _Outer(_Inner(a.reshape(4, 3), v.inner.x), v.name, v.q),
        "dtype": lambda: _Outer(_Inner(a.view(np.int64), v.inner.x), v.name, v.q),  # same bytes
    }[which]()
    assert value_digest(changed) != value_digest(v)


def test_an_object_without_readable_content_is_refused_and_not_memoized():
    with pytest.raises(TypeError, match="cannot read a object"):
        value_digest(object())
    calls = []
    for _ in range(2):
        search_memo.memoized(lambda: calls.append(1), object())
    assert len(calls) == 2


def test_the_demo_search_is_computed_once_and_its_result_is_shared_read_only(monkeypatch):
    job = parse_job(job_document(DEMO_JOB, "demo.toml"), "demo.toml")
    model = job.robot_model()
    options = job_search(job, None)
    cell = options.cell(model, job.tool, job.stock)
    F = refine_cut(job.cut, job.stock, "demo", job.tool.wire_length, None).frames
    calls = []
    real = wire_pose._search
    monkeypatch.setattr(wire_pose, "_search", lambda *a: calls.append(1) or real(*a))
    monkeypatch.setattr(search_memo, "_memo", type(search_memo._memo)())
    first = wire_pose.search_wire_pose(F, job.tool, cell, options)
    again = wire_pose.search_wire_pose(F.copy(), job.tool, cell, options)
    assert again is first and len(calls) == 1
    with pytest.raises(ValueError, match="read-only"):
        first.q[0, 0] = 0.0
    # another input, another search: the options, one roll more
    other = wire_pose.search_wire_pose(F, job.tool, cell,
                                       dataclasses.replace(options, rolls=options.rolls + 1))
    assert other is not first and len(calls) == 2
