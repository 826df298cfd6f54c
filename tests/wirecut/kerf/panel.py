"""A tapered panel (issue 33's proof): a plane cut through a block whose wire's two chord
ends sweep different chords (root 100 mm, tip 80 mm: the tip end moves 0.8 times as fast),
written as a job file with its rulings; the part is below the plane ``z = Z0``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

Z0 = 0.3
ROOT, TIP = 0.10, 0.08  # m: the chords the wire's ends sweep at y = -0.1 and y = +0.1
FEED = 0.02
KERF = 0.0008
MATERIAL = {"kerf_base": 0.0003, "kerf_gain": 2.5e-7, "power_threshold": 10.0}

MATERIAL_TABLE = "\n[material]\n" + "".join(f"{k} = {v!r}\n" for k, v in MATERIAL.items())


def write_panel(folder: Path, heat: str = 'heat = { output = "standard:0", preheat = 0.5 }',
                material: bool = True, cut: str = "") -> Path:
    """The panel's rulings (``panel.json``) and job (``panel.toml``) in ``folder``; the job's
    path.  ``heat``: the ``[tool]`` line of the heat; ``cut``: more ``[cut]`` fields."""
    u = np.linspace(-1.0, 1.0, 9)
    root = np.stack([0.5 + 0.5 * ROOT * u, np.full(9, -0.1), np.full(9, Z0)], axis=1)
    tip = np.stack([0.5 + 0.5 * TIP * u, np.full(9, 0.1), np.full(9, Z0)], axis=1)
    d = tip - root
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    (folder / "panel.json").write_text(json.dumps({
        "format": "ruledrobot.lines/1", "units": "m", "closed": False,
        "lines": [{"point": p.tolist(), "direction": q.tolist()}
                  for p, q in zip(root, d, strict=True)]}))
    job = folder / "panel.toml"
    job.write_text(f"""
[surface]
file = "panel.json"
algorithm = "projection"
scheme = "four_point"
steps = 3

[stock]
centre = [0.5, 0.0, 0.3]
size = [0.06, 0.2, 0.1]

[robot]
model = "ur5e"

[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
clearance = 0.02
mass = 1.0
{heat}

[cut]
feed_speed = {FEED!r}
lead_in = 0.01
lead_out = 0.01
kerf = {KERF!r}
keep = [0.5, 0.0, 0.27]
{cut}
""" + (MATERIAL_TABLE if material else ""))
    return job


def write_corner(folder: Path, heat: str) -> Path:
    """A cut with a corner stop in the block: the wire (along y) runs along ``z = Z0``
    in +x, then turns 40 degrees down (more than the 30 the time law stops at); the part
    is above.  Its job's path."""
    a = np.radians(40.0)
    pts = [[0.44 + 0.01 * i, 0.0, Z0] for i in range(7)]
    pts += [[0.5 + 0.01 * i * np.cos(a), 0.0, Z0 - 0.01 * i * np.sin(a)] for i in range(1, 8)]
    (folder / "corner.json").write_text(json.dumps({
        "format": "ruledrobot.lines/1", "units": "m", "closed": False,
        "lines": [{"point": p, "direction": [0.0, 1.0, 0.0]} for p in pts]}))
    text = (write_panel(folder, heat).read_text()
            .replace('file = "panel.json"', 'file = "corner.json"')
            .replace("steps = 3", "steps = 2")
            .replace("keep = [0.5, 0.0, 0.27]", "keep = [0.49, 0.0, 0.34]"))
    job = folder / "corner.toml"
    job.write_text(text)
    return job
