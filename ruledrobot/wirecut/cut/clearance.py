"""The clearance rules of the cell: arm, bow and wire against the stock, the table and
each other, for batches of configurations (the planner's own collision model).

The arm is the MuJoCo model's own link geometry as capsules (so the planner and
the simulation agree); the bow rods have the simulated bow's rod radius.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...geometry.box import Box
from ...geometry.checks import FloatArray
from ...geometry.segments import segment_distance
from ...robot.arm.shape import arm_capsules
from ...robot.tool import BowTool
from ..job.spec import ToolSpec
from .wire_geometry import wire_frame

__all__ = ["Cell", "clearance"]


#: link bodies checked against the bow and the wire: the upper arm, the forearm and
#: wrist 1 (bodies 1-3); wrists 2 and 3 carry the bow's hub.
_BODIES_NEAR_BOW = (1, 2, 3)


@dataclass(frozen=True)
class Cell:
    """The fixed setting of a search: robot, bow and wire, stock, table, thresholds."""

    model: object
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

    @classmethod
    def of(cls, model, tool: ToolSpec, stock: Box, table_z, margin, singular_min, q_start):
        bow = BowTool.from_spec(tool)
        wire = np.array([bow.wire_start, bow.wire_end])
        hub = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, bow.hub_length]])
        return cls(model, wire_frame(tool), bow.segments(), wire, stock, table_z, margin,
                   singular_min, q_start, hub, bow.hub_radius)  # fmt: skip


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
    w = np.einsum("nij,kej->nkei", Pf[:, :3, :3], rods) + Pf[:, None, None, :3, 3]
    ends, radius, body = arm_capsules(model, qf)  # (n, S, 2, 3), (S,), (S,)
    n = len(qf)
    # the rods are tubes of the bow's arm radius; the wire is the cut, not a collision
    bow_in_stock = stock.segment_hits(w[:, :3, 0], w[:, :3, 1],
                                      margin + BowTool.arm_radius).any(axis=1)  # fmt: skip
    if cell.hub is not None:  # the hub on the flange: a short cylinder, as a capsule
        h = np.einsum("nij,ej->nei", Pf[:, :3, :3], cell.hub) + Pf[:, None, :3, 3]
        bow_in_stock |= stock.segment_hits(h[:, 0], h[:, 1], margin + cell.hub_radius)
    out = {
        "bow hits the stock": bow_in_stock,
        "arm hits the stock": np.zeros(n, bool),
        "bow or wire hits the arm": np.zeros(n, bool),
        "bow below the table": np.zeros(n, bool),
        "arm below the table": np.zeros(n, bool),
    }
    for k in range(len(radius)):
        a, b = ends[:, k, 0], ends[:, k, 1]
        out["arm hits the stock"] |= stock.segment_hits(a, b, margin + radius[k])
        if body[k] in _BODIES_NEAR_BOW:
            dist = segment_distance(a[:, None], b[:, None], w[:, :, 0], w[:, :, 1])
            out["bow or wire hits the arm"] |= (
                dist < radius[k] + BowTool.arm_radius + margin
            ).any(axis=1)
    if cell.table_z is not None:
        out["bow below the table"] = (w[:, :3, :, 2] < cell.table_z + margin).any(axis=(1, 2))
        # every link from the shoulder on (the column stands on the base, on the table);
        # a capsule is lowest at an end point
        up = body >= 1
        low = ends[:, up][..., 2].min(axis=2) - radius[up]  # (n, S_up)
        out["arm below the table"] = (low < cell.table_z + margin).any(axis=1)
    return {key: v.reshape(shape) for key, v in out.items()}
