"""Fixtures of the simulation tests.

MuJoCo reads ``MUJOCO_GL`` once, at ``import mujoco``; pytest imports every test
module in one process, so the headless backend is chosen here, before any
test module of this folder imports mujoco (EGL: Mesa llvmpipe on a CPU machine).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")

import numpy as np
import pytest

from ruledrobot.robot import load


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def ur5e():
    return load("ur5e")
