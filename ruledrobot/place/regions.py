"""Where the block goes: search regions, turns of the block, placements, moved jobs.

Every pose of a job is in the robot base frame (README): the stock, each cut's
surface ``pose`` and ``keep`` point.  Moving the block is one rigid motion ``T``
(4, 4) of the base frame applied to all of them — the cut surfaces move with the
block, so the cut in the block is the same.  Only motions that keep the table
where it is are searched: a **turn** of the block (about the vertical, or tipped
90 / 180 degrees over a bottom edge onto another face, resting on the same
support height) followed by a shift and a yaw on the table.

* ``move = "stock"``: the region is the block's centre ``x, y`` (m, base frame) and
  its yaw (rad, about the vertical through its centre, relative to the job's
  orientation after the turn).  ``T = Tr(x, y, 0) Rz(yaw) Tr(-c_x, -c_y, 0) T_turn``.
* ``move = "robot"``: the block stays where it is and the robot's base moves by
  ``x, y`` (m) and turns by ``yaw`` (rad) in its current base frame: in the new base
  frame the block has moved by the inverse, ``T = (Tr(x, y, 0) Rz(yaw))^-1 T_turn``;
  the placed job's ``[robot] base`` moves by ``Tr(x, y, 0) Rz(yaw)``
  (:meth:`Placement.job`), so in the simulation's world the block stays put.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..geometry import se3
from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..io.words import mm
from ..wirecut.job.spec import Job

__all__ = [
    "AS_CLAMPED",
    "Placement",
    "Region",
    "Turn",
    "mm",
    "moved_job",
    "parse_range",
    "parse_turns",
    "transforms",
]

MOVES = ("stock", "robot")


def parse_range(text: str, what: str, unit: float = 1.0) -> tuple[float, float]:
    """Parse ``"a:b"`` (or one number ``"a"``) into ``(a * unit, b * unit)``.

    ValueError names ``what`` (e.g. ``--x``) and what was expected.
    """
    parts = str(text).split(":")
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise ValueError(f"{what}: expected LOW:HIGH or one number, got {text!r}") from None
    if len(vals) == 1:
        vals = vals * 2
    if len(vals) != 2 or not all(np.isfinite(vals)) or vals[1] < vals[0]:
        raise ValueError(f"{what}: expected LOW:HIGH with LOW <= HIGH, got {text!r}")
    return vals[0] * unit, vals[1] * unit


@dataclass(frozen=True)
class Turn:
    """A turn of the block before it is placed.

    ``axis`` "z" (about the vertical through its centre) or "x" / "y" (tipped over a bottom
    edge parallel to the block's own x / y axis, landing on another face at the same support
    height), by ``degrees`` (a multiple of 90)."""

    axis: str = "z"
    degrees: int = 0

    def __post_init__(self) -> None:
        if self.axis not in ("x", "y", "z") or self.degrees % 90:
            raise ValueError(f"turn: expected x, y or z and a multiple of 90 degrees, got "
                             f"{self.axis}{self.degrees}")  # fmt: skip
        object.__setattr__(self, "degrees", int(self.degrees) % 360)

    @property
    def label(self) -> str:
        """The turn as the CLI writes it: ``"as clamped"`` or axis and degrees, e.g. ``"x90"``."""
        return "as clamped" if self.degrees == 0 else f"{self.axis}{self.degrees}"

    def matrix(self, stock: Box) -> FloatArray:
        """The turn as a rigid motion (4, 4) of the base frame for the job's ``stock``."""
        if self.degrees == 0:
            return np.eye(4)
        angle = np.radians(self.degrees)
        if self.axis == "z":
            axis = np.array([0.0, 0.0, 1.0])
        else:
            axis = stock.rotation[:, "xy".index(self.axis)]
        R = se3.rotation_about_axis(axis, angle)
        c = stock.centre
        pts = stock.corners - stock.centre
        lift = (pts[:, 2].min() - (pts @ R.T)[:, 2].min())  # keep the bottom height
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = c - R @ c + np.array([0.0, 0.0, lift])
        return T


#: the block as the job clamps it (no turn)
AS_CLAMPED = Turn()


def parse_turns(text: str) -> tuple[Turn, ...]:
    """``"z90,z180,x90"`` -> turns (the empty string: none)."""
    out = []
    for item in filter(None, (s.strip() for s in str(text).split(","))):
        axis, deg = item[:1].lower(), item[1:]
        if axis not in ("x", "y", "z") or not deg.lstrip("-").isdigit() or int(deg) % 90:
            raise ValueError(f"--turns: expected items like z90, z180, x90, y180 (axis x, y or "
                             f"z and a multiple of 90 degrees), got {item!r}")  # fmt: skip
        out.append(Turn(axis, int(deg)))
    return tuple(dict.fromkeys(t for t in out if t.degrees))


@dataclass(frozen=True)
class Region:
    """Where to search.

    ``x``, ``y`` (m) and ``yaw`` (rad) ranges (LOW, HIGH) — of the block's centre and yaw
    (``move = "stock"``), or of the robot base's move (``"robot"``), see the module doc."""

    x: tuple[float, float]
    y: tuple[float, float]
    yaw: tuple[float, float]
    move: str = "stock"

    def __post_init__(self) -> None:
        if self.move not in MOVES:
            raise ValueError(f"--move: expected stock or robot, got {self.move!r}")
        for name in ("x", "y", "yaw"):
            lo, hi = getattr(self, name)
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"--{name}: expected LOW <= HIGH, got {lo}:{hi}")
        if self.yaw[1] - self.yaw[0] > 2.0 * np.pi + 1e-9:
            raise ValueError("--yaw: a range wider than 360 degrees")

    @classmethod
    def around(cls, job: Job, move: str = "stock", half: float = 0.3,
               yaw_half: float = np.pi / 2) -> Region:  # fmt: skip
        """The default region: the job's placement +- ``half`` (m) and +- ``yaw_half`` (rad)."""
        if move == "stock":
            cx, cy = (float(v) for v in job.stock.centre[:2])
            return cls((cx - half, cx + half), (cy - half, cy + half), (-yaw_half, yaw_half))
        return cls((-half, half), (-half, half), (-yaw_half, yaw_half), "robot")

    def grid(self, n: tuple[int, int, int]) -> FloatArray:
        """Return the (N, 3) ``[x, y, yaw]`` samples: ``n`` per axis, ends included.

        One where a range is a single value.
        """
        axes = [np.linspace(lo, hi, k) if hi > lo else np.array([lo])
                for (lo, hi), k in zip((self.x, self.y, self.yaw), n, strict=True)]  # fmt: skip
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)

    def edges(self, xyz: FloatArray) -> str:
        """Return which ends of the region ``xyz`` lies on, as the options that would widen them.

        ``xyz`` ``[x, y, yaw]`` (3,); the options as ``"the low end of --x"``...; '' when
        inside.  A range of one value has no edge; a yaw range of a full turn neither.
        """
        out = []
        full_turn = self.yaw[1] - self.yaw[0] >= 2.0 * np.pi - 1e-9
        for k, (name, (lo, hi)) in enumerate(zip(("x", "y", "yaw"), (self.x, self.y, self.yaw),
                                                  strict=True)):  # fmt: skip
            if hi <= lo or (name == "yaw" and full_turn):
                continue
            tol = 1e-6 * max(hi - lo, 1.0)
            if xyz[k] <= lo + tol:
                out.append(f"the low end of --{name}")
            elif xyz[k] >= hi - tol:
                out.append(f"the high end of --{name}")
        return ", ".join(out)

    def clip(self, xyz: FloatArray) -> FloatArray:
        """Samples (N, 3) clipped into the region."""
        lo = np.array([self.x[0], self.y[0], self.yaw[0]])
        hi = np.array([self.x[1], self.y[1], self.yaw[1]])
        return np.clip(xyz, lo, hi)


@dataclass(frozen=True)
class Placement:
    """One placement.

    ``x, y`` (m), ``yaw`` (rad) in the sense of ``move`` (module doc), after ``turn``."""

    x: float
    y: float
    yaw: float
    move: str = "stock"
    turn: Turn = AS_CLAMPED

    def transform(self, job: Job) -> FloatArray:
        """The rigid motion T (4, 4) of the base frame that places the job's block."""
        return transforms(job, np.array([[self.x, self.y, self.yaw]]), self.move, self.turn)[0]

    def base_motion(self) -> FloatArray:
        """How the robot's base moves (4, 4), in its present base frame.

        ``Tr(x, y, 0) Rz(yaw)`` for ``move = "robot"``, the identity when the block moves."""
        if self.move != "robot":
            return np.eye(4)
        return transforms_of_base(np.array([[self.x, self.y, self.yaw]]))[0]

    def job(self, job: Job) -> Job:
        """Return ``job`` placed: its block moved, and its robot base with it when the robot moves.

        The block moved by :func:`moved_job` and, when the robot moves, its ``[robot] base``
        moved with it (``base @`` :meth:`base_motion`), so the simulation's world keeps the
        block where it stands.
        """
        moved = moved_job(job, self.transform(job))
        if self.move != "robot":
            return moved
        robot = dataclasses.replace(job.robot, base=job.robot.base @ self.base_motion())
        return dataclasses.replace(moved, robot=robot)

    def describe(self) -> str:
        """The placement in words, lengths in mm and the yaw in degrees (for reports).

        Says where the block's centre goes (``move = "stock"``) or how far the robot's base
        moves and turns (``move = "robot"``), and the :attr:`.regions.Turn.label` when turned."""
        turn = "" if self.turn.degrees == 0 else f", after turning it {self.turn.label}"
        if self.move == "stock":
            return (f"block centre at x = {mm(self.x)} mm, y = {mm(self.y)} mm, "
                    f"yaw {np.degrees(self.yaw):+.1f} deg{turn}")  # fmt: skip
        return (f"robot base moved by x = {mm(self.x)} mm, y = {mm(self.y)} mm, "
                f"turned {np.degrees(self.yaw):+.1f} deg{turn}")  # fmt: skip


def transforms_of_base(xyz: FloatArray) -> FloatArray:
    """``Tr(x, y, 0) Rz(yaw)`` (N, 4, 4) of samples ``[x, y, yaw]`` (N, 3)."""
    xyz = np.asarray(xyz, dtype=np.float64).reshape(-1, 3)
    c, s = np.cos(xyz[:, 2]), np.sin(xyz[:, 2])
    M = np.zeros((len(xyz), 4, 4))
    M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1] = c, -s, s, c
    M[:, 2, 2] = M[:, 3, 3] = 1.0
    M[:, 0, 3], M[:, 1, 3] = xyz[:, 0], xyz[:, 1]
    return M


def transforms(job: Job, xyz: FloatArray, move: str, turn: Turn = AS_CLAMPED) -> FloatArray:
    """Rigid motions (N, 4, 4) of samples ``[x, y, yaw]`` (N, 3) (module doc)."""
    M = transforms_of_base(xyz)
    Tt = turn.matrix(job.stock)
    if move == "robot":
        return se3.inverse(M) @ Tt
    centre = Tt[:3, :3] @ job.stock.centre + Tt[:3, 3]
    back = np.eye(4)
    back[:2, 3] = -centre[:2]
    return M @ back @ Tt


def moved_job(job: Job, T: FloatArray) -> Job:
    """The job with its block moved by T (4, 4).

    The stock, every cut's surface pose and keep point (in memory; :mod:`.job_file` writes it)."""
    stock = job.stock.moved(T)
    cuts = []
    for cut in job.cuts:
        keep = cut.keep
        if keep is not None and not isinstance(keep, str):
            keep = T[:3, :3] @ np.asarray(keep) + T[:3, 3]
        surface = dataclasses.replace(cut.surface, pose=T @ cut.surface.pose)
        cuts.append(dataclasses.replace(cut, surface=surface, keep=keep))
    return dataclasses.replace(job, cuts=tuple(cuts), stock=stock)
