"""Checks and verdicts: every measurement either decides or is labelled information.

A :class:`Check` is one measured value against its limit; a :class:`Verdict` is
the conjunction of its *gating* checks (``gating=False`` marks information
only).  ``plan``, ``run`` and ``batch`` end with one verdict: exit status 0 when
it holds, 1 when a gating check fails (``docs/verdict.md``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = ["Check", "Verdict"]


def _fmt(x: float | int | str | None, unit: str) -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        s = f"{x:,}"
    elif not math.isfinite(x):
        s = str(x)
    else:
        s = f"{x:.4g}"
    return f"{s} {unit}".rstrip()


@dataclass(frozen=True)
class Check:
    """One measurement and its verdict.

    ``name``: short identifier (``"collisions"``); ``label``: what is measured, in
    words; ``value`` and ``limit`` in ``unit``; ``relation``: ``"<="``, ``">="``,
    ``"=="`` or ``""`` (information); ``ok``: whether it holds; ``gating``: whether
    it decides the verdict; ``detail``: where and why, in words, for failures.
    """

    name: str
    label: str
    value: float | int | str | None
    limit: float | int | str | None = None
    unit: str = ""
    relation: str = ""
    ok: bool = True
    gating: bool = True
    detail: str = ""

    @classmethod
    def at_most(cls, name: str, label: str, value: float | None, limit: float, unit: str = "",
                detail: str = "") -> Check:  # fmt: skip
        """``value <= limit`` (a missing value fails)."""
        ok = value is not None and math.isfinite(value) and value <= limit
        return cls(name, label, value, limit, unit, "<=", bool(ok), True, "" if ok else detail)

    @classmethod
    def at_least(cls, name: str, label: str, value: float | None, limit: float, unit: str = "",
                 detail: str = "") -> Check:  # fmt: skip
        """``value >= limit`` (a missing value fails)."""
        ok = value is not None and math.isfinite(value) and value >= limit
        return cls(name, label, value, limit, unit, ">=", bool(ok), True, "" if ok else detail)

    @classmethod
    def info(cls, name: str, label: str, value: float | int | str | None, unit: str = "",
             detail: str = "") -> Check:  # fmt: skip
        """Information only: shown and written, never deciding."""
        return cls(name, label, value, None, unit, "", True, False, detail)

    @property
    def value_text(self) -> str:
        """The value with its unit for a table (``"0.012 m"``, ``"yes"``; ``"-"`` if missing)."""
        return _fmt(self.value, self.unit)

    @property
    def limit_text(self) -> str:
        """The relation and limit with its unit (``"<= 0.0005 m"``), or ``"information"``."""
        if not self.gating:
            return "information"
        return f"{self.relation} {_fmt(self.limit, self.unit)}".strip()

    def as_dict(self) -> dict[str, Any]:
        """The check's fields as a dict for a report (a non-finite float ``value`` as None)."""
        d = asdict(self)
        if isinstance(d["value"], float) and not math.isfinite(d["value"]):
            d["value"] = None
        return d


@dataclass(frozen=True)
class Verdict:
    """The conjunction of the gating checks."""

    checks: tuple[Check, ...] = field(default_factory=tuple)

    @property
    def ok(self) -> bool:
        """Whether every gating check holds."""
        return all(c.ok for c in self.checks if c.gating)

    @property
    def failed(self) -> tuple[Check, ...]:
        """The gating checks that fail, in order."""
        return tuple(c for c in self.checks if c.gating and not c.ok)

    def __getitem__(self, name: str) -> Check:
        for c in self.checks:
            if c.name == name:
                return c
        raise KeyError(name)

    def summary(self) -> str:
        """One line: ``"all 11 checks hold"`` or ``"2 checks fail: collisions, feed"``."""
        n = sum(c.gating for c in self.checks)
        if self.ok:
            return f"all {n} checks hold"
        names = ", ".join(c.name for c in self.failed)
        k = len(self.failed)
        return f"{k} of {n} checks fail: {names}"

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> Verdict:
        """The verdict written by :meth:`as_dict` (a report's ``"verdict"``)."""
        fields = Check.__dataclass_fields__
        return cls(tuple(Check(**{k: v for k, v in c.items() if k in fields})
                         for c in doc["checks"]))  # fmt: skip

    def as_dict(self) -> dict[str, Any]:
        """The verdict as a dict for a report.

        ``ok``, ``summary``, the ``failed`` checks' names and every check's
        :meth:`Check.as_dict`; :meth:`from_dict` reads it back."""
        return {
            "ok": self.ok,
            "summary": self.summary(),
            "failed": [c.name for c in self.failed],
            "checks": [c.as_dict() for c in self.checks],
        }
