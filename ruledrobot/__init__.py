"""ruledrobot: robot motion planning on ruled surfaces.

Quick tour::

    import ruledrobot as rr
    lines = rr.Lines.from_point_direction(points, directions)
    res = rr.refine(lines, algorithm="dh", scheme="four_point", steps=4)
    res.lines, res.frames
    rr.subdivide(poses, scheme="chaikin", steps=3)     # SE(3) geodesic subdivision
"""

from .algorithms import RefineResult, refine
from .geometry import se3, sphere
from .geometry.lines import Lines
from .geometry.ruled import RuledSurface
from .io.lines import load_lines, read_lines_document, save_lines
from .subdivision import SCHEME_NAMES, subdivide

__version__ = "0.1.0"


def __getattr__(name: str):
    """Import the heavier sub-packages on first use (``rr.robot``), keeping ``import`` fast."""
    if name in ("robot", "sim", "export", "wirecut"):
        import importlib

        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'ruledrobot' has no attribute {name!r}")


__all__ = [
    "SCHEME_NAMES",
    "Lines",
    "RefineResult",
    "RuledSurface",
    "__version__",
    "load_lines",
    "read_lines_document",
    "refine",
    "robot",
    "save_lines",
    "se3",
    "sphere",
    "subdivide",
]
