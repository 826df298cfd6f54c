"""The clearance rules of the cell: arm, bow and wire against the stock, the table and
each other, for batches of configurations (the planner's own collision model).

The arm is the MuJoCo model's own link geometry as capsules (so the planner and
the simulation agree); the bow rods have the simulated bow's rod radius.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.se3 import transform_points
from ...geometry.segments import segment_distance
from ...robot.arm.model import RobotModel
from ...robot.arm.shape import arm_capsules
from ...robot.tool import BowTool
from ..job.spec import ToolSpec

__all__ = ["ARM_STOCK", "ARM_TABLE", "BOW_ARM", "BOW_STOCK", "BOW_TABLE", "MARGIN", "RULES",
           "SINGULAR_MIN", "Cell", "clearance"]

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
RULES = (BOW_STOCK, ARM_STOCK, BOW_ARM, BOW_TABLE, ARM_TABLE)


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


def clearance(cell: Cell, q: FloatArray, P: FloatArray) -> dict[str, np.ndarray]:
    """Per configuration (...): which clearance rule it breaks (dict of bool arrays).

    ``q`` (..., 6) joints and ``P`` (..., 4, 4) their flange poses.  The arm is the
    MuJoCo model's own link geometry as capsules (:func:`ruledrobot.robot.arm.shape.arm_capsules`:
    housings and tubes, the UR's side offset included), the bow rods have the
    simulated bow's rod radius.  The wire inside the stock is the cut, not a collision.
    """
    model, stock, margin = cell.model, cell.stock, cell.margin
    shape = q.shape[:-1]
    qf = np.nan_to_num(q.reshape(-1, q.shape[-1]))
    Pf = P.reshape(-1, 4, 4)
    rods = np.concatenate([cell.rods, cell.wire[None]], axis=0)  # (4, 2, 3)
    w = transform_points(Pf[:, None], rods)  # (n, 4, 2, 3)
    ends, radius, body = arm_capsules(model, qf)  # (n, S, 2, 3), (S,), (S,)
    n, S = len(qf), len(radius)
    # one batch of segments against the stock, each with its own grown margin: the bow's
    # rods (tubes of the bow's arm radius; the wire is the cut, not a collision), the hub
    # on the flange (a short cylinder, as a capsule) and the arm's capsules
    seg_a, seg_b = [w[:, :3, 0]], [w[:, :3, 1]]
    grow = [np.full(3, margin + BowTool.arm_radius)]
    if cell.hub is not None:
        h = transform_points(Pf, cell.hub)
        seg_a.append(h[:, None, 0])
        seg_b.append(h[:, None, 1])
        grow.append(np.array([margin + cell.hub_radius]))
    seg_a.append(ends[:, :, 0])
    seg_b.append(ends[:, :, 1])
    grow.append(margin + radius)
    hits = stock.segment_hits(np.concatenate(seg_a, axis=1), np.concatenate(seg_b, axis=1),
                              np.concatenate(grow)[:, None])  # (n, segments)  # fmt: skip
    out = {
        BOW_STOCK: hits[:, : hits.shape[1] - S].any(axis=1),
        ARM_STOCK: hits[:, hits.shape[1] - S :].any(axis=1),
        BOW_ARM: np.zeros(n, bool),
        BOW_TABLE: np.zeros(n, bool),
        ARM_TABLE: np.zeros(n, bool),
    }
    near = np.isin(body, _BODIES_NEAR_BOW)
    if near.any():  # the capsules of the links near the bow against its rods and wire
        e = ends[:, near]  # (n, K, 2, 3)
        a, b = e[:, :, None, 0], e[:, :, None, 1]  # (n, K, 1, 3)
        dist = segment_distance(a, b, w[:, None, :, 0], w[:, None, :, 1])  # (n, K, 4)
        reach = radius[near] + BowTool.arm_radius + margin
        out[BOW_ARM] = (dist < reach[None, :, None]).any(axis=(1, 2))
    if cell.table_z is not None:
        out[BOW_TABLE] = (w[:, :3, :, 2] < cell.table_z + margin).any(axis=(1, 2))
        # every link from the shoulder on (the column stands on the base, on the table);
        # a capsule is lowest at an end point
        up = body >= 1
        low = ends[:, up][..., 2].min(axis=2) - radius[up]  # (n, S_up)
        out[ARM_TABLE] = (low < cell.table_z + margin).any(axis=1)
    return {key: v.reshape(shape) for key, v in out.items()}
