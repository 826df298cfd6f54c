"""Time ``ruledrobot carve`` on parts of about 10,000 triangles (target: under a minute each
on the 2-core machine for the mesh's work) and print the time per stage (``robot_check``:
the planner's wire-pose search on each cut, per cut, not per triangle) and the excess
against the visual hull of as many parallel directions.

    .venv/bin/python scripts/bench_carve.py [--triangles 10000] [--rough 4]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from ruledrobot.carve import carve
from ruledrobot.io.mesh import write_stl

CELL = """\
[part]
file = "{file}"
units = "m"
pose = {pose}
tolerance = 0.0005
rough_cuts = {rough}
[stock]
centre = [0.5, 0.0, 0.3]
size = [0.2, 0.2, 0.15]
[robot]
model = "ur5e"
[tool]
wire_start = [-0.2, 0.0, 0.25]
wire_end = [0.2, 0.0, 0.25]
"""


def _grid_mesh(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A closed mesh of a grid (nu, nv, 3) about the origin, periodic in u, fans at the v ends."""
    nu, nv, _ = P.shape
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b = idx, np.roll(idx, -1, axis=0)
    quads = np.stack([a[:, :-1], b[:, :-1], b[:, 1:], a[:, 1:]], -1).reshape(-1, 4)
    faces = [quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]
    V = [P.reshape(-1, 3)]
    for k in (0, nv - 1):  # a fan to the centre of each end ring
        c = len(np.concatenate(V))
        V.append(P[:, k].mean(axis=0)[None])
        ring = idx[:, k]
        faces.append(np.stack([np.full(nu, c), np.roll(ring, -1), ring], 1))
    v, f = np.concatenate(V), np.concatenate(faces)
    # star-shaped about the origin: every face turned to face away from it
    t = v[f]
    out = np.einsum("ij,ij->i", np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), t.mean(axis=1))
    return v, np.where((out < 0)[:, None], f[:, ::-1], f)


def ellipsoid(n: int) -> tuple[np.ndarray, np.ndarray]:
    nu = int(np.sqrt(n))
    nv = n // (2 * nu) + 1
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    t = np.linspace(0.02, np.pi - 0.02, nv)
    P = np.stack([np.cos(u)[:, None] * np.sin(t), np.sin(u)[:, None] * np.sin(t),
                  np.broadcast_to(np.cos(t), (nu, nv))], -1) * [0.09, 0.06, 0.045]
    return _grid_mesh(P)


def column(n: int) -> tuple[np.ndarray, np.ndarray]:
    nu = int(np.sqrt(2 * n))
    nv = n // (2 * nu) + 1
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    z = np.linspace(-0.1, 0.1, nv)
    r = 0.06 * np.sqrt(1 + z**2 / 0.09)
    P = np.stack([np.cos(u)[:, None] * r, np.sin(u)[:, None] * r,
                  np.broadcast_to(z, (nu, nv))], -1)
    return _grid_mesh(P)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--triangles", type=int, default=10_000)
    ap.add_argument("--rough", type=int, default=4)
    args = ap.parse_args()
    parts = {"ellipsoid 90 x 60 x 45 mm (roughed)": (ellipsoid, "[0.5, 0.0, 0.3, 0.0, 0.0, 0.0]"),
             "hyperboloid column (exact)": (column, "[0.5, 0.0, 0.3, 1.5707963, 0.0, 0.0]")}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for name, (make, pose) in parts.items():
            v, f = make(args.triangles)
            write_stl(d / "part.stl", v, f)
            (d / "cell.toml").write_text(CELL.format(file="part.stl", pose=pose, rough=args.rough))
            t = time.perf_counter()
            res = carve(d / "cell.toml", d / "out")
            total = time.perf_counter() - t
            r = res.report
            stages = ", ".join(f"{k} {v:.2f} s" for k, v in r["timings_s"].items())
            print(f"{name}: {len(f)} triangles, {total:.1f} s ({stages})")
            robot = r["timings_s"].get("robot_check", 0.0)
            print(f"  the mesh's work (all but the planner's checks of the cuts, whose time "
                  f"does not grow with the triangles): {total - robot:.1f} s")
            w, b = r["whole"], r["baseline"]
            line = (f"  {w['cuts']} cuts ({w['exact_cuts']} exact), excess "
                    f"{100 * w['excess']:.2f} %")
            if b:
                line += (f"; visual hull of {len(b['directions'])} parallel directions "
                         f"{100 * b['excess']:.2f} %")
            print(line + f"; verdict {'PASS' if r['ok'] else 'FAIL'}")


if __name__ == "__main__":
    main()
