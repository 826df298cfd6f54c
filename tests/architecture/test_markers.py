"""The lists that mark tests ``slow`` and ``realtime`` (tests/conftest.py) name tests that
exist: a renamed or moved test would otherwise drop out of a list silently (and a slow
one land in ``make test-fast``)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.conftest import REALTIME_DIRS, REALTIME_TESTS, SLOW_MODULES, SLOW_TESTS

ROOT = Path(__file__).parents[2]


def test_every_listed_module_and_test_exists():
    missing = [m for m in (*SLOW_MODULES, *REALTIME_DIRS) if not (ROOT / m).exists()]
    for nodeid in (*SLOW_TESTS, *REALTIME_TESTS):
        module, name = nodeid.split("::")
        path = ROOT / module
        if not path.is_file() or not re.search(rf"^def {name}\(", path.read_text(), re.M):
            missing.append(nodeid)
    assert not missing, missing
    assert not {t.split("::")[0] for t in SLOW_TESTS} & SLOW_MODULES  # listed once
