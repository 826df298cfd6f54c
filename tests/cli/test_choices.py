"""The CLI's choice lists are the library's names (written out in the CLI so that it
starts without importing numpy; this test keeps the two the same)."""

from __future__ import annotations

from ruledrobot.algorithms import ALGORITHMS
from ruledrobot.cli.robot import RunModeName
from ruledrobot.cli.surfaces import AlgorithmName, SchemeName
from ruledrobot.export.run_result import RunMode
from ruledrobot.subdivision import SCHEME_NAMES


def test_algorithm_choices_are_the_librarys():
    assert [a.value for a in AlgorithmName] == list(ALGORITHMS)


def test_scheme_choices_are_the_librarys():
    assert [s.value for s in SchemeName] == list(SCHEME_NAMES)


def test_run_mode_choices_are_the_runners():
    assert [m.value for m in RunModeName] == [m.value for m in RunMode]
