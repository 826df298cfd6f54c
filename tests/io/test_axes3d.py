"""The undistorted 3-D view (ruledrobot.io.axes3d): a cube about the centre, equal
aspect, the axes labelled with the unit."""

from __future__ import annotations

import numpy as np
import pytest

from ruledrobot.io.axes3d import cube_axes


def test_the_axes_show_the_cube_about_the_centre():
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    ax = Figure().add_subplot(projection="3d")
    cube_axes(ax, np.array([0.1, -0.2, 0.3]), 0.5, "(m)")
    np.testing.assert_allclose(ax.get_xlim(), (-0.4, 0.6))
    np.testing.assert_allclose(ax.get_ylim(), (-0.7, 0.3))
    np.testing.assert_allclose(ax.get_zlim(), (-0.2, 0.8))
    aspect = ax.get_box_aspect()
    np.testing.assert_allclose(aspect, aspect[0])
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("x (m)", "y (m)", "z (m)")
