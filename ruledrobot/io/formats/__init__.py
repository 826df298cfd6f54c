"""The file formats of hot-wire cutting and CAD, in and out (``docs/formats.md``).

Readers turn a file into :class:`Rulings` (metres, the file's frame); writers
turn rulings into a file.  Each kind has one module; this registry maps a kind
to its option parser, reader and writer:

===========  ==============================  ======  ======
kind         files                           read    write
===========  ==============================  ======  ======
``lines``    ``.json`` ``.csv``              yes     yes
``gcode``    ``.ngc`` ``.gcode`` ``.nc`` ...  yes     yes
``airfoil``  ``.dat`` (root and tip)         yes     --
``dxf``      ``.dxf``                        yes     yes
``rhino``    ``.3dm``                        yes     yes (and meshes)
===========  ==============================  ======  ======

Options come as a mapping (a job's ``[surface.<kind>]`` table, or command-line
options) and are checked by :class:`~.options.Options`; errors name the file,
the section (or option) and the field.  ezdxf and rhino3dm are imported only
when a DXF or 3DM file is read or written (the ``cad`` extra).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .options import Options
from .rulings import Planes, Rulings

__all__ = ["READ_KINDS", "WRITE_KINDS", "Planes", "ReadSpec", "Rulings", "kind_of",
           "parse_read_spec", "parse_write_options", "read_rulings", "write_rulings"]  # fmt: skip

READ_KINDS = ("lines", "gcode", "airfoil", "dxf", "rhino")
WRITE_KINDS = ("lines", "gcode", "dxf", "rhino")
_SUFFIXES = {
    ".json": "lines", ".csv": "lines",
    ".ngc": "gcode", ".gcode": "gcode", ".nc": "gcode", ".tap": "gcode", ".cnc": "gcode",
    ".gc": "gcode", ".dat": "airfoil", ".dxf": "dxf", ".3dm": "rhino",
}  # fmt: skip


def kind_of(path: str | os.PathLike[str], writing: bool = False) -> str:
    """The kind of a file by its suffix; ValueError naming the known suffixes."""
    p = Path(path)
    kind = _SUFFIXES.get(p.suffix.lower())
    kinds = WRITE_KINDS if writing else READ_KINDS
    if kind not in kinds:
        known = " ".join(s for s, k in _SUFFIXES.items() if k in kinds)
        raise ValueError(f"{p}: unknown file type {p.suffix!r}; expected one of {known} "
                         "(or name the kind)")  # fmt: skip
    return kind


@dataclass(frozen=True)
class ReadSpec:
    """A checked request to read rulings.

    The ``kind``, the ``path`` of the file (an airfoil's root) and the reader's ``options``
    object."""

    kind: str
    path: Path
    options: Any = None


def _lines_options(o: Options) -> None:
    o.done()


def _gcode_options(o: Options):
    from .gcode import GcodeReadOptions

    return GcodeReadOptions.parse(o)


def _dxf_options(o: Options):
    from .dxf import DxfOptions

    return DxfOptions.parse(o)


def _rhino_options(o: Options):
    from .rhino import RhinoOptions

    return RhinoOptions.parse(o)


def _wing_options(o: Options):
    from .wing import WingOptions

    return WingOptions.parse(o)


_READ_OPTIONS: dict[str, Callable[[Options], Any]] = {
    "lines": _lines_options, "gcode": _gcode_options, "airfoil": _wing_options,
    "dxf": _dxf_options, "rhino": _rhino_options,
}  # fmt: skip


def parse_read_spec(kind: str, value: str | os.PathLike[str] | Mapping[str, Any], where: str,
                    base_dir: Path | None = None, cli: bool = False) -> ReadSpec:  # fmt: skip
    """Check a request to read ``kind``.

    ``value`` is the file's path, or a mapping of the reader's options with the path under
    ``file`` (an airfoil: ``root`` and ``tip``). Relative paths are taken from ``base_dir``."""
    if kind not in READ_KINDS:
        raise ValueError(f"{where}: unknown kind {kind!r}; expected one of {', '.join(READ_KINDS)}")
    key = "root" if kind == "airfoil" else "file"
    raw = {key: value} if isinstance(value, (str, os.PathLike)) else value
    o = Options(raw, where, cli=cli, base_dir=base_dir)
    path = o.path(key, kind=kind)
    if kind == "airfoil":
        return ReadSpec(kind, path, _wing_options(o))
    return ReadSpec(kind, path, _READ_OPTIONS[kind](o))


def read_rulings(spec: ReadSpec) -> Rulings:
    """Read the rulings a :class:`ReadSpec` asks for."""
    if spec.kind == "lines":
        from ..lines import read_lines_document

        doc = read_lines_document(spec.path)
        return Rulings(doc.lines, doc.closed, source=str(spec.path))
    if spec.kind == "gcode":
        from .gcode import read_gcode

        return read_gcode(spec.path, spec.options)
    if spec.kind == "airfoil":
        from .wing import read_wing

        return read_wing(spec.options)
    if spec.kind == "dxf":
        from .dxf import read_dxf

        return read_dxf(spec.path, spec.options)
    from .rhino import read_rhino

    return read_rhino(spec.path, spec.options)


def parse_write_options(kind: str, raw: Mapping[str, Any], where: str, cli: bool = False,
                        prefix: str = "") -> Any:  # fmt: skip
    """The checked writer options of ``kind`` (None for lines files, which take none)."""
    o = Options(raw, where, cli=cli, prefix=prefix)
    if kind == "gcode":
        from .gcode_write import GcodeWriteOptions

        return GcodeWriteOptions.parse(o)
    if kind in ("dxf", "rhino"):
        from .cad_common import CadWriteOptions

        return CadWriteOptions.parse(o, surface=kind == "rhino")
    if kind != "lines":
        known = ", ".join(WRITE_KINDS)
        raise ValueError(f"{where}: cannot write {kind!r}; expected one of {known}")
    o.done()
    return None


def write_rulings(path: str | os.PathLike[str], rulings: Rulings, kind: str | None = None,
                  options: Any = None) -> Path:  # fmt: skip
    """Write rulings as ``kind`` (default: by the suffix) with the writer's ``options``.

    ``options`` from :func:`parse_write_options` (None: defaults).  Atomic; returns the
    path.
    """
    kind = kind or kind_of(path, writing=True)
    if kind == "lines":
        from ..lines import save_lines

        return save_lines(path, rulings.lines, closed=rulings.closed)
    if kind == "gcode":
        from .gcode_write import write_gcode

        return write_gcode(path, rulings, options)
    if kind == "dxf":
        from .dxf import write_dxf

        return write_dxf(path, rulings, options)
    if kind == "rhino":
        from .rhino_write import write_rhino

        return write_rhino(path, rulings, options)
    raise ValueError(f"{path}: cannot write {kind!r}; expected one of {', '.join(WRITE_KINDS)}")
