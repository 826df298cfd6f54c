"""Where an input file named in a user's file is: the one rule for every format.

A job file names other files (a lines file, G-code, airfoils, DXF, 3DM, a calibration);
a relative path is taken from the folder of the file that names it, never from the
working folder, and never joined twice (issue 22).  :func:`input_path` is that rule;
the job parser, the format readers' options, batch and the viewer use it.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["FILE_KINDS", "check_not_input", "input_path", "missing_file"]

#: how messages name a file of each kind (``"no such G-code file: ..."``)
FILE_KINDS = {
    "lines": "lines file",
    "gcode": "G-code file",
    "airfoil": "airfoil file",
    "dxf": "DXF file",
    "rhino": "3DM file",
    "calibration": "calibration file",
}


def input_path(named: str | os.PathLike[str], base_dir: str | os.PathLike[str] | None) -> Path:
    """The file ``named`` by a file whose folder is ``base_dir``.

    An absolute path as it is, a relative one from ``base_dir`` (the working folder when None),
    normalised (``a/./b`` and ``a/x/../b`` read ``a/b``; ``~`` is the user's home)."""
    p = Path(named).expanduser()
    if not p.is_absolute() and base_dir is not None:
        p = Path(base_dir) / p
    return Path(os.path.normpath(p))


def missing_file(path: Path, kind: str = "file") -> str | None:
    """Return ``"no such G-code file: PATH"`` when ``path`` is not a file, else None.

    ``kind`` a key of :data:`FILE_KINDS` or a name.
    """
    if path.is_file():
        return None
    what = FILE_KINDS.get(kind, kind)
    if path.is_dir():
        return f"expected a {what}, {path} is a folder"
    return f"no such {what}: {path}"


def check_not_input(output: str | os.PathLike[str], *inputs: str | os.PathLike[str]) -> None:
    """Raise ValueError when ``output`` is one of the ``inputs``.

    The same file by path, or by device and inode through a link: a command never writes
    over the file it reads (``ruledrobot refine wing.json --out wing.json`` would have
    replaced the user's rulings with the refined ones).
    """
    out = Path(os.path.normpath(Path(output).expanduser().absolute()))
    for given in inputs:
        src = Path(os.path.normpath(Path(given).expanduser().absolute()))
        same = out == src
        if not same and out.exists() and src.exists():
            same = os.path.samefile(out, src)
        if same:
            raise ValueError(f"{output}: is the input file {given}; the command would write "
                             "over what it reads: choose another output name")
