"""Small helpers to write MJCF with :mod:`xml.etree` (exact, deterministic numbers)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..geometry import se3


def fmt(x: float) -> str:
    """Shortest round-trip text of a float (``repr``), ``0`` for +-0, no trailing ``.0``."""
    v = float(x)
    if v == 0.0:
        return "0"
    if not np.isfinite(v):
        raise ValueError(f"MJCF: cannot write the non-finite number {v!r}")
    r = repr(v)
    return r[:-2] if r.endswith(".0") else r


def vec(v: ArrayLike) -> str:
    """Space-separated numbers of a vector."""
    return " ".join(fmt(x) for x in np.asarray(v, dtype=np.float64).ravel())


def quat(R: ArrayLike) -> str:
    """MuJoCo quaternion text ``w x y z`` of a rotation matrix (3, 3)."""
    q = se3.quaternion_from_matrix(np.asarray(R, dtype=np.float64))
    return vec(q)


def is_identity_rotation(R: ArrayLike) -> bool:
    """Whether the rotation matrix ``R`` (3, 3) is exactly the identity (no tolerance)."""
    return bool(np.array_equal(np.asarray(R), np.eye(3)))


def sub(parent: ET.Element, tag: str, **attrs: Any) -> ET.Element:
    """A child element; ``None`` attributes are skipped, others converted with :func:`fmt`."""
    el = ET.SubElement(parent, tag)
    for k, v in attrs.items():
        if v is None:
            continue
        key = k.rstrip("_")  # class_ -> class
        if isinstance(v, bool):
            el.set(key, "true" if v else "false")
        elif isinstance(v, str):
            el.set(key, v)
        elif isinstance(v, (int, float, np.floating, np.integer)):
            el.set(key, fmt(float(v)))
        else:
            el.set(key, vec(v))
    return el


def placed(parent: ET.Element, tag: str, T: ArrayLike, **attrs: Any) -> ET.Element:
    """A child element (body, site, camera, geom) at the pose T (4, 4) in the parent frame."""
    T = np.asarray(T, dtype=np.float64)
    pos = T[:3, 3]
    el = ET.SubElement(parent, tag)
    name = attrs.pop("name", None)
    if name is not None:
        el.set("name", name)
    if np.any(pos != 0.0):
        el.set("pos", vec(pos))
    if not is_identity_rotation(T[:3, :3]):
        el.set("quat", quat(T[:3, :3]))
    for k, v in attrs.items():
        if v is None:
            continue
        tmp = sub(ET.Element("x"), "y", **{k: v})
        for kk, vv in tmp.attrib.items():
            el.set(kk, vv)
    return el


def to_string(root: ET.Element, comment: str | None = None) -> str:
    """Indented XML text (no XML declaration), with an optional leading comment."""
    ET.indent(root, space="  ")
    body = ET.tostring(root, encoding="unicode")
    head = f"<!-- {comment} -->\n" if comment else ""
    return head + body + "\n"
