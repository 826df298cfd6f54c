"""Shared test fixtures and data generators."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from ruledrobot.geometry.surfaces import helical_motion  # noqa: F401  (re-exported for tests)

#: CI (``CI`` set) runs the same examples every time (``derandomize``): a submission is
#: judged on its code, not on the draw; the random search runs where people work (the
#: "dev" profile), and what it finds is kept in the example database and fixed
settings.register_profile(
    "ci", max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow],
    derandomize=True,
)
settings.register_profile("dev", max_examples=100, deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

#: tests that run real-time servers (500 Hz streams, a controller's clock, timed faults):
#: marked ``realtime`` so that ``make test`` runs them apart from the parallel rest, where
#: they do not compete with CPU-bound tests for the two cores (in three groups of modules:
#: mostly waiting for the controller's clock, they leave each other room)
REALTIME_DIRS = ("tests/export/", "tests/ursim/")
REALTIME_TESTS = frozenset({"tests/cli/test_cli.py::test_run_streams_to_the_embedded_emulator"})


#: test modules that take long (whole plans, carving, MuJoCo rendering, clusters): marked
#: ``slow``, left out of ``make test-fast`` (measured with ``pytest --durations``)
SLOW_MODULES: frozenset[str] = frozenset({
    "tests/batch/test_cli.py", "tests/batch/test_cluster.py", "tests/batch/test_place_dask.py",
    "tests/carve/test_cad_meshes.py", "tests/carve/test_carved_exact.py",
    "tests/carve/test_demo_carve.py", "tests/carve/test_developables.py",
    "tests/carve/test_exact.py", "tests/carve/test_rough_and_input.py",
    "tests/carve/test_samples_made.py",
    "tests/carve/test_tessellation.py", "tests/cli/test_cli.py", "tests/formats/test_cad.py",
    "tests/gallery/test_gallery.py", "tests/make/test_make_column.py",
    "tests/make/test_make_input.py", "tests/make/test_make_parts.py",
    "tests/place/test_place.py", "tests/place/test_setups.py", "tests/sim/test_playback.py",
    "tests/sim/test_render.py", "tests/view/test_browser.py", "tests/view/test_video.py",
    "tests/wirecut/test_calibrated_plan.py", "tests/wirecut/test_killed_plan.py",
    "tests/wirecut/test_once_plan.py", "tests/wirecut/test_parts.py",
    "tests/wirecut/test_planner.py", "tests/wirecut/test_robot_base.py",
    "tests/formats/test_formats_matrix.py", "tests/wirecut/motion/test_one_truth.py",
    "tests/wirecut/reach/test_map.py", "tests/wirecut/reach/test_reach_agree.py",
})  # fmt: skip

#: single tests (parameters left out) that take 5 s or more on a busy 2-core machine (about
#: 1.5 s quiet; ``pytest -n 2 -m "not realtime" --durations=80``, issue 34), in modules
#: that are fast otherwise: marked ``slow`` too, so that ``make test-fast`` stays under 90 s
SLOW_TESTS: frozenset[str] = frozenset({
    "tests/architecture/test_doc_references.py::test_every_reference_resolves",
    "tests/architecture/test_layers.py::test_every_layer_imports_only_downward",
    "tests/carve/test_part_mesh_fins.py::test_a_seam_loop_keeps_what_its_planes_keep_not_its_fins",
    "tests/cli/test_field_smaller.py::test_the_demo_names_the_job_file_it_leaves",
    "tests/cli/test_field_smaller.py::test_video_on_a_failing_plan_says_why_there_is_none",
    "tests/formats/test_gcode_corners.py::"
    "test_a_profile_with_sharp_corners_plans_and_the_wire_stops_at_them",
    "tests/formats/test_job_cli.py::test_a_foam_cutter_file_plans_and_verifies_as_a_ur_job",
    "tests/formats/test_job_paths.py::test_plan_from_the_parent_folder_with_a_gcode_table",
    "tests/geometry/test_se3.py::test_geodesic_matches_expm_logm",
    "tests/geometry/test_se3_kernel.py::test_kernel_is_the_numpy_path_property",
    "tests/geometry/test_se3_kernel.py::test_small_geodesics_do_not_load_numba",
    "tests/place/test_job_file.py::test_the_toml_writer_reads_back",
    "tests/robot/test_calibrated_kernel.py::test_lanes_any_batch_size",
    "tests/robot/test_wire_in_stock.py::test_model_equals_an_independent_measure",
    "tests/view/test_cli_and_layers.py::"
    "test_view_imports_point_down_and_only_the_cli_and_make_import_view",
    "tests/wirecut/cut/test_span.py::test_the_demo_and_part_jobs_still_plan",
    "tests/wirecut/cut/test_wire_pose.py::test_impossible_jobs_are_reported",
    "tests/wirecut/cut/test_wire_pose.py::test_varying_roll_by_dynamic_programming",
    "tests/wirecut/motion/test_polyline_corners.py::test_a_polyline_of_any_format_plans_like_the_gcode",
    "tests/wirecut/motion/test_timing.py::test_limits_hold_on_the_sampled_output",
    "tests/wirecut/motion/test_transit_ompl.py::"
    "test_a_transit_between_cuts_on_opposite_sides_is_found_and_clear_in_mujoco",
    "tests/wirecut/report/test_files.py::test_a_passing_plan_writes_its_trajectory_and_files",
    "tests/wirecut/report/test_outcome.py::test_a_job_out_of_reach_says_why_and_where_to_move",
    "tests/wirecut/report/test_part_mesh.py::"
    "test_part_stl_is_one_closed_two_manifold_of_the_right_volume",
    "tests/wirecut/report/test_user_files.py::test_replanning_keeps_recordings_and_every_users_file",
    "tests/wirecut/report/test_verdict.py::test_a_colliding_cut_fails_with_collisions_in_words",
    "tests/wirecut/test_once_clearance.py::test_moves_checked_in_a_batch_are_each_move_checked_alone",
    "tests/wirecut/test_search_options.py::test_the_options_reach_the_passes_of_an_open_and_a_closed_cut",
})  # fmt: skip


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "realtime: runs real-time servers; make test runs these after the others, "
        "not in parallel (tests/conftest.py)")  # fmt: skip
    config.addinivalue_line(
        "markers", "slow: a long test, left out of make test-fast (tests/conftest.py)")


def _rel(path: Path, config: pytest.Config) -> str:
    """``path`` relative to the rootdir, with forward slashes (as in node ids)."""
    try:
        return path.relative_to(config.rootpath).as_posix()
    except ValueError:
        return path.as_posix()


def pytest_ignore_collect(collection_path: Path, config: pytest.Config) -> bool | None:
    """Skip importing the modules a run deselects whole: ``-m realtime`` everything but
    :data:`REALTIME_DIRS` and the modules of :data:`REALTIME_TESTS`; ``-m "not realtime
    ..."`` :data:`REALTIME_DIRS` (every test there is real-time); ``-m "... and not slow"``
    :data:`SLOW_MODULES`.  The same tests run, without rewriting and importing modules for
    nothing (collection took 10-25 s a process; ``make test``, ``make test-fast``)."""
    which = config.getoption("markexpr", "").strip()
    rel = _rel(collection_path, config) + ("/" if collection_path.is_dir() else "")
    if which == "realtime":
        files = {t.split("::")[0] for t in REALTIME_TESTS}
        wanted = rel.startswith(REALTIME_DIRS) or rel in files
        return None if wanted or any(d.startswith(rel) for d in (*REALTIME_DIRS, *files)) else True
    conjuncts = {c.strip() for c in which.split(" and ")}
    if "not realtime" in conjuncts and rel.startswith(REALTIME_DIRS):
        return True
    if "not slow" in conjuncts and rel in SLOW_MODULES:
        return True
    return None


#: the modules that take longest (worker seconds, ``--durations``, 6 Dec 2026), longest
#: first: ``make test`` hands whole modules to its workers in collection order
#: (``--no-loadscope-reorder``; xdist's default order, by number of tests, handed the
#: one-test modules of 20-35 s out last, and one worker ran them alone at the end)
LONGEST_FIRST: tuple[str, ...] = (
    # not real-time
    "tests/place/test_place.py", "tests/view/test_browser.py",
    "tests/carve/test_developables.py", "tests/carve/test_samples_made.py",
    "tests/carve/test_carved_exact.py", "tests/wirecut/reach/test_reach_agree.py",
    "tests/batch/test_cli.py", "tests/formats/test_formats_matrix.py",
    "tests/batch/test_cluster.py", "tests/carve/test_demo_carve.py",
    "tests/batch/test_place_dask.py", "tests/wirecut/test_killed_plan.py",
    "tests/make/test_make_column.py", "tests/wirecut/motion/test_polyline_corners.py",
    "tests/wirecut/test_parts.py", "tests/carve/test_tessellation.py",
    "tests/carve/test_rough_and_input.py", "tests/carve/test_exact.py",
    "tests/carve/test_cad_meshes.py", "tests/wirecut/motion/test_transit_ompl.py",
    # real-time
    "tests/export/test_path_programs.py", "tests/export/test_forward.py",
    "tests/export/test_run_part.py", "tests/export/test_run_calibrated.py",
    "tests/ursim/test_emulator_abuse.py", "tests/export/test_run_path.py",
    "tests/export/test_runner.py", "tests/ursim/test_emulator_primary.py",
    "tests/export/test_heat_corner_forward.py", "tests/ursim/test_client.py",
)  # fmt: skip


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the real-time tests (:data:`REALTIME_DIRS`, :data:`REALTIME_TESTS`) and the slow
    ones (:data:`SLOW_MODULES`, :data:`SLOW_TESTS`); put the modules of
    :data:`LONGEST_FIRST` first, in its order (each module's tests stay together and in
    their order)."""
    for item in items:
        nodeid = item.nodeid.replace("\\", "/")
        if nodeid.startswith(REALTIME_DIRS) or nodeid.split("[")[0] in REALTIME_TESTS:
            item.add_marker(pytest.mark.realtime)
        if nodeid.split("::")[0] in SLOW_MODULES or nodeid.split("[")[0] in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
    rank = {m: k for k, m in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda it: rank.get(it.nodeid.replace("\\", "/").split("::")[0], len(rank)))


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
