"""Typed reading of a format's options, with errors that name where they came from.

The same options come from a job file (``[surface.gcode] tower_distance = 0.8``)
or from the command line (``--tower-distance 0.8``); :class:`Options` checks each
one and names it the way the user wrote it.  Lengths are metres, angles radians.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..fields import FieldReader
from ..paths import input_path, missing_file
from ..units import unit_name

__all__ = ["Options"]


class Options(FieldReader):
    """Checked access to a mapping of options.

    ``where`` prefixes every message (``"job.toml: [surface.gcode]"``); ``cli=True``
    names fields as options (``--tower-distance``, ``--out-units`` with ``prefix="out_"``)
    instead of keys.  Call :meth:`done`
    last: unknown keys are refused with the list of known ones.
    """

    def __init__(self, raw: Mapping[str, Any], where: str, cli: bool = False,
                 base_dir: Path | None = None, prefix: str = "") -> None:  # fmt: skip
        if not isinstance(raw, Mapping):
            raise ValueError(f"{where}: expected a table of options, got {raw!r}")
        self.raw = dict(raw)
        self.where = where
        self.cli = cli
        self.base_dir = base_dir
        self.prefix = prefix
        self.used: set[str] = set()

    def name(self, key: str) -> str:
        """The user's name of field ``key``: the key itself, or ``--prefix-key`` when ``cli``."""
        return "--" + (self.prefix + key).replace("_", "-") if self.cli else key

    def label(self, key: str) -> str:
        """Where a field is.

        ``"a.ngc (gcode): --tower-distance"``, ``"job.toml: [surface.gcode] tower_distance"``."""
        sep = ": " if self.cli else " "
        return f"{self.where}{sep}{self.name(key)}"

    def fail(self, key: str, msg: str) -> ValueError:
        """The ValueError for field ``key``, ``msg`` prefixed by :meth:`label`."""
        return ValueError(f"{self.label(key)}: {msg}")

    def has(self, key: str) -> bool:
        """Whether ``key`` is given with a value (not absent, not None); does not mark it used."""
        return self.raw.get(key) is not None

    def get(self, key: str, default: Any = None) -> Any:
        """The raw value of ``key`` (``default`` when absent or None), marked as used."""
        self.used.add(key)
        value = self.raw.get(key)
        return default if value is None else value

    def number(self, key: str, default: float | None = None, *, lo: float | None = None,
               hi: float | None = None, positive: bool = False, nonzero: bool = False,
               required: str = "") -> float | None:  # fmt: skip
        """Return option ``key`` as a finite number.

        ``None`` when absent and ``default`` is None and not ``required``; ``required`` is
        the hint given when it is missing.
        """
        v = self.get(key, default)
        if v is None:
            if required:
                raise self.fail(key, f"missing; {required}")
            return None
        self.finite(key, v)
        if positive and v <= 0:
            raise self.fail(key, f"expected a number > 0, got {v!r}")
        if nonzero and v == 0:
            raise self.fail(key, "expected a non-zero number")
        if lo is not None and v < lo:
            raise self.fail(key, f"expected a number >= {lo:g}, got {v!r}")
        if hi is not None and v > hi:
            raise self.fail(key, f"expected a number <= {hi:g}, got {v!r}")
        return float(v)

    def integer(self, key: str, default: int | None = None, *, lo: int | None = None,
                hi: int | None = None) -> int | None:  # fmt: skip
        """Return option ``key`` as an integer, ``lo <= v <= hi`` when those are given.

        ``None`` when absent and ``default`` is None; booleans and floats are refused.
        """
        v = self.get(key, default)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.fail(key, f"expected an integer, got {v!r}")
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            rng = f"{lo if lo is not None else '-inf'} <= {self.name(key)} <= " \
                  f"{hi if hi is not None else 'inf'}"  # fmt: skip
            raise self.fail(key, f"expected an integer {rng}, got {v!r}")
        return int(v)

    def choice(self, key: str, options: tuple[str, ...], default: str | None) -> str | None:
        """Return option ``key`` as one of ``options``, lower-cased.

        The value is matched case-insensitively; ``None`` when absent and ``default`` is
        None.
        """
        v = self.get(key, default)
        if v is None:
            return None
        if not isinstance(v, str) or v.lower() not in options:
            raise self.fail(key, f"expected one of {', '.join(options)}, got {v!r}")
        return v.lower()

    def string(self, key: str, default: str | None = None) -> str | None:
        """A string (``None`` when absent and ``default`` is None)."""
        v = self.get(key, default)
        if v is not None and not isinstance(v, str):
            raise self.fail(key, f"expected a string, got {v!r}")
        return v

    def strings(self, key: str, n: int | None = None) -> tuple[str, ...] | None:
        """A list of strings (one string counts as a list of one)."""
        v = self.get(key)
        if v is None:
            return None
        if isinstance(v, str):
            v = [v]
        if not isinstance(v, (list, tuple)) or not all(isinstance(x, str) for x in v) or (
            n is not None and len(v) != n
        ):
            count = f"{n} " if n is not None else ""
            raise self.fail(key, f"expected a list of {count}strings, got {v!r}")
        return tuple(v)

    def vector(self, key: str, n: int) -> np.ndarray | None:
        """A list of ``n`` finite numbers as an ndarray, shape (n,) (``None`` when absent)."""
        v = self.get(key)
        return None if v is None else self.numbers(key, v, n)

    def unit(self, key: str, default: str | None = None) -> str | None:
        """Return a length unit's canonical name (``m``, ``cm``, ``mm``, ``in``).

        See :func:`ruledrobot.io.units.unit_name`; ``None`` when absent and ``default`` is
        None.
        """
        v = self.get(key, default)
        if v is None:
            return None
        return unit_name(v, self.label(key))

    def path(self, key: str, required: bool = True, kind: str = "file") -> Path | None:
        """Return a file that exists (relative paths from ``base_dir``).

        Resolved by :func:`ruledrobot.io.paths.input_path`; ``kind`` names it in the message
        when it is missing (``"lines"``, ``"gcode"``, ...: ``"no such G-code file: PATH"``).
        """
        v = self.get(key)
        if v is None:
            if required:
                raise self.fail(key, "missing; expected the path of a file")
            return None
        if not isinstance(v, (str, os.PathLike)):
            raise self.fail(key, f"expected a path string, got {v!r}")
        p = input_path(v, self.base_dir)
        missing = missing_file(p, kind)
        if missing:
            raise self.fail(key, missing)
        return p

    def done(self) -> None:
        """Refuse the keys no reader asked for.

        Raises
        ------
        ValueError
            When ``raw`` holds a key not read by :meth:`get`; the message lists the
            known ones.
        """
        extra = sorted(set(self.raw) - self.used)
        if extra:
            raise ValueError(
                f"{self.where}: unknown option(s) {', '.join(self.name(k) for k in extra)}; "
                f"expected some of {', '.join(self.name(k) for k in sorted(self.used))}"
            )
