"""Calibration files: ``ruledrobot.calibration/1`` JSON, read and written atomically.

File format (JSON, one object; lengths in metres, angles in radians)::

    {"format": "ruledrobot.calibration/1",
     "model": "ur5e",
     "source": "controller 192.168.1.10",
     "status": 2,
     "checksum": [3005486464, 2969637617, 688696456, 2832462165, 2830625259, 2832973731],
     "dh": {"theta_offset": [6 numbers], "a": [6], "d": [6], "alpha": [6]}}

``format``, ``model`` and ``dh`` are required; ``source`` defaults to the file's
path, ``status`` and ``checksum`` to null.  The DH values are the *effective*
ones (what the controller reports), written with 17 significant digits so that a
file read back gives the same table bit for bit.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..robot.arm.calibration import _COLUMNS, Calibration, CalibrationError, _column
from .atomic import atomic_write_json
from .text import json_object, read_user_text

__all__ = ["CALIBRATION_FORMAT", "load_calibration", "save_calibration"]

CALIBRATION_FORMAT = "ruledrobot.calibration/1"


def _to_dict(cal: Calibration) -> dict[str, Any]:
    return {
        "format": CALIBRATION_FORMAT,
        "model": cal.model,
        "source": cal.source,
        "status": cal.status,
        "checksum": None if cal.checksum is None else list(cal.checksum),
        "dh": {name: [float(v) for v in getattr(cal, name)] for name in _COLUMNS},
    }


def save_calibration(path: str | os.PathLike[str], cal: Calibration) -> Path:
    """Write ``cal`` as a ``ruledrobot.calibration/1`` JSON file (atomically); returns the path."""
    if not isinstance(cal, Calibration):
        raise TypeError(f"save_calibration: expected a Calibration, got {type(cal).__name__}")
    return atomic_write_json(path, _to_dict(cal))


def load_calibration(path: str | os.PathLike[str]) -> Calibration:
    """Read a ``ruledrobot.calibration/1`` JSON file.

    Every error is a :class:`CalibrationError` (a ``ValueError``) naming the file and
    the field, e.g. ``cal.json: dh.d[2] (joint 3 (elbow)): not a finite number`` or
    ``cal.json: joint 4 (wrist 1): alpha = ... differs from the nominal ...``.
    """
    p, text = read_user_text(path, "calibration file", CalibrationError)
    doc = json_object(text, str(p), CalibrationError, "not JSON (line {line}: {msg})")
    fmt = doc.get("format")
    if fmt != CALIBRATION_FORMAT:
        raise CalibrationError(f"{p}: format: expected {CALIBRATION_FORMAT!r}, got {fmt!r}")
    for key in ("model", "dh"):
        if key not in doc:
            raise CalibrationError(f"{p}: {key}: missing")
    unknown = sorted(set(doc) - {"format", "model", "source", "status", "checksum", "dh"})
    if unknown:
        raise CalibrationError(f"{p}: {unknown[0]}: unknown field")
    dh = doc["dh"]
    if not isinstance(dh, dict):
        raise CalibrationError(f"{p}: dh: expected an object with {', '.join(_COLUMNS)}")
    cols = {}
    for name in _COLUMNS:
        if name not in dh:
            raise CalibrationError(f"{p}: dh.{name}: missing")
        values = dh[name]
        if not isinstance(values, list) or any(
            isinstance(v, bool) or not isinstance(v, (int, float)) for v in values
        ):
            raise CalibrationError(f"{p}: dh.{name}: expected a list of 6 numbers, got {values!r}")
        try:
            cols[name] = _column(values, f"dh.{name}")
        except CalibrationError as exc:
            raise CalibrationError(f"{p}: {exc}") from None
    extra = sorted(set(dh) - set(_COLUMNS))
    if extra:
        raise CalibrationError(f"{p}: dh.{extra[0]}: unknown field")
    if not isinstance(doc["model"], str):
        raise CalibrationError(f"{p}: model: expected a string, got {doc['model']!r}")
    source = doc.get("source")
    if source is None:
        source = str(p)
    try:
        return Calibration(doc["model"], cols["theta_offset"], cols["a"], cols["d"],
                           cols["alpha"], checksum=doc.get("checksum"), source=source,
                           status=doc.get("status"))  # fmt: skip
    except CalibrationError as exc:
        raise CalibrationError(f"{p}: {exc}") from None
