"""The hot-wire work cell: the arm on a table, a bow tool on its flange, a block of stock.

Frames: the table, the stock and the camera are given in the **robot base
frame** (DH frame 0, the frame of the trajectory CSV's TCP poses); the
scene places them at ``model.base @ pose`` in the world, like the robot.
The bow is given in the **flange frame**.

Collision classes (``contype`` / ``conaffinity`` bits):

* arm links, base, bow (arms, crossbar, hub), table, stock: ``1 / 3``: every
  pair of them can collide, except static-static pairs (base, table and
  stock never collide with each other), joint neighbours and the excluded
  link pairs of :func:`~ruledrobot.sim.mjcf.robot_mjcf`;
* the wire: ``2 / 0``: it collides with whatever has bit 2 in its affinity --
  the arm, the base and the table -- but **not with the stock**, which it is
  meant to cut (the stock's affinity is ``1``).  The playback reports the wire
  inside the stock separately (:mod:`ruledrobot.sim.playback`);
* floor, table legs, markers: visual only (``0 / 0``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.box import Box
from ..geometry.checks import FloatArray
from ..robot._checks import as_point
from ..robot.arm.model import RobotModel
from ..robot.arm.shape import link_radii
from ..robot.tool import BowSpec, BowTool
from ._xml import placed, sub, to_string
from .mjcf import ServoGains, build_robot

__all__ = [
    "BowTool", "CutJob", "Scene", "default_camera", "default_table", "example_scene",
    "scene_mjcf",
]  # fmt: skip


class _Placed(Protocol):
    @property
    def base(self) -> ArrayLike: ...


class CutJob(Protocol):
    """What :meth:`Scene.from_job` reads of a cut job (``ruledrobot.wirecut.job.spec.Job``).

    ``robot.base`` (4, 4) where the arm stands in the world, ``tool`` the bow's spec, ``stock``
    the block (robot base frame) and ``robot_model()`` the arm."""

    @property
    def robot(self) -> _Placed:
        """The job's ``[robot]``: its ``base`` (4, 4), the pose of the robot base in the world."""
        ...

    @property
    def tool(self) -> BowSpec:
        """The bow's spec (flange frame)."""
        ...

    @property
    def stock(self) -> Box:
        """The block of stock (robot base frame, [m])."""
        ...

    def robot_model(self) -> RobotModel:
        """Return the arm's model (with the job's calibration) in its own base frame.

        ``base`` the identity; :meth:`Scene.from_job` places it at ``robot.base``.
        """
        ...


#: Geom names of the scene's static objects and of the wire.
WIRE_GEOM = "wire"
STOCK_GEOM = "stock"
TABLE_GEOM = "table"

_BOW_RGBA = "0.95 0.55 0.10 1"
_WIRE_RGBA = "0.90 0.05 0.05 1"
_STOCK_RGBA = "0.93 0.88 0.62 0.55"
#: with the part drawn inside it, the stock is the material the cuts remove: fainter
_STOCK_WITH_PART_RGBA = "0.93 0.88 0.62 0.22"
_PART_RGBA = "0.35 0.70 0.40 1"
_TABLE_RGBA = "0.55 0.42 0.30 1"


def default_table(model: RobotModel, stock: Box | None = None, margin: float = 0.25) -> Box:
    """Return a 4 cm table top whose upper face is the base plane (z = 0 of the base frame).

    Covering the robot's footprint and the stock's, with ``margin`` [m] around them (at
    least 1.2 x 0.9 m).
    """
    reach = float(model.reach) if model.reach else float(np.sum(np.abs(model.a)) + 0.3)
    pts = [np.array([-0.2, -0.2]), np.array([0.2, 0.2])]
    if stock is not None:
        xyz = stock.corners
        pts += [xyz[:, :2].min(axis=0), xyz[:, :2].max(axis=0)]
    else:
        pts += [np.array([-0.3 * reach, -0.6 * reach]), np.array([0.8 * reach, 0.6 * reach])]
    lo = np.min(pts, axis=0) - margin
    hi = np.max(pts, axis=0) + margin
    size_xy = np.maximum(hi - lo, [1.2, 0.9])
    centre_xy = 0.5 * (lo + hi)
    return Box(centre=[centre_xy[0], centre_xy[1], -0.02], size=[size_xy[0], size_xy[1], 0.04])


def _look_at(pos: FloatArray, target: FloatArray) -> tuple[FloatArray, FloatArray]:
    """MuJoCo camera ``xyaxes`` (right, up) for a camera at ``pos`` looking at ``target``."""
    f = target - pos
    f = f / np.linalg.norm(f)
    right = np.cross(f, [0.0, 0.0, 1.0])
    if np.linalg.norm(right) < 1e-9:
        right = np.array([1.0, 0.0, 0.0])
    right = right / np.linalg.norm(right)
    up = np.cross(right, f)
    return right, up


def default_camera(model: RobotModel, stock: Box | None = None) -> tuple[FloatArray, FloatArray]:
    """Camera position and target (3,) in the base frame: a three-quarter view of the cell."""
    reach = float(model.reach) if model.reach else float(np.sum(np.abs(model.a)) + 0.3)
    base = np.array([0.0, 0.0, 0.35 * reach])
    if stock is not None:
        target = 0.5 * (base + stock.centre)
        v = np.array([stock.centre[0], stock.centre[1], 0.0])
    else:
        target = base.copy()
        v = np.array([1.0, 0.0, 0.0])
    nv = np.linalg.norm(v)
    v = v / nv if nv > 1e-9 else np.array([1.0, 0.0, 0.0])
    side = np.array([-v[1], v[0], 0.0])
    extent = max(reach, float(np.linalg.norm(target - base)) + 0.5 * reach)
    direction = 0.45 * v - 1.0 * side + 0.55 * np.array([0.0, 0.0, 1.0])
    pos = target + 2.1 * extent * direction / np.linalg.norm(direction)
    return pos, target


@dataclass(frozen=True)
class Scene:
    """Everything :func:`scene_mjcf` needs; ``play`` and the renderers accept it.

    ``robot`` the arm (its ``base`` and ``tool`` included); ``tool`` the bow or
    None; ``stock`` the block (robot base frame) or None; ``table`` a table
    top (robot base frame), ``"auto"`` (:func:`default_table`) or None;
    ``width`` x ``height`` the video resolution (sets the offscreen buffer);
    ``camera`` ``(position, target)`` in the base frame or None
    (:func:`default_camera`); ``part`` the kept part's mesh (``vertices`` (V, 3) m and
    ``faces`` (F, 3) in the base frame, e.g. :func:`ruledrobot.wirecut.report.part_mesh.part_mesh`)
    or None — drawn in green inside a fainter stock, for looking only (no contacts).
    """

    robot: RobotModel
    tool: BowTool | None = None
    stock: Box | None = None
    table: Box | str | None = "auto"
    width: int = 640
    height: int = 480
    camera: tuple[ArrayLike, ArrayLike] | None = field(default=None, repr=False)
    gains: ServoGains | None = field(default=None, repr=False)
    part: Any = field(default=None, repr=False)

    @classmethod
    def from_job(
        cls, job: CutJob, robot: RobotModel | None = None, bow: BowTool | None = None, **kw: Any
    ) -> Scene:
        """The cell of a cut job (:class:`CutJob`: ``ruledrobot.wirecut.job.spec.Job``).

        ``job.robot_model()`` (model, calibration; unless ``robot`` is given) placed at the
        job's ``[robot] base``, the bow of ``job.tool`` (:meth:`BowTool.from_spec`; ``bow``
        when the caller built it already) and ``job.stock`` (in the robot base frame, like
        every pose of a job)."""
        if robot is None:
            robot = job.robot_model()
        robot = robot.with_base(job.robot.base)
        tool = BowTool.from_spec(job.tool) if bow is None else bow
        return cls(robot, tool=tool, stock=job.stock, **kw)

    def mjcf(self) -> str:
        """The MJCF text of the scene (:func:`scene_mjcf`)."""
        return scene_mjcf(
            self.robot,
            tool=self.tool,
            stock=self.stock,
            table=self.table,
            width=self.width,
            height=self.height,
            camera=self.camera,
            gains=self.gains,
            part=self.part,
        )


def _in_base(model: RobotModel, T: FloatArray) -> FloatArray:
    return np.asarray(model.base) @ T


def _block_geom(
    world: ET.Element, model: RobotModel, block: Box, name: str, rgba: str, *, conaffinity: int
) -> ET.Element:
    """A block of the cell (the table, the stock) as a colliding box geom of the world body.

    ``block`` is given in the robot base frame and placed at ``model.base @ block.pose``
    (4, 4); the geom's ``size`` is MuJoCo's half edge lengths [m]; ``contype`` 1 and
    ``conaffinity`` as given (the collision classes of the module doc).
    """
    return placed(world, "geom", _in_base(model, block.pose), name=name, type="box",
                  size=0.5 * block.size, rgba=rgba, contype=1, conaffinity=conaffinity)  # fmt: skip


def scene_mjcf(
    model: RobotModel,
    tool: BowTool | None = None,
    stock: Box | None = None,
    table: Box | str | None = "auto",
    *,
    width: int = 640,
    height: int = 480,
    camera: tuple[ArrayLike, ArrayLike] | None = None,
    gains: ServoGains | None = None,
    floor: bool = True,
    part: Any = None,
) -> str:
    """MJCF text of the work cell: arm on a table, bow tool, stock, lights, camera.

    Parameters
    ----------
    model : the arm (:func:`~ruledrobot.sim.mjcf.robot_mjcf` builds it; its
        ``tool`` is the ``tcp`` site).  With a bow, the bow's mass replaces
        ``model.tool_mass`` (no ``payload`` body).
    tool : the bow on the flange (body ``bow``: hub, ``bow_arm0``,
        ``bow_arm1``, ``bow_bar`` geoms, the ``wire`` geom and the sites
        ``wire_start``, ``wire_end``), or None.
    stock : the block to cut, a :class:`~ruledrobot.geometry.box.Box` in the
        robot base frame (geom ``stock``), or None.
    table : a Box in the base frame (geom ``table``), ``"auto"`` for
        :func:`default_table`, or None.
    width, height : video resolution [px]; the offscreen buffer is made at
        least this large.
    camera : ``(position, target)`` (3,), (3,) in the base frame; default
        :func:`default_camera`.  The camera is named ``cell``.
    gains : servo gains (default :meth:`ServoGains.default`).
    floor : draw a floor 0.75 m below the table top (visual only).

    Render settings are the fast ones: ``offsamples = 0``, no shadows.
    """
    if not isinstance(model, RobotModel):
        raise ValueError(f"model: expected a RobotModel, got {type(model).__name__}")
    if tool is not None and not isinstance(tool, BowTool):
        raise ValueError(f"tool: expected a BowTool or None, got {type(tool).__name__}")
    if stock is not None and not isinstance(stock, Box):
        raise ValueError(f"stock: expected a Box or None, got {type(stock).__name__}")
    for name, v in (("width", width), ("height", height)):
        if not isinstance(v, (int, np.integer)) or v < 16:
            raise ValueError(f"{name}: expected an integer >= 16 (pixels), got {v!r}")
    if isinstance(table, str):
        if table != "auto":
            raise ValueError(f"table: expected a Box, 'auto' or None, got {table!r}")
        table = default_table(model, stock)
    elif table is not None and not isinstance(table, Box):
        raise ValueError(f"table: expected a Box, 'auto' or None, got {type(table).__name__}")

    tree = build_robot(
        model,
        gains=gains,
        armature=None,
        damping=None,
        timestep=None,
        collisions=True,
        payload=tool is None,
        keyframe=True,
        comment_model=f"{model.name}_cell",
        conaffinity=3,
    )
    root = tree.root

    # render settings: fast offscreen, buffer for the video, plain light background
    visual = root.find("visual")
    assert visual is not None
    sub(visual, "global", offwidth=max(int(width), 640), offheight=max(int(height), 480))
    sub(
        visual,
        "headlight",
        ambient="0.35 0.35 0.35",
        diffuse="0.45 0.45 0.45",
        specular="0.1 0.1 0.1",
    )
    asset = ET.Element("asset")
    root.insert(list(root).index(visual) + 1, asset)
    sub(
        asset,
        "texture",
        name="sky",
        type="skybox",
        builtin="gradient",
        rgb1="0.85 0.88 0.92",
        rgb2="0.55 0.60 0.68",
        width=64,
        height=64,
    )
    # a plain floor: a checker texture costs ~20 % of the frame rate on llvmpipe
    sub(asset, "material", name="floor", rgba="0.60 0.61 0.63 1", reflectance=0.0)

    world = tree.worldbody
    reach = float(model.reach) if model.reach else float(np.sum(np.abs(model.a)) + 0.3)
    base_T = np.asarray(model.base)
    light_pos = base_T @ np.array([0.3 * reach, -0.6 * reach, 3.0 * reach + 1.0, 1.0])
    sub(
        world,
        "light",
        name="key",
        pos=light_pos[:3],
        dir=base_T[:3, :3] @ [-0.2, 0.3, -1.0],
        directional=True,
        castshadow=False,
        diffuse="0.6 0.6 0.6",
        specular="0.2 0.2 0.2",
    )

    if table is not None:
        _block_geom(world, model, table, TABLE_GEOM, _TABLE_RGBA, conaffinity=3)
        top = table.centre[2] - 0.5 * table.size[2]
        legs_h = 0.71
        half = 0.5 * table.size
        for j, (sx, sy) in enumerate(((-1, -1), (-1, 1), (1, -1), (1, 1))):
            corner = (
                table.rotation
                @ np.array([sx * (half[0] - 0.05), sy * (half[1] - 0.05), -half[2] - 0.5 * legs_h])
                + table.centre
            )
            T = np.eye(4)
            T[:3, :3] = table.rotation
            T[:3, 3] = corner
            placed(
                world,
                "geom",
                _in_base(model, T),
                name=f"table_leg{j}",
                type="box",
                size=[0.03, 0.03, 0.5 * legs_h],
                rgba=_TABLE_RGBA,
                contype=0,
                conaffinity=0,
            )
        floor_at = [table.centre[0], table.centre[1], top - legs_h]  # under the legs
    else:
        floor_at = [0.0, 0.0, -0.001]
    if floor:
        T = np.eye(4)
        T[:3, 3] = floor_at
        placed(
            world,
            "geom",
            _in_base(model, T),
            name="floor",
            type="plane",
            size=[4 * reach, 4 * reach, 0.05],
            material="floor",
            contype=0,
            conaffinity=0,
        )

    if stock is not None:
        rgba = _STOCK_RGBA if part is None else _STOCK_WITH_PART_RGBA
        _block_geom(world, model, stock, STOCK_GEOM, rgba, conaffinity=1)
    if part is not None and len(part.faces):
        v = np.asarray(part.vertices, dtype=np.float64)
        f = np.asarray(part.faces, dtype=np.int64)
        sub(asset, "mesh", name="part", vertex=" ".join(f"{x:.6g}" for x in v.ravel()),
            face=" ".join(str(int(i)) for i in f.ravel()))  # fmt: skip
        placed(world, "geom", _in_base(model, np.eye(4)), name="part", type="mesh", mesh="part",
               rgba=_PART_RGBA, contype=0, conaffinity=0, group=1)  # fmt: skip

    if tool is not None:
        bow = placed(tree.last_body, "body", tree.flange, name="bow", gravcomp=1)
        com, inertia = tool.inertia()
        if tool.mass > 0.0:
            sub(
                bow,
                "inertial",
                pos=com,
                mass=tool.mass,
                fullinertia=[
                    inertia[0, 0],
                    inertia[1, 1],
                    inertia[2, 2],
                    inertia[0, 1],
                    inertia[0, 2],
                    inertia[1, 2],
                ],
            )
        flange_r = float(link_radii(model)[-1])
        sub(
            bow,
            "geom",
            name="bow_hub",
            type="cylinder",
            size=min(tool.hub_radius, flange_r),
            fromto=[0.0, 0.0, 0.0, 0.0, 0.0, tool.hub_length],
            rgba=_BOW_RGBA,
            mass=0,
        )
        seg = tool.segments()
        for name, (p0, p1) in zip(("bow_arm0", "bow_arm1", "bow_bar"), seg, strict=True):
            if np.linalg.norm(p1 - p0) > 1e-9:
                sub(
                    bow,
                    "geom",
                    name=name,
                    type="capsule",
                    size=tool.arm_radius,
                    fromto=np.concatenate([p0, p1]),
                    rgba=_BOW_RGBA,
                    mass=0,
                )
        wire = np.concatenate([tool.wire_start, tool.wire_end])
        # the wire as it is (contacts; hidden group 3) and as it is drawn (visible, thicker)
        sub(
            bow,
            "geom",
            name=WIRE_GEOM,
            type="capsule",
            size=tool.wire_radius,
            fromto=wire,
            rgba=_WIRE_RGBA,
            contype=2,
            conaffinity=0,
            mass=0,
            group=3,
        )
        sub(
            bow,
            "geom",
            name="wire_visual",
            type="capsule",
            size=max(tool.wire_radius, 0.0015),
            fromto=wire,
            rgba=_WIRE_RGBA,
            contype=0,
            conaffinity=0,
            mass=0,
        )
        for name, p in (("wire_start", tool.wire_start), ("wire_end", tool.wire_end)):
            sub(bow, "site", name=name, pos=p, size=2.5 * tool.wire_radius + 0.002, rgba=_WIRE_RGBA)

    pos, target = (
        default_camera(model, stock)
        if camera is None
        else (as_point(camera[0], "camera position"), as_point(camera[1], "camera target"))
    )
    if np.linalg.norm(np.asarray(target) - np.asarray(pos)) < 1e-9:
        raise ValueError("camera: position and target must differ")
    pw = (base_T @ np.append(pos, 1.0))[:3]
    tw = (base_T @ np.append(target, 1.0))[:3]
    right, up = _look_at(pw, tw)
    sub(world, "camera", name="cell", pos=pw, xyaxes=np.concatenate([right, up]), fovy=45)
    comment = (
        f"{model.name} hot-wire cell: generated by ruledrobot.sim.scene.scene_mjcf; "
        "robot base frame = DH frame 0"
    )
    return to_string(root, comment)


def example_scene() -> Scene:
    """The example cell of ``models/ur5e_hotwire_cell.xml``.

    A UR5e with a 400 mm bow (wire from ``(-0.2, 0, 0.25)`` to ``(0.2, 0, 0.25)`` in the flange
    frame, 1 kg) and a 200 mm foam cube on the table, centred at ``(0.5, 0, 0.1)`` in the base
    frame."""
    from ..robot import load

    return Scene(
        load("ur5e"),
        tool=BowTool([-0.2, 0.0, 0.25], [0.2, 0.0, 0.25]),
        stock=Box(centre=[0.5, 0.0, 0.1], size=[0.2, 0.2, 0.2]),
    )
