"""``ruledrobot convert``: one file of rulings (or a mesh) into another format.

The logic of the command, free of the command line: the input's kind comes from
its suffix (or ``src_kind``), so does the output's; the reader and writer
options are checked mappings (:mod:`.options`).  A triangle mesh (``.stl``,
``.obj``) converts to a 3DM model.  Nothing is written unless everything was
read and checked; writes are atomic.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..paths import check_not_input
from . import (
    READ_KINDS,
    WRITE_KINDS,
    kind_of,
    parse_read_spec,
    parse_write_options,
    read_rulings,  # fmt: skip
    write_rulings,
)
from .options import Options
from .rulings import Rulings

__all__ = ["Conversion", "convert"]

MESH_SUFFIXES = (".stl", ".obj")


@dataclass(frozen=True)
class Conversion:
    """What :func:`convert` did.

    The files, their kinds, the number of rulings (mesh: triangles), whether closed, and the
    reader's notes."""

    source: Path
    target: Path
    source_kind: str
    target_kind: str
    count: int
    closed: bool = False
    notes: tuple[str, ...] = ()
    rulings: Rulings | None = None


def convert(source: str | os.PathLike[str], target: str | os.PathLike[str], *,
            source_kind: str | None = None, target_kind: str | None = None,
            read_options: Mapping[str, Any] | None = None,
            write_options: Mapping[str, Any] | None = None, cli: bool = False,
            ) -> Conversion:  # fmt: skip
    """Read ``source`` and write ``target`` (see the module doc).

    ``cli=True`` names options as command-line options in errors (writer options with
    ``--out-``)."""
    src, dst = Path(source), Path(target)
    tip = (read_options or {}).get("tip")
    check_not_input(dst, src, *([] if tip is None else [tip]))
    read_options = dict(read_options or {})
    write_options = dict(write_options or {})
    if target_kind is not None and target_kind not in WRITE_KINDS:
        raise ValueError(f"{dst}: cannot write {target_kind!r}; expected one of "
                         f"{', '.join(WRITE_KINDS)}")  # fmt: skip
    if source_kind is None and src.suffix.lower() in MESH_SUFFIXES:
        return _convert_mesh(src, dst, target_kind, read_options, write_options, cli)
    if source_kind is not None and source_kind not in READ_KINDS:
        raise ValueError(f"{src}: unknown kind {source_kind!r}; expected one of "
                         f"{', '.join(READ_KINDS)}")  # fmt: skip
    kind_in = source_kind or kind_of(src)
    kind_out = target_kind or kind_of(dst, writing=True)
    key = "root" if kind_in == "airfoil" else "file"
    spec = parse_read_spec(kind_in, {key: str(src), **read_options}, f"{src} ({kind_in})",
                           cli=cli)  # fmt: skip
    wopts = parse_write_options(kind_out, write_options, f"{dst} ({kind_out} output)", cli=cli,
                                prefix="out_" if cli else "")  # fmt: skip
    rulings = read_rulings(spec)
    path = write_rulings(dst, rulings, kind_out, wopts)
    return Conversion(src, path, kind_in, kind_out, len(rulings), rulings.closed, rulings.notes,
                      rulings)  # fmt: skip


def _convert_mesh(src: Path, dst: Path, target_kind: str | None, read_options: Mapping,
                  write_options: Mapping, cli: bool) -> Conversion:  # fmt: skip
    from ..mesh import read_obj, read_stl
    from .rhino_write import write_mesh_3dm

    kind_out = target_kind or kind_of(dst, writing=True)
    if kind_out != "rhino":
        raise ValueError(f"{src}: a mesh converts to a Rhino model (.3dm) only, not {kind_out}")
    Options(read_options, f"{src} (mesh)", cli=cli).done()
    o = Options(write_options, f"{dst} (rhino output)", cli=cli, prefix="out_" if cli else "")
    units = o.unit("units", "mm")
    o.done()
    try:
        mesh = read_stl(src) if src.suffix.lower() == ".stl" else read_obj(src)
    except FileNotFoundError:
        raise ValueError(f"{src}: no such mesh file") from None
    vertices, faces = mesh[0], mesh[1]
    path = write_mesh_3dm(dst, vertices, faces, units)
    return Conversion(src, path, "mesh", "rhino", len(faces))
