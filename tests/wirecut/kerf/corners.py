"""Profiles with sharp corners (issue 33's corner proof): the wire along y through the
panel's block (60 x 200 x 100 mm at (0.5, 0, 0.3)), its path a polygon in the x-z plane,
refined linearly (the corners stay corners); the part on one side.  A profile is its
polygon (the part's faces, metres in x-z) and a job file written from it."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .panel import write_panel

Y0, Y1 = -0.1, 0.1  # the block's faces the wire's chord ends lie on
CENTRE = np.array([0.5, 0.3])  # the block's centre, x-z

ANALOG_CONSTANT_KERF = ('heat = { output = "analog:0", mode = "constant_kerf", '
                        "full_scale = 400.0, preheat = 0.5 }")
DIGITAL = 'heat = { output = "standard:0", preheat = 0.5 }'


@dataclass(frozen=True)
class Profile:
    """A polygon ``vertices`` (N, 2) [m, x-z] (closed: a loop), the unit normals (N', 2)
    of its faces (vertex k to k + 1) into the waste, and its job's path."""

    vertices: np.ndarray
    closed: bool
    normals: np.ndarray
    job: Path

    def segments(self) -> tuple[np.ndarray, np.ndarray]:
        """The faces' start and end points (N', 2)."""
        v = self.vertices
        b = np.roll(v, -1, axis=0) if self.closed else v[1:]
        return v[: len(b)], b


def _normals(vertices: np.ndarray, closed: bool, keep) -> np.ndarray:
    """Unit normals of the faces into the waste: of a loop, outwards (``keep = "inside"``,
    the left normal of a counter-clockwise loop turned round: shoelace area) or inwards;
    of an open path, turned away from ``keep``'s side (x, z) of the face nearest it, the
    same side for every face."""
    a = vertices
    b = np.roll(a, -1, axis=0) if closed else a[1:]
    a = a[: len(b)]
    d = (b - a) / np.linalg.norm(b - a, axis=1, keepdims=True)
    left = np.stack([-d[:, 1], d[:, 0]], axis=1)
    if closed:
        ccw = float(np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])) > 0.0
        return -left if ccw == (keep == "inside") else left
    keep = np.asarray(keep, dtype=np.float64)
    t = np.clip(((keep - a) * d).sum(axis=1) / np.linalg.norm(b - a, axis=1), 0.0, 1.0)
    foot = a + t[:, None] * (b - a)
    k = int(np.argmin(np.linalg.norm(keep - foot, axis=1)))
    return -left if (keep - foot[k]) @ left[k] > 0.0 else left


def write_profile(folder: Path, name: str, vertices, closed: bool, keep, heat: str,
                  material: bool = True, spacing: float = 0.005) -> Profile:
    """The profile's rulings (every ``spacing`` along its faces, vertices kept) and its job
    (the panel's cell, ``scheme = "linear"``); ``keep``: ``"inside"``/``"outside"`` of a
    loop, or a point (x, z) of the part."""
    v = np.asarray(vertices, dtype=np.float64)
    b = np.roll(v, -1, axis=0) if closed else v[1:]
    pts = []
    for p, q in zip(v[: len(b)], b, strict=True):
        n = max(int(np.ceil(np.linalg.norm(q - p) / spacing)), 1)
        pts += [p + (q - p) * j / n for j in range(n)]
    if not closed:
        pts.append(v[-1])
    (folder / f"{name}.json").write_text(json.dumps({
        "format": "ruledrobot.lines/1", "units": "m", "closed": closed,
        "lines": [{"point": [p[0], 0.0, p[1]], "direction": [0.0, 1.0, 0.0]} for p in pts]}))
    if isinstance(keep, str):
        keep_line = f'keep = "{keep}"'
    else:
        keep_line = f"keep = [{float(keep[0])!r}, 0.0, {float(keep[1])!r}]"
    text = (write_panel(folder, heat, material).read_text()
            .replace('file = "panel.json"', f'file = "{name}.json"')
            .replace('scheme = "four_point"', 'scheme = "linear"')
            .replace("steps = 3", "steps = 0")
            .replace("keep = [0.5, 0.0, 0.27]", keep_line))
    job = folder / f"{name}.toml"
    job.write_text(text)
    return Profile(v, closed, _normals(v, closed, keep), job)


def corner(folder: Path, turn_deg: float, convex: bool, heat: str, material: bool = True,
           name: str = "corner") -> Profile:
    """An open path along ``z = 0.3`` in +x to (0.5, 0.3), then turned down by
    ``turn_deg`` to the block's bottom and past it; the part inside the angle (convex) or
    outside it (concave: the waste inside)."""
    a = np.radians(turn_deg)
    u = np.array([np.cos(a), -np.sin(a)])
    c = np.array([0.5, 0.3])
    v = np.array([[0.44, 0.3], c, c + 0.07 * u])
    inner = c + 0.004 * (np.array([-1.0, 0.0]) + u) / np.linalg.norm(np.array([-1.0, 0.0]) + u)
    keep = inner if convex else c + np.array([-0.01, 0.04])
    return write_profile(folder, name, v, False, keep, heat, material)


def square(folder: Path, heat: str, material: bool = True, side: float = 0.03) -> Profile:
    """A closed square loop (``side`` m) round the block's centre, the part inside: four
    convex corners.  (A square hole, the part outside, cannot be cut with a wire: its slit
    would cut the part.)"""
    h = 0.5 * side
    v = np.array([[0.5 - h, 0.3 - h], [0.5 + h, 0.3 - h], [0.5 + h, 0.3 + h],
                  [0.5 - h, 0.3 + h]])  # fmt: skip
    return write_profile(folder, "square", v, True, "inside", heat, material)


def ell(folder: Path, heat: str, material: bool = True, side: float = 0.03) -> Profile:
    """A closed L-shaped loop (a ``side`` m square less its upper right quarter) round the
    block's centre, the part inside: five convex corners and a concave one."""
    h = 0.5 * side
    v = np.array([[-h, -h], [h, -h], [h, 0.0], [0.0, 0.0], [0.0, h], [-h, h]]) + CENTRE
    return write_profile(folder, "ell", v, True, "inside", heat, material)
