"""Tests of the controller emulator, with raw clients and the real ur_rtde client.

The fixtures (emulators on distinct loopback addresses, hard time limits, ur_rtde
interfaces) live in :mod:`tests.support.emulators`.
"""

from __future__ import annotations

import pytest

from tests.support.emulators import _deadline, emulator, host, ur  # noqa: F401  (fixtures)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """These tests run real-time servers (500 Hz streams, timed faults) on whatever else
    the machine is doing: a failure is rerun once, and the run says so ("1 rerun")."""
    for item in items:
        if "tests/ursim/" in item.nodeid.replace("\\", "/"):
            item.add_marker(pytest.mark.flaky(reruns=1))
