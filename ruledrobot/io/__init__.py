"""File formats at the edges: lines (JSON/CSV), meshes; all writes are atomic."""

from .lines import LinesDocument, load_lines, read_lines_document, save_lines

__all__ = ["LinesDocument", "load_lines", "read_lines_document", "save_lines"]
