"""Writing TOML text: the values and tables of the job files the project writes.

A minimal writer (no third-party dependency: tomli-w is an extra of the batch planner)
for the flat tables of a job file — numbers, strings, booleans, lists and inline
tables.  Floats always carry a ``.`` or an exponent (so that TOML reads them back as
floats), rounded to 12 decimals (``-0.0`` as ``0.0``); numpy scalars and arrays are
written as numbers and lists.  Used by carve's jobs, the kerf ladder's and the placement's
job files (a whole parsed document, :func:`toml_document`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["toml_document", "toml_table", "toml_value"]


def toml_value(v: Any) -> str:
    """``v`` as a TOML value (module doc); ValueError for a type TOML cannot hold here."""
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        r = repr(round(float(v), 12) + 0.0)
        return r if "." in r or "e" in r or "inf" in r or "nan" in r else r + ".0"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, np.ndarray):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + " }"
    raise ValueError(f"cannot write {type(v).__name__} to TOML")


def toml_table(name: str, table: dict[str, Any], header: str = "[{}]") -> list[str]:
    """Write a TOML table as lines.

    The lines of the table ``name`` (``header`` ``"[[{}]]"`` for an array entry), one
    ``key = value`` each, and a blank line."""
    return [header.format(name), *(f"{k} = {toml_value(v)}" for k, v in table.items()), ""]


def toml_document(doc: dict[str, Any], prefix: str = "") -> str:
    """Write a whole TOML document (a parsed job file: values, tables, arrays of tables).

    The inverse of ``tomllib.loads`` for such documents: a key's plain values first, then
    its tables (``[prefix.name]``) and arrays of tables (``[[prefix.name]]``), recursively.
    """
    def is_array_of_tables(v: Any) -> bool:
        return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)

    out = [f"{k} = {toml_value(v)}" for k, v in doc.items()
           if not isinstance(v, dict) and not is_array_of_tables(v)]  # fmt: skip
    for k, v in doc.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out += [f"\n[{name}]", toml_document(v, name + ".").rstrip("\n")]
        elif is_array_of_tables(v):
            for entry in v:
                out += [f"\n[[{name}]]", toml_document(entry, name + ".").rstrip("\n")]
    return "\n".join(out) + "\n"
