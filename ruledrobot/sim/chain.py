"""The serial chain of a line sequence as MuJoCo MJCF: the paper's view of a discrete
ruled surface as the joint axes of a robot (``ruledrobot chain``)."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ._xml import placed, sub, to_string

__all__ = ["chain_mjcf", "write_chain"]


def chain_mjcf(
    lines_or_surface: object,
    *,
    closed: bool | None = None,
    radius: float | None = None,
    axis_length: float | None = None,
    actuators: bool = True,
) -> str:
    """MJCF text of the serial chain whose joint axes are the given lines.

    ``lines_or_surface`` is a :class:`~ruledrobot.geometry.ruled.RuledSurface`,
    a :class:`~ruledrobot.Lines` or Plücker rows (N, 6) (``closed`` applies
    to the last two).  Body ``axis{i}`` (i = 0..N-1) sits at DH frame i of
    ``RuledSurface.dh_frames()`` and carries hinge ``joint{i}`` about its z
    axis, the line i; the child body is placed by DH row i of
    ``dh_parameters()``, ``Trans_x(a) Rot_x(alpha) Rot_z(theta) Trans_z(d)``
    (Craig's ordering).  So at ``q = 0`` the joint axes (``mjData.xaxis``,
    ``xanchor``) are the input lines, oriented as they are.  A closed surface
    ends in a site ``end`` at its closing frame (frame 0, turned by pi about x
    after a flip); an open one in a site ``end`` at the last frame.

    Geometry: a cylinder along each joint axis (``axis_length``, default 1.5 x
    the median spacing, at least 4 radii) and capsules along the common
    normals and joint offsets; ``radius`` defaults to 1.5 % of the chain's
    size.  No gravity; ``actuators`` adds a position servo per joint, so the
    chain can be posed from a viewer.  Masses come from the geoms (density
    1000 kg/m^3).
    """
    from ..geometry.lines import Lines
    from ..geometry.ruled import RuledSurface, dh_transform

    if isinstance(lines_or_surface, RuledSurface):
        surf = lines_or_surface
        if closed is not None and bool(closed) != surf.closed:
            raise ValueError(f"closed={closed} contradicts the surface (closed={surf.closed})")
    else:
        lines = (
            lines_or_surface
            if isinstance(lines_or_surface, Lines)
            else Lines.from_plucker(np.asarray(lines_or_surface, dtype=np.float64))
        )
        surf = RuledSurface(lines, closed=bool(closed))
    T = surf.dh_frames()
    rows = surf.dh_parameters()
    n = T.shape[0]
    rel = dh_transform(rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3])  # (P, 4, 4)
    origins = T[:, :3, 3]
    size = float(np.linalg.norm(np.ptp(origins, axis=0))) if n > 1 else 1.0
    spacing = np.concatenate([rows[:, 2], np.abs(rows[:, 1])])
    step = float(np.median(spacing[spacing > 1e-9])) if np.any(spacing > 1e-9) else size / n
    r = float(radius) if radius is not None else max(0.015 * max(size, step), 1e-4)
    if not r > 0.0:
        raise ValueError(f"radius: must be positive, got {radius}")
    half = 0.5 * (float(axis_length) if axis_length is not None else max(1.5 * step, 4 * r))
    if not half > 0.0:
        raise ValueError(f"axis_length: must be positive, got {axis_length}")

    root = ET.Element("mujoco", model="line_chain")
    sub(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="true")
    sub(root, "option", timestep=0.002, integrator="implicitfast", gravity="0 0 0")
    visual = sub(root, "visual")
    sub(visual, "quality", offsamples=0)
    sub(visual, "map", znear=0.001)
    default = sub(root, "default")
    sub(default, "geom", contype=0, conaffinity=0, density=1000)
    sub(
        default, "joint", type="hinge", axis="0 0 1", limited=False, damping=0.01 * r, armature=1e-4
    )
    worldbody = sub(root, "worldbody")
    top = [*origins.mean(axis=0)[:2], origins[:, 2].max() + 3 * size + 1]
    sub(worldbody, "light", name="top", pos=top, dir="0 0 -1", directional=True, castshadow=False)
    parent = worldbody
    pose = T[0]
    for i in range(n):
        body = placed(parent, "body", pose, name=f"axis{i}")
        sub(body, "joint", name=f"joint{i}")
        sub(body, "geom", name=f"axis{i}", type="cylinder", size=[r, half], rgba="0.25 0.50 0.72 1")
        if i < rel.shape[0]:
            nxt = rel[i]
            foot = np.array([float(rows[i, 2]), 0.0, 0.0])
            if rows[i, 2] > 1e-9:
                sub(
                    body,
                    "geom",
                    name=f"normal{i}",
                    type="capsule",
                    size=0.5 * r,
                    fromto=np.concatenate([np.zeros(3), foot]),
                    rgba="0.78 0.80 0.82 1",
                )
            if abs(rows[i, 1]) > 1e-9:
                sub(
                    body,
                    "geom",
                    name=f"offset{i}",
                    type="capsule",
                    size=0.5 * r,
                    fromto=np.concatenate([foot, nxt[:3, 3]]),
                    rgba="0.78 0.80 0.82 1",
                )
        if i == n - 1:
            # closed: the closing row leads to frame 0 (turned by pi about x after a flip)
            end = rel[i] if surf.closed else np.eye(4)
            placed(body, "site", end, name="end", size=1.5 * r, rgba="0.9 0.1 0.1 1")
        parent = body
        if i < n - 1:
            pose = rel[i]
    if actuators:
        act = sub(root, "actuator")
        for i in range(n):
            sub(act, "position", name=f"pos{i}", joint=f"joint{i}", kp=1.0, kv=0.1)
    return to_string(root, f"serial chain of {n} lines (ruledrobot.sim.chain.chain_mjcf)")


def write_chain(
    lines_path: str | os.PathLike[str], out_path: str | os.PathLike[str], **options: object
) -> Path:
    """Read a lines file (``.json``/``.csv``) and write its chain MJCF to ``out_path``.

    The file's ``closed`` flag is used; ``options`` go to :func:`chain_mjcf`.
    Returns the written path.  ValueError names the file on bad input.
    """
    from ..geometry.ruled import RuledSurface
    from ..io.lines import read_lines_document

    doc = read_lines_document(lines_path)
    try:
        surf = RuledSurface(doc.lines, closed=doc.closed)
        text = chain_mjcf(surf, **options)  # type: ignore[arg-type]
    except ValueError as exc:
        raise ValueError(f"{lines_path}: {exc}") from None
    return atomic_write_text(out_path, text)
