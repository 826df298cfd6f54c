"""3-D pictures shown undistorted: matplotlib 3-D axes set to a cube of equal aspect.

The carved block (``carve.png``, millimetres) and the gallery's examples (metres) are
drawn this way.  Nothing here imports matplotlib: the caller has made the axes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["cube_axes"]


def cube_axes(ax: Any, centre: ArrayLike, half: float, unit: str) -> None:
    """Show the cube ``centre +- half`` on the 3-D axes ``ax``, equal aspect, axes labelled.

    Parameters
    ----------
    ax : mpl_toolkits.mplot3d.axes3d.Axes3D
        The axes; their limits, box aspect and axis labels are set.
    centre : array-like, shape (3,)
        Centre of the cube in the axes' data frame and unit (the picture's).
    half : float
        Half the cube's edge, in the same unit.
    unit : str
        The unit as the labels give it after the axis name: ``"(m)"`` labels
        ``x (m)``, ``"mm"`` labels ``x mm``.
    """
    x, y, z = np.asarray(centre, dtype=np.float64)
    ax.set_xlim(x - half, x + half)
    ax.set_ylim(y - half, y + half)
    ax.set_zlim(z - half, z + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
    ax.set_xlabel(f"x {unit}")
    ax.set_ylabel(f"y {unit}")
    ax.set_zlabel(f"z {unit}")
