"""The hot-wire bow: the one definition of the tool that planner and simulation share.

A :class:`BowTool` is a wire between two points of the flange frame held by two
arms and a crossbar.  :meth:`BowTool.wire_frame` is the TCP of every cut
trajectory; :meth:`BowTool.segments` the rods the planner's clearance checks
use; :meth:`BowTool.inertia` the payload (mass, centre of gravity) the
controller is told and the simulation carries.  Units: m, kg, flange frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from ._checks import FloatArray, as_point

__all__ = ["BowSpec", "BowTool"]


class BowSpec(Protocol):
    """What :meth:`BowTool.from_spec` reads of a spec: the wire's ends and the bow's mass.

    The spec is the ``[tool]`` of a cut job (``ruledrobot.wirecut.job.spec.ToolSpec``): the
    wire's end points in the flange frame [m] and the bow's mass [kg] (None: the default).
    """

    @property
    def wire_start(self) -> ArrayLike:
        """(3,) start of the wire in the flange frame [m]."""
        ...

    @property
    def wire_end(self) -> ArrayLike:
        """(3,) end of the wire in the flange frame [m]."""
        ...

    @property
    def mass(self) -> float | None:
        """Total mass of the bow [kg]; None for :class:`BowTool`'s default."""
        ...


@dataclass(frozen=True)
class BowTool:
    """A hot-wire bow: a wire between two points of the flange frame, held by two arms.

    Attributes
    ----------
    wire_start, wire_end : (3,) wire end points in the flange frame [m].
    arm_radius : radius of the bow's arms and crossbar [m].
    wire_radius : radius of the wire [m] (drawn and used for wire contacts).
    hub_radius, hub_length : the mounting plate on the flange [m] (a cylinder
        along the flange z axis from the flange face).
    mass : total mass of the bow [kg] (arms and crossbar, uniform rods).

    The shape is that of the cut planner (``ruledrobot.wirecut``): an arm from
    each wire end straight back to the plane through the flange z axis normal
    to the bow's depth direction (the component of the wire midpoint normal
    to the wire), and a crossbar between the two arms' feet.
    """

    wire_start: FloatArray
    wire_end: FloatArray
    arm_radius: float = 0.008
    wire_radius: float = 0.0004
    hub_radius: float = 0.035
    hub_length: float = 0.015
    mass: float = 1.0

    def __post_init__(self) -> None:
        a = as_point(self.wire_start, "wire_start")
        b = as_point(self.wire_end, "wire_end")
        if np.linalg.norm(b - a) < 1e-6:
            raise ValueError("wire_end: must differ from wire_start (a wire needs a length)")
        object.__setattr__(self, "wire_start", a)
        object.__setattr__(self, "wire_end", b)
        for name in ("arm_radius", "wire_radius", "hub_radius", "hub_length"):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0.0):
                raise ValueError(f"{name}: expected a positive length (m), got {v!r}")
            object.__setattr__(self, name, v)
        mass = float(self.mass)
        if not (np.isfinite(mass) and mass >= 0.0):
            raise ValueError(f"mass: expected a mass >= 0 (kg), got {mass!r}")
        object.__setattr__(self, "mass", mass)

    @classmethod
    def from_spec(cls, spec: BowSpec, **overrides: Any) -> BowTool:
        """Build the bow from any object with ``wire_start``, ``wire_end`` (optionally ``mass``).

        E.g. the ``[tool]`` of a cut job (``ruledrobot.wirecut.job.spec.ToolSpec``).
        """
        kw: dict[str, Any] = {"wire_start": spec.wire_start, "wire_end": spec.wire_end}
        if getattr(spec, "mass", None) is not None:
            kw["mass"] = spec.mass
        kw.update(overrides)
        return cls(**kw)

    @classmethod
    def of(cls, tool: BowSpec | BowTool) -> BowTool:
        """Return ``tool`` itself when it is a bow already, else :meth:`from_spec` of it.

        A bow is built once and passed down.
        """
        return tool if isinstance(tool, BowTool) else cls.from_spec(tool)

    @property
    def wire_length(self) -> float:
        """Length of the wire [m]."""
        return float(np.linalg.norm(self.wire_end - self.wire_start))

    def depth_direction(self) -> FloatArray:
        """Unit vector (3,) from the flange axis towards the wire, normal to the wire."""
        z = (self.wire_end - self.wire_start) / self.wire_length
        mid = 0.5 * (self.wire_start + self.wire_end)
        x = mid - (mid @ z) * z
        if np.linalg.norm(x) < 1e-9:
            x = np.array([0.0, 0.0, 1.0]) - z[2] * z
            if np.linalg.norm(x) < 1e-9:
                x = np.array([1.0, 0.0, 0.0]) - z[0] * z
        return x / np.linalg.norm(x)

    def segments(self) -> FloatArray:
        """The bow's rods (3, 2, 3) in the flange frame.

        Arm at the start, arm at the end, crossbar (the same rods as
        ``ruledrobot.wirecut.cut.wire_pose.bow_segments``)."""
        x = self.depth_direction()
        a = self.wire_start - (self.wire_start @ x) * x
        b = self.wire_end - (self.wire_end @ x) * x
        return np.array([[self.wire_start, a], [self.wire_end, b], [a, b]])

    def inertia(self) -> tuple[FloatArray, FloatArray]:
        """COM (3,) and inertia tensor (3, 3) about it, flange frame [m, kg m^2].

        The mass is spread over the three rods in proportion to their length;
        each rod is a solid cylinder of radius ``arm_radius``.
        """
        seg = self.segments()
        length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=-1)
        total = float(length.sum())
        if self.mass == 0.0 or total == 0.0:
            return 0.5 * (self.wire_start + self.wire_end), np.zeros((3, 3))
        m = self.mass * length / total
        centres = 0.5 * (seg[:, 0] + seg[:, 1])
        com = (m[:, None] * centres).sum(axis=0) / self.mass
        inertia = np.zeros((3, 3))
        r2 = self.arm_radius**2
        for mk, lk, ck, (p0, p1) in zip(m, length, centres, seg, strict=True):
            if lk > 0.0:
                u = (p1 - p0) / lk
                across = mk * (3.0 * r2 + lk * lk) / 12.0
                inertia += across * np.eye(3) + (0.5 * mk * r2 - across) * np.outer(u, u)
            r = ck - com
            inertia += mk * ((r @ r) * np.eye(3) - np.outer(r, r))
        return com, inertia

    def wire_frame(self) -> FloatArray:
        """The wire frame W (4, 4) in the flange frame.

        Origin at the wire midpoint, z from ``wire_start`` to ``wire_end``, x the depth
        direction, y = z x x."""
        z = (self.wire_end - self.wire_start) / self.wire_length
        x = self.depth_direction()
        W = np.eye(4)
        W[:3, 0], W[:3, 1], W[:3, 2] = x, np.cross(z, x), z
        W[:3, 3] = 0.5 * (self.wire_start + self.wire_end)
        return W
