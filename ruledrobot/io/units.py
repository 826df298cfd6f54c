"""Length units of files: every reader converts to metres on reading.

``"m"``, ``"cm"``, ``"mm"`` and ``"in"`` (inches, 25.4 mm exactly), with the
spelled-out names as aliases (``"millimetres"``, ``"inches"``, ...).
"""

from __future__ import annotations

__all__ = ["UNIT_NAMES", "unit_name", "unit_scale"]

#: metres per unit
_SCALE = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
_ALIASES = {
    "metre": "m", "metres": "m", "meter": "m", "meters": "m",
    "centimetre": "cm", "centimetres": "cm", "centimeter": "cm", "centimeters": "cm",
    "millimetre": "mm", "millimetres": "mm", "millimeter": "mm", "millimeters": "mm",
    "inch": "in", "inches": "in",
}  # fmt: skip
UNIT_NAMES = tuple(_SCALE)


def unit_name(value: object, where: str) -> str:
    """The canonical name (``m``, ``cm``, ``mm``, ``in``) of a unit given by a user.

    ValueError naming ``where`` otherwise."""
    if isinstance(value, str):
        key = value.strip().lower()
        key = _ALIASES.get(key, key)
        if key in _SCALE:
            return key
    raise ValueError(
        f"{where}: unknown length unit {value!r}; expected one of {', '.join(UNIT_NAMES)}"
    )


def unit_scale(value: object, where: str) -> float:
    """Metres per unit of the unit ``value`` (see :func:`unit_name`)."""
    return _SCALE[unit_name(value, where)]
