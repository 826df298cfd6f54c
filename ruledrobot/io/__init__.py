"""File formats at the edges: lines (JSON/CSV), meshes, trajectories, calibrations;
all writes are atomic."""

from .calibration import load_calibration, save_calibration
from .lines import LinesDocument, load_lines, read_lines_document, save_lines

__all__ = [
    "LinesDocument",
    "load_calibration",
    "load_lines",
    "read_lines_document",
    "save_calibration",
    "save_lines",
]
