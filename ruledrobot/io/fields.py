"""Typed reading of one table's fields, the checks every reader of user tables shares.

:class:`FieldReader` is the base of the format options' reader
(:class:`ruledrobot.io.formats.options.Options`) and of the job file's sections
(``ruledrobot.wirecut.job.sections.Section``): each says where a field is (:meth:`fail`)
and how a field is read (``get``); the value checks, and their messages, are here once.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["FieldReader"]


class FieldReader:
    """Checked values of a table's fields; subclasses define ``get`` and ``fail``.

    ``raw`` holds the table, ``used`` the keys read so far (unknown keys are the rest).
    """

    raw: Mapping[str, Any]
    used: set[str]

    def fail(self, key: str, msg: str) -> ValueError:
        """The error for field ``key``, its message naming where the field is."""
        raise NotImplementedError

    def get(self, key: str, default: Any = None) -> Any:
        """The raw value of ``key`` (``default`` when absent), marked as used."""
        raise NotImplementedError

    def boolean(self, key: str, default: bool) -> bool:
        """``key`` as true or false (``default`` when absent)."""
        v = self.get(key, default)
        if not isinstance(v, bool):
            raise self.fail(key, f"expected true or false, got {v!r}")
        return v

    def finite(self, key: str, v: Any) -> float:
        """``v``, the value of ``key``, as a finite float (booleans refused)."""
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
            raise self.fail(key, f"expected a finite number, got {v!r}")
        return float(v)

    def numbers(
        self, key: str, v: Any, n: int, sequences: tuple[type, ...] = (list, tuple)
    ) -> np.ndarray:
        """``v``, the value of ``key``, as (n,) finite floats (a list of ``n`` numbers)."""
        if (
            not isinstance(v, sequences)
            or len(v) != n
            or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v)
        ):
            raise self.fail(key, f"expected a list of {n} numbers, got {v!r}")
        arr = np.asarray(v, dtype=np.float64)
        if not np.all(np.isfinite(arr)):
            raise self.fail(key, "contains NaN or infinity")
        return arr
