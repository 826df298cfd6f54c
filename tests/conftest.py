"""Shared test fixtures and data generators."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from ruledrobot.geometry.surfaces import helical_motion  # noqa: F401  (re-exported for tests)

settings.register_profile(
    "ci", max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile("dev", max_examples=100, deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

#: tests that run real-time servers (500 Hz streams, a controller's clock, timed faults):
#: marked ``realtime`` so that ``make test`` runs them apart from the parallel rest, one at
#: a time, where they do not compete with other tests for the two cores
REALTIME_DIRS = ("tests/export/", "tests/ursim/")
REALTIME_TESTS = frozenset({"tests/cli/test_cli.py::test_run_streams_to_the_embedded_emulator"})


#: test modules that take long (whole plans, carving, MuJoCo rendering, clusters): marked
#: ``slow``, left out of ``make test-fast`` (measured with ``pytest --durations``)
SLOW_MODULES: frozenset[str] = frozenset({
    "tests/batch/test_cli.py", "tests/batch/test_cluster.py", "tests/batch/test_place_dask.py",
    "tests/carve/test_cad_meshes.py", "tests/carve/test_carved_exact.py",
    "tests/carve/test_demo_carve.py", "tests/carve/test_developables.py",
    "tests/carve/test_exact.py", "tests/carve/test_rough_and_input.py",
    "tests/carve/test_tessellation.py", "tests/cli/test_cli.py", "tests/formats/test_cad.py",
    "tests/gallery/test_gallery.py", "tests/make/test_make_column.py",
    "tests/make/test_make_input.py", "tests/make/test_make_parts.py",
    "tests/place/test_place.py", "tests/place/test_setups.py", "tests/sim/test_playback.py",
    "tests/sim/test_render.py", "tests/view/test_browser.py", "tests/view/test_video.py",
    "tests/wirecut/test_calibrated_plan.py", "tests/wirecut/test_killed_plan.py",
    "tests/wirecut/test_once_plan.py", "tests/wirecut/test_parts.py",
    "tests/wirecut/test_planner.py", "tests/wirecut/test_robot_base.py",
})  # fmt: skip


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "realtime: runs real-time servers; make test runs these after the others, "
        "not in parallel (tests/conftest.py)")  # fmt: skip
    config.addinivalue_line(
        "markers", "slow: a long test, left out of make test-fast (tests/conftest.py)")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the real-time tests (:data:`REALTIME_DIRS`, :data:`REALTIME_TESTS`)."""
    for item in items:
        nodeid = item.nodeid.replace("\\", "/")
        if nodeid.startswith(REALTIME_DIRS) or nodeid.split("[")[0] in REALTIME_TESTS:
            item.add_marker(pytest.mark.realtime)
        if nodeid.split("::")[0] in SLOW_MODULES:
            item.add_marker(pytest.mark.slow)


def random_rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    """Uniform random rotation matrices (n, 3, 3)."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
            2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
            2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
        ],
        axis=-1,
    ).reshape(n, 3, 3)  # fmt: skip


def random_poses(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    """Random rigid motions (n, 4, 4)."""
    T = np.zeros((n, 4, 4))
    T[:, :3, :3] = random_rotations(rng, n)
    T[:, :3, 3] = scale * rng.normal(size=(n, 3))
    T[:, 3, 3] = 1.0
    return T


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)
