"""The clearance rules of the cell: arm, bow and wire against the stock, the table and
each other, for batches of configurations (the planner's own collision model).

The arm is the MuJoCo model's own link geometry as capsules (so the planner and
the simulation agree); the bow rods have the simulated bow's rod radius.
:func:`clearance` poses the bodies at the configurations (:class:`Posed`: the arm's
forward kinematics, the bow carried by the flange poses) and judges the rules on them
(:func:`broken`); a caller that judges one batch at several margins (the reach map's
margin ladder) poses it once and calls :func:`broken` per margin.

**The arm against itself** (:data:`ARM_ARM`, on in a cell with ``self_collision``: the
transits') tests every pair of capsules of link bodies that MuJoCo lets touch
(:func:`self_pairs`, 32 pairs on a UR): the robot's base (a static capsule, the MuJoCo
``base`` geom, :func:`base_capsule`) and the links 1-6 (bodies 0-5 of
:func:`~ruledrobot.robot.arm.shape.arm_capsules`), less

* the capsules of one body, and of joint neighbours (k, k + 1): MuJoCo skips a body and
  its parent, and every neighbour pair has capsules that overlap at every configuration;
* the pairs the MuJoCo model excludes (:func:`ruledrobot.sim.mjcf.build_robot`): the base
  with links 1 and 2 — they too overlap at every configuration — and on UR arms link 3
  with link 5 and link 4 with link 6 (bodies 2-4, 3-5: their capsules never come nearer
  than 9.5 mm on any catalogue arm, 38.9 and 14.6 mm on the UR5e); on other arms every
  pair two bodies apart.

Measured over 20,000 random configurations of every catalogue arm (margin 5 mm): the
pairs that overlap at every configuration are exactly the neighbours' and the base's
with links 1 and 2 (on the UR5e at least 137, 58 (base-link2), 130, 117, 94, 77 and 77
mm deep); every pair tested is clear at some configuration (by 50 mm or more).  The bow
(its rods, the wire, the hub) is tested against every link but the flange's own (link 6,
its parent in MuJoCo) and against the base: the hub keeps 30.6 mm from the wrist-2 link
of the UR5e at any configuration, the demo bow's rods 49 mm.  Over 20,000 random
configurations of the demo's cell every contact MuJoCo finds between two links, a link
and the base, or the bow and a link is one of these rules' (4,055 and 6,949
configurations; the rules flag 1,053 and 950 more: the margin, and capsules for MuJoCo's
cylinders).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Collection
from dataclasses import dataclass, field

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.se3 import transform_points
from ...geometry.segments import segment_distance
from ...robot.arm.model import RobotModel
from ...robot.arm.shape import arm_capsules, link_radii, link_segments
from ...robot.tool import BowTool
from ..job.spec import ToolSpec

__all__ = ["ARM_ARM", "ARM_STOCK", "ARM_TABLE", "BOW_ARM", "BOW_STOCK", "BOW_TABLE", "MARGIN",
           "RULES", "SINGULAR_MIN", "Cell", "Posed", "base_capsule", "broken", "clearance",
           "self_pairs"]

#: the planner's thresholds, one home for the wire-pose search (:mod:`.wire_pose`), the
#: transits, the reach map's rules (:class:`ruledrobot.wirecut.reach.margins.Rules`) and
#: the verdict's singularity check: the clearance [m] of bow and arm from the stock, the
#: table and each other, and the least singularity measure of a configuration
MARGIN = 0.005
SINGULAR_MIN = 0.02

#: the clearance rules by name: the keys of :func:`clearance`'s answer, in its order
#: (the reach map's reasons and the placement search read these names)
BOW_STOCK = "bow hits the stock"
ARM_STOCK = "arm hits the stock"
BOW_ARM = "bow or wire hits the arm"
BOW_TABLE = "bow below the table"
ARM_TABLE = "arm below the table"
#: the arm against itself: only in a cell with ``self_collision`` (the transits'; module doc)
ARM_ARM = "arm hits the arm"
RULES = (BOW_STOCK, ARM_STOCK, BOW_ARM, BOW_TABLE, ARM_TABLE, ARM_ARM)


#: link bodies checked against the bow and the wire: the upper arm, the forearm and
#: wrist 1 (bodies 1-3); wrists 2 and 3 carry the bow's hub.
_BODIES_NEAR_BOW = (1, 2, 3)


@dataclass(frozen=True)
class Cell:
    """The fixed setting of a search: robot, bow and wire, stock, table, thresholds.

    Built once per plan (:meth:`of`, :meth:`~.wire_pose.SearchOptions.cell`) and passed
    down: the passes' search, the transits (:meth:`with_rules`) and the timing read
    its ``bow``."""

    model: RobotModel
    W: FloatArray  # wire frame in the flange frame
    rods: FloatArray  # (3, 2, 3) bow rods in the flange frame
    wire: FloatArray  # (2, 3) wire ends in the flange frame
    stock: Box
    table_z: float | None
    margin: float
    singular_min: float
    q_start: FloatArray | None
    hub: FloatArray | None = None  # (2, 3) the hub's axis in the flange frame
    hub_radius: float = 0.0
    bow: BowTool | None = field(default=None, repr=False)
    #: test the arm against itself (:data:`ARM_ARM`) and the bow against every link but
    #: the flange's (module doc); off: the bow against the upper arm, forearm, wrist 1
    self_collision: bool = False

    @functools.cached_property
    def touch(self) -> _Touch:
        """Return the capsule pairs of the arm with itself and with the bow, built on first use.

        The pairs the ``self_collision`` rule tests.
        """
        return _touch_pairs(self)

    @classmethod
    def of(
        cls, model: RobotModel, tool: ToolSpec | BowTool, stock: Box, table_z: float | None,
        margin: float, singular_min: float, q_start: FloatArray | None,
    ) -> Cell:
        """The cell of ``model`` with the bow of ``tool`` (a spec, or the bow built once)."""
        bow = BowTool.of(tool)
        wire = np.array([bow.wire_start, bow.wire_end])
        hub = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, bow.hub_length]])
        return cls(model, bow.wire_frame(), bow.segments(), wire, stock, table_z, margin,
                   singular_min, q_start, hub, bow.hub_radius, bow)  # fmt: skip

    def with_rules(
        self, table_z: float | None, margin: float, singular_min: float,
        q_start: FloatArray | None,
    ) -> Cell:
        """The same robot, bow and stock under other thresholds (no bow built again)."""
        return dataclasses.replace(self, table_z=table_z, margin=margin,
                                   singular_min=singular_min, q_start=q_start)  # fmt: skip


def base_capsule(model: RobotModel) -> tuple[FloatArray, float]:
    """The robot's base as a capsule.

    Its axis (2, 3) [m] in the robot base frame and its radius [m] — the MuJoCo ``base`` geom
    (:func:`ruledrobot.sim.mjcf.build_robot`: a cylinder of 1.15 shoulder-housing radii from
    the base plane up to the column)."""
    nom = model.nominal
    _, base_h = link_segments(nom)
    z = (0.0, base_h) if nom.d[0] >= 0.0 else (-base_h, 0.0)
    axis = transform_points(np.asarray(nom.base), np.array([[0.0, 0.0, z[0]], [0.0, 0.0, z[1]]]))
    return axis, 1.15 * float(link_radii(nom)[0])


def _excluded(model: RobotModel) -> set[tuple[int, int]]:
    """Body pairs (i <= j) never tested against each other (module doc); -1 is the base."""
    J = model.n_joints
    out = {(i, j) for i in range(-1, J) for j in range(i, min(i + 2, J))}  # itself, neighbours
    if model.has_analytic_ik:  # the MuJoCo model's exclusions (sim.mjcf.build_robot)
        out |= {(-1, 1), (2, 4), (3, 5)}
    else:
        out |= {(i, i + 2) for i in range(-1, J - 2)}
    return out


def self_pairs(model: RobotModel, body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the capsule pairs (I, J) (P,) the arm's self-collision rule tests.

    Indices into the capsules ``body`` (S,) (the body of each, -1 the base): the pairs are
    those of bodies MuJoCo lets touch (module doc).
    """
    I, J = np.triu_indices(len(body), 1)
    excluded = _excluded(model)
    keep = np.array([(min(a, b), max(a, b)) not in excluded
                     for a, b in zip(body[I].tolist(), body[J].tolist(), strict=True)],
                    dtype=bool).reshape(-1)  # fmt: skip
    return I[keep], J[keep]


@dataclass(frozen=True, eq=False)
class _Touch:
    """The capsule pairs of a ``self_collision`` cell, built once per cell.

    The capsules are stacked as the base, the arm's ``S`` (:func:`arm_capsules`) and the
    tool's (rods, wire, hub); ``I``, ``J`` (P,) index pairs of them, ``radii`` (P,) [m]
    the sum of their radii (the distance their axes must keep, less the margin: the touch
    holds at any margin), ``bow`` (P,) the pairs of
    the bow with a link (the others: the arm with itself), ``half`` (C,) [m] each rigid
    capsule's half length (a bound for the broad phase)."""

    base: FloatArray  # (2, 3) the base's axis, robot base frame
    I: np.ndarray
    J: np.ndarray
    radii: FloatArray
    bow: np.ndarray
    half: FloatArray


def _touch_pairs(cell: Cell) -> _Touch:
    """The pairs (:class:`_Touch`) of the cell's arm with itself and with the bow."""
    model = cell.model
    axis, r0 = base_capsule(model)
    ends, radius, body = arm_capsules(model, np.zeros(model.n_joints))
    tool = np.concatenate([cell.rods, cell.wire[None]], axis=0)
    tool_r = np.full(len(tool), BowTool.arm_radius)
    if cell.hub is not None:
        tool = np.concatenate([tool, cell.hub[None]], axis=0)
        tool_r = np.r_[tool_r, cell.hub_radius]
    J = model.n_joints
    body_all = np.r_[-1, body, np.full(len(tool), J)]  # J: the tool, on the flange's body
    r = np.r_[r0, radius, tool_r]
    segs = np.concatenate([axis[None], ends, tool], axis=0)  # (C, 2, 3), rigid lengths
    a, b = self_pairs(model, np.r_[-1, body])
    ta, tb = np.nonzero((body_all[:, None] < J - 1) & (body_all[None, :] == J))
    I, Jp = np.r_[a, ta], np.r_[b, tb]
    bow = np.r_[np.zeros(len(a), bool), np.ones(len(ta), bool)]
    half = 0.5 * np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1)
    return _Touch(axis, I, Jp, r[I] + r[Jp], bow, half)


def _touching(
    cell: Cell, margin: float, w: FloatArray, hub: FloatArray | None, ends: FloatArray
) -> tuple[np.ndarray, np.ndarray]:
    """At ``margin`` [m]: (n,) the bow (rods and wire ``w`` (n, 4, 2, 3), ``hub`` (n, 2,
    3)) touches a link other than the flange's or the base (:data:`BOW_ARM`), and (n,) the
    arm's capsules ``ends`` (n, S, 2, 3) touch each other or the base (:data:`ARM_ARM`),
    for a ``self_collision`` cell.  The compiled kernel
    (:func:`ruledrobot.geometry._collide_kernel.pairs_within`): a broad phase of bounding
    spheres and the exact distance of the axes of the pairs it keeps."""
    from ...geometry._collide_kernel import pairs_within

    t = cell.touch
    n = len(ends)
    parts = [np.broadcast_to(t.base, (n, 1, 2, 3)), ends, w]
    if hub is not None:
        parts.append(hub[:, None])
    E = np.ascontiguousarray(np.concatenate(parts, axis=1))  # (n, C, 2, 3)
    out = np.zeros((n, 2), dtype=bool)
    pairs_within(E, t.I, t.J, t.radii + margin, t.half, t.bow, out)
    return out[:, 1], out[:, 0]


@dataclass(frozen=True, eq=False)
class Posed:
    """The cell's bodies at ``n`` configurations: what the clearance rules measure.

    Everything the rules read that a margin or a stock does not change — the forward
    kinematics of the arm's capsules and the bow carried by the flange poses — computed
    once (:meth:`of`) and judged at any margin and stock by :func:`broken` (the reach
    map's margin ladder, :func:`ruledrobot.wirecut.reach.margins.clearance_margins`, judges
    one batch at several levels).  Indexing (``posed[idx]``, an index or mask array over
    the configurations) takes a subset.  Robot base frame, metres.
    """

    w: FloatArray  # (n, 4, 2, 3) the bow's three rods and the wire (the last)
    hub: FloatArray | None  # (n, 2, 3) the hub's axis; None: a cell with no hub
    ends: FloatArray  # (n, S, 2, 3) the arm's capsules' axes (arm_capsules)
    radius: FloatArray  # (S,) their radii [m]
    body: np.ndarray  # (S,) the link body of each (0: the column over the base)

    @classmethod
    def of(cls, cell: Cell, q: FloatArray, P: FloatArray) -> Posed:
        """Return the bodies of ``cell`` posed at configurations, flattened to ``n``.

        Joints ``q`` (..., 6) (NaN read as 0) with their flange poses ``P`` (..., 4, 4).
        """
        qf = np.nan_to_num(q.reshape(-1, q.shape[-1]))
        Pf = P.reshape(-1, 4, 4)
        rods = np.concatenate([cell.rods, cell.wire[None]], axis=0)  # (4, 2, 3)
        hub = None if cell.hub is None else transform_points(Pf, cell.hub)
        ends, radius, body = arm_capsules(cell.model, qf)  # (n, S, 2, 3), (S,), (S,)
        return cls(transform_points(Pf[:, None], rods), hub, ends, radius, body)

    def __len__(self) -> int:
        return len(self.ends)

    def __getitem__(self, idx: np.ndarray) -> Posed:
        """The configurations ``idx`` (an index or mask array)."""
        return dataclasses.replace(self, w=self.w[idx], ends=self.ends[idx],
                                   hub=None if self.hub is None else self.hub[idx])  # fmt: skip


def clearance(cell: Cell, q: FloatArray, P: FloatArray) -> dict[str, np.ndarray]:
    """Per configuration (...): which clearance rule it breaks (dict of bool arrays).

    ``q`` (..., 6) joints and ``P`` (..., 4, 4) their flange poses: the cell's bodies there
    (:meth:`Posed.of`) judged by the rules at the cell's margin (:func:`broken`).
    """
    out = broken(cell, Posed.of(cell, q, P))
    return {key: v.reshape(q.shape[:-1]) for key, v in out.items()}


def broken(
    cell: Cell, at: Posed, margin: float | None = None, stock: Box | None = None,
    only: Collection[str] = RULES,
) -> dict[str, np.ndarray]:
    """Per configuration (n,): which clearance rule the bodies ``at`` break (bool arrays).

    At ``margin`` [m] against ``stock`` (a :class:`~ruledrobot.geometry.box.Box` or one
    box per configuration, :class:`~ruledrobot.wirecut.reach.grid.RowBoxes`), the cell's
    by default; the rules named in ``only`` (default all; keys in :data:`RULES`' order).
    The arm is the MuJoCo model's own link geometry as capsules
    (:func:`ruledrobot.robot.arm.shape.arm_capsules`: housings and tubes, the UR's side
    offset included), the bow rods have the simulated bow's rod radius.  The wire inside
    the stock is the cut, not a collision.  A cell with ``self_collision`` adds
    :data:`ARM_ARM` (the arm against itself) and tests the bow against every link but the
    flange's and the base (module doc).
    """
    margin = cell.margin if margin is None else margin
    stock = cell.stock if stock is None else stock
    w, h, ends, radius, body = at.w, at.hub, at.ends, at.radius, at.body
    n, S = len(at), len(radius)
    out = {key: np.zeros(n, bool) for key in RULES
           if key in only and (key != ARM_ARM or cell.self_collision)}  # fmt: skip
    # one batch of segments against the stock, each with its own grown margin: the bow's
    # rods (tubes of the bow's arm radius; the wire is the cut, not a collision), the hub
    # on the flange (a short cylinder, as a capsule) and the arm's capsules
    seg_a, seg_b, grow = [], [], []
    if BOW_STOCK in out:
        seg_a.append(w[:, :3, 0])
        seg_b.append(w[:, :3, 1])
        grow.append(np.full(3, margin + BowTool.arm_radius))
        if h is not None:
            seg_a.append(h[:, None, 0])
            seg_b.append(h[:, None, 1])
            grow.append(np.array([margin + cell.hub_radius]))
    if ARM_STOCK in out:
        seg_a.append(ends[:, :, 0])
        seg_b.append(ends[:, :, 1])
        grow.append(margin + radius)
    if seg_a:
        hits = stock.segment_hits(np.concatenate(seg_a, axis=1), np.concatenate(seg_b, axis=1),
                                  np.concatenate(grow)[:, None])  # (n, segments)  # fmt: skip
        n_bow = hits.shape[1] - S if ARM_STOCK in out else hits.shape[1]
        if BOW_STOCK in out:
            out[BOW_STOCK] = hits[:, :n_bow].any(axis=1)
        if ARM_STOCK in out:
            out[ARM_STOCK] = hits[:, n_bow:].any(axis=1)
    if cell.self_collision and (BOW_ARM in out or ARM_ARM in out):
        bow_arm, arm_arm = _touching(cell, margin, w, h, ends)
        out.update({k: v for k, v in ((BOW_ARM, bow_arm), (ARM_ARM, arm_arm)) if k in out})
    elif BOW_ARM in out:
        near = np.isin(body, _BODIES_NEAR_BOW)
        if near.any():  # the capsules of the links near the bow against its rods and wire
            e = ends[:, near]  # (n, K, 2, 3)
            a, b = e[:, :, None, 0], e[:, :, None, 1]  # (n, K, 1, 3)
            dist = segment_distance(a, b, w[:, None, :, 0], w[:, None, :, 1])  # (n, K, 4)
            reach = radius[near] + BowTool.arm_radius + margin
            out[BOW_ARM] = (dist < reach[None, :, None]).any(axis=(1, 2))
    if cell.table_z is not None and BOW_TABLE in out:
        # the rods are capsules of the bow's arm radius in MuJoCo: lowest at an end point
        # less the radius; the hub is a cylinder: lowest on an end's rim, r sqrt(1 - a_z^2)
        # below the end's centre (a: its unit axis)
        low = w[:, :3, :, 2].min(axis=(1, 2)) - BowTool.arm_radius
        if h is not None:
            a_z = (h[:, 1, 2] - h[:, 0, 2]) / np.linalg.norm(h[:, 1] - h[:, 0], axis=1)
            rim = cell.hub_radius * np.sqrt(np.clip(1.0 - a_z**2, 0.0, None))
            low = np.minimum(low, h[:, :, 2].min(axis=1) - rim)
        out[BOW_TABLE] = low < cell.table_z + margin
    if cell.table_z is not None and ARM_TABLE in out:
        # every link from the shoulder on (the column stands on the base, on the table);
        # a capsule is lowest at an end point
        up = body >= 1
        low = ends[:, up][..., 2].min(axis=2) - radius[up]  # (n, S_up)
        out[ARM_TABLE] = (low < cell.table_z + margin).any(axis=1)
    return out
