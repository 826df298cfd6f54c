"""The robot model: a standard-DH serial arm with limits, masses, base and tool.

A :class:`RobotModel` is immutable.  The catalogue (:func:`ruledrobot.robot.load`)
builds the Universal Robots arms; :meth:`RobotModel.from_dh` builds any other
arm from its DH table.  :meth:`~RobotModel.with_tool`, :meth:`~RobotModel.with_base`
and :meth:`~RobotModel.with_limits` return modified copies.

Frames (see ``docs/robot.md``):

* **world**: the frame the user's poses live in.  ``base`` is the pose of the
  robot base frame (DH frame 0, the UR controller's ``base``) in the world;
  identity by default, so world = robot base.
* **flange**: DH frame n (the UR ``tool0`` / tool flange frame).
* **TCP**: ``tool`` is the pose of the tool centre point in the flange frame
  (UR's "TCP offset"); identity by default, so TCP = flange.

``fk`` maps joints to TCP poses in the world, ``ik`` and ``path_ik`` map TCP
poses in the world to joints: ``T_world_tcp = base @ A_1 ... A_n @ tool``.

A catalogue arm can carry its factory calibration
(:meth:`RobotModel.with_calibration`, ``load(name, calibration=...)``): its DH
columns are then the controller's *effective* values, FK is exact for that robot,
and ``ik`` refines the nominal closed form on the calibrated chain
(:mod:`ruledrobot.robot.ik.calibrated`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ...geometry import se3
from .._checks import (
    FloatArray,
    as_array,
    as_joint_vector,
    as_pose_or_vector,
    readonly,
)
from ..ik import analytic as _ik
from ..ik.path import LIMIT_TOL
from .calibration import Calibration
from .inverse import InverseKinematics
from .kinematics import DHChain
from .ur_tables import nominal_dh

#: Default joint acceleration limit [rad/s^2].  UR publishes none; this is the
#: URScript ``movej`` default acceleration (``a=1.4``), a conservative value
#: every UR arm reaches on every joint.  Override with ``with_limits``.
DEFAULT_ACCELERATION = 1.4

_UR_ALPHA = np.array([np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0])


def _identity() -> FloatArray:
    return readonly(np.eye(4))


@dataclass(frozen=True, eq=False, kw_only=True)
class RobotModel(InverseKinematics):
    """A serial arm in standard DH form, with limits, masses, base and tool.

    All arrays are float64, read-only; ``J`` is the number of joints (6 for
    the analytic IK).  Units: m, rad, s, kg, N m.

    Attributes
    ----------
    name : model name (``"ur5e"``, ``"custom"``, ...).
    d, a, alpha : (J,) standard-DH parameters; ``A_i = Rz(q_i + theta_offset_i)
        Tz(d_i) Tx(a_i) Rx(alpha_i)`` (UR convention: all offsets 0).
    theta_offset : (J,) joint zero offsets [rad].
    lower, upper : (J,) joint position limits [rad] (``+-inf`` = unlimited).
    max_velocity : (J,) joint speed limits [rad/s].
    max_acceleration : (J,) joint acceleration limits [rad/s^2] (UR publishes
        none; catalogue default :data:`DEFAULT_ACCELERATION`).
    max_torque : (J,) joint torque limits [N m].
    link_mass : (J,) link masses [kg] (link i moves with joint i).
    link_com : (J, 3) centre of mass of link i in DH frame i [m].
    control_period : controller period [s] (0.002 e-Series, 0.008 CB3).
    base : (4, 4) pose of the robot base (DH frame 0) in the world frame.
    tool : (4, 4) pose of the TCP in the flange frame (DH frame J).
    tool_mass : mass of the tool [kg]; tool_com : (3,) its centre of mass in
        the flange frame [m].
    payload : rated payload [kg] (datasheet), or None.
    reach : nominal reach [m] (datasheet), or None.
    calibration : the robot's factory calibration (:class:`~ruledrobot.robot.Calibration`),
        or None for the nominal arm.  When set, ``theta_offset, a, d, alpha`` are its
        effective values (use :meth:`with_calibration`; a table that differs from the
        calibration's is refused) and :attr:`nominal` is the arm without it.
    """

    name: str
    d: FloatArray
    a: FloatArray
    alpha: FloatArray
    theta_offset: FloatArray
    lower: FloatArray
    upper: FloatArray
    max_velocity: FloatArray
    max_acceleration: FloatArray
    max_torque: FloatArray
    link_mass: FloatArray
    link_com: FloatArray
    control_period: float
    base: FloatArray = field(default_factory=_identity)
    tool: FloatArray = field(default_factory=_identity)
    tool_mass: float = 0.0
    tool_com: FloatArray = field(default_factory=lambda: readonly(np.zeros(3)))
    payload: float | None = None
    reach: float | None = None
    calibration: Calibration | None = None

    # derived, filled in __post_init__
    _ur: _ik.URGeometry | None = field(init=False, repr=False, default=None)
    _ur_problem: str = field(init=False, repr=False, default="")
    _base_inv: FloatArray | None = field(init=False, repr=False, default=None)
    _tool_inv: FloatArray | None = field(init=False, repr=False, default=None)
    # the table the closed form seeds from (nominal for a calibrated arm): d, a, alpha, offset
    _seed_dh: tuple[FloatArray, ...] = field(init=False, repr=False, default=())
    _refine: bool = field(init=False, repr=False, default=False)  # calibrated: Newton finish

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name: expected a non-empty string, got {self.name!r}")
        d = np.asarray(self.d)
        if d.ndim != 1 or d.shape[0] < 1:
            raise ValueError(f"d: expected a 1-D DH column with one entry per joint, got {d.shape}")
        n = d.shape[0]
        put = object.__setattr__
        for f in ("d", "a", "alpha", "theta_offset"):
            put(self, f, readonly(as_joint_vector(getattr(self, f), f, n)))
        lower = as_joint_vector(self.lower, "lower", n, allow_inf=True)
        upper = as_joint_vector(self.upper, "upper", n, allow_inf=True)
        bad = ~(lower < upper)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"lower[{i}] = {lower[i]:g} must be below upper[{i}] = {upper[i]:g}")
        put(self, "lower", readonly(lower))
        put(self, "upper", readonly(upper))
        for f, allow_inf in (
            ("max_velocity", False),
            ("max_acceleration", False),
            ("max_torque", True),
        ):
            v = as_joint_vector(getattr(self, f), f, n, allow_inf=allow_inf)
            if np.any(v <= 0.0):
                raise ValueError(f"{f}[{int(np.argmax(v <= 0.0))}]: must be positive")
            put(self, f, readonly(v))
        mass = as_joint_vector(self.link_mass, "link_mass", n)
        if np.any(mass < 0.0):
            raise ValueError(f"link_mass[{int(np.argmax(mass < 0.0))}]: must be >= 0")
        put(self, "link_mass", readonly(mass))
        com = as_array(self.link_com, "link_com")
        com = as_array(np.broadcast_to(com, (n, 3)) if com.ndim < 2 else com, "link_com", (3,))
        if com.shape != (n, 3):
            raise ValueError(f"link_com: expected shape ({n}, 3), got {com.shape}")
        put(self, "link_com", readonly(com))
        period = float(as_array(self.control_period, "control_period"))
        if not period > 0.0:
            raise ValueError(f"control_period: must be positive, got {period}")
        put(self, "control_period", period)
        put(self, "base", readonly(as_pose_or_vector(self.base, "base")))
        put(self, "tool", readonly(as_pose_or_vector(self.tool, "tool")))
        tool_mass = float(as_array(self.tool_mass, "tool_mass"))
        if tool_mass < 0.0:
            raise ValueError(f"tool_mass: must be >= 0, got {tool_mass}")
        put(self, "tool_mass", tool_mass)
        put(self, "tool_com", readonly(as_array(self.tool_com, "tool_com", (3,)).reshape(3)))
        for f in ("payload", "reach"):
            v = getattr(self, f)
            if v is not None:
                v = float(as_array(v, f))
                if v <= 0.0:
                    raise ValueError(f"{f}: must be positive or None, got {v}")
                put(self, f, v)
        seed_dh = (self.d, self.a, self.alpha, self.theta_offset)
        refine = False
        if self.calibration is not None:
            seed_dh, refine = _check_calibration(self)
        ur, problem = _ur_geometry(seed_dh[0], seed_dh[1], seed_dh[2])
        put(self, "_ur", ur)
        put(self, "_ur_problem", problem)
        put(self, "_seed_dh", seed_dh)
        put(self, "_refine", refine)
        eye = np.eye(4)
        put(self, "_base_inv", None if np.array_equal(self.base, eye) else se3.inverse(self.base))
        put(self, "_tool_inv", None if np.array_equal(self.tool, eye) else se3.inverse(self.tool))

    # ------------------------------------------------------------------ construction

    @classmethod
    def from_dh(
        cls,
        d: ArrayLike,
        a: ArrayLike,
        alpha: ArrayLike,
        *,
        name: str = "custom",
        theta_offset: ArrayLike = 0.0,
        lower: ArrayLike = -2 * np.pi,
        upper: ArrayLike = 2 * np.pi,
        max_velocity: ArrayLike = np.pi,
        max_acceleration: ArrayLike = DEFAULT_ACCELERATION,
        max_torque: ArrayLike = np.inf,
        link_mass: ArrayLike = 0.0,
        link_com: ArrayLike = (0.0, 0.0, 0.0),
        control_period: float = 0.002,
        base: ArrayLike | None = None,
        tool: ArrayLike | None = None,
        tool_mass: float = 0.0,
        tool_com: ArrayLike = (0.0, 0.0, 0.0),
        payload: float | None = None,
        reach: float | None = None,
    ) -> RobotModel:
        """Build an arm from its standard-DH table (one entry per joint).

        ``d``, ``a`` [m] and ``alpha`` [rad] are the DH columns; per-joint
        parameters accept a scalar (same for every joint) or a vector.  The
        defaults for unknown data are: limits +-2 pi, speed pi rad/s,
        acceleration :data:`DEFAULT_ACCELERATION`, unlimited torque, massless
        links, a 2 ms control period.  Analytic IK is available when the table
        has the UR structure (``alpha = [pi/2, 0, 0, pi/2, -pi/2, 0]``,
        ``a1 = a4 = a5 = a6 = 0``, ``a2, a3 != 0``); FK and the Jacobian work
        for any table.
        """
        n = np.asarray(d).shape[0] if np.ndim(d) == 1 else 0
        if n == 0:
            raise ValueError(f"d: expected a 1-D DH column, got shape {np.shape(d)}")
        return cls(
            name=name,
            d=d,
            a=a,
            alpha=alpha,
            theta_offset=theta_offset,
            lower=lower,
            upper=upper,
            max_velocity=max_velocity,
            max_acceleration=max_acceleration,
            max_torque=max_torque,
            link_mass=link_mass,
            link_com=link_com,
            control_period=control_period,
            base=np.eye(4) if base is None else base,
            tool=np.eye(4) if tool is None else tool,
            tool_mass=tool_mass,
            tool_com=tool_com,
            payload=payload,
            reach=reach,
        )

    def with_tool(
        self, tool: ArrayLike, mass: float | None = None, com: ArrayLike | None = None
    ) -> RobotModel:
        """A copy with the TCP at ``tool`` in the flange frame.

        ``tool`` is a 4x4 pose or a UR pose vector ``[x, y, z, rx, ry, rz]`` (the
        controller's TCP setting).  ``mass`` [kg] and ``com`` (flange frame [m])
        replace the tool's mass properties when given.
        """
        changes: dict = {"tool": as_pose_or_vector(tool, "tool")}
        if mass is not None:
            changes["tool_mass"] = mass
        if com is not None:
            changes["tool_com"] = com
        return dataclasses.replace(self, **changes)

    def with_base(self, base: ArrayLike) -> RobotModel:
        """A copy whose base frame sits at ``base`` (4x4 or UR pose vector) in the world."""
        return dataclasses.replace(self, base=as_pose_or_vector(base, "base"))

    def with_calibration(self, calibration: Calibration | None) -> RobotModel:
        """A copy that carries ``calibration`` (its effective DH table); None: the nominal arm.

        ``calibration`` is a :class:`~ruledrobot.robot.Calibration` (files are read by
        :func:`ruledrobot.io.load_calibration`).  It must be a calibration of this model
        (``ValueError`` otherwise).  Base, tool, limits and masses are kept.  FK is then
        the DH chain with the effective parameters; ``ik``
        seeds every branch with the nominal closed form and finishes on the calibrated
        chain; a nominal calibration gives the closed form's answer bit for bit.
        """
        if calibration is None:
            return self.nominal
        calibration = _calibration_of(self.name, calibration)
        return dataclasses.replace(
            self,
            calibration=calibration,
            theta_offset=calibration.theta_offset,
            a=calibration.a,
            d=calibration.d,
            alpha=calibration.alpha,
        )

    @property
    def nominal(self) -> RobotModel:
        """This arm without its calibration (the catalogue table); ``self`` when uncalibrated."""
        if self.calibration is None:
            return self
        d, a, alpha, offset = self._seed_dh
        return dataclasses.replace(
            self, calibration=None, theta_offset=offset, a=a, d=d, alpha=alpha
        )

    def with_limits(
        self,
        *,
        lower: ArrayLike | None = None,
        upper: ArrayLike | None = None,
        velocity: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
        torque: ArrayLike | None = None,
    ) -> RobotModel:
        """A copy with some limits replaced (scalars apply to every joint)."""
        changes = {
            k: v
            for k, v in (
                ("lower", lower),
                ("upper", upper),
                ("max_velocity", velocity),
                ("max_acceleration", acceleration),
                ("max_torque", torque),
            )
            if v is not None
        }
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ properties

    @property
    def n_joints(self) -> int:
        """Number of joints J."""
        return int(self.d.shape[0])

    @property
    def has_analytic_ik(self) -> bool:
        """True when the DH table has the UR structure the closed-form IK needs.

        Also True for a calibrated catalogue arm: its IK starts from the closed form of
        its nominal table and finishes on the calibrated chain.
        """
        return self._ur is not None

    @property
    def ur_geometry(self) -> _ik.URGeometry:
        """``(d1, a2, a3, d4 + d2 + d3, d5, d6)``; ValueError for a non-UR table.

        A calibrated arm gives the numbers of its nominal table.
        """
        if self._ur is None:
            raise ValueError(f"model {self.name!r}: no analytic IK: {self._ur_problem}")
        return self._ur

    def __repr__(self) -> str:
        extra = ""
        if self._base_inv is not None:
            extra += ", base set"
        if self._tool_inv is not None:
            extra += f", tool set ({self.tool_mass:g} kg)"
        if self.calibration is not None:
            extra += f", calibrated ({self.calibration.source or 'no source'})"
        return f"RobotModel({self.name!r}, {self.n_joints} joints{extra})"

    # ------------------------------------------------------------------ kinematics

    def _joints(self, q: ArrayLike, name: str = "q") -> FloatArray:
        return as_array(q, name, (self.n_joints,))

    def _chain(self, table: tuple[FloatArray, ...] | None = None) -> DHChain:
        """The arm's chain with its base and tool; ``table`` (d, a, alpha, offset) in
        place of its own (the nominal one of a calibrated arm)."""
        own = (self.d, self.a, self.alpha, self.theta_offset)
        base = None if self._base_inv is None else self.base
        tool = None if self._tool_inv is None else self.tool
        return DHChain(own if table is None else table, base, tool)

    def fk(self, q: ArrayLike) -> FloatArray:
        """TCP poses in the world frame: joints (..., J) [rad] -> (..., 4, 4).

        ``base @ A_1(q_1) ... A_J(q_J) @ tool`` (the flange when no tool is set).
        Vectorised closed form: a loop over the joints, none over poses.
        """
        q = self._joints(q)
        T = self._chain().fk(q.reshape(-1, self.n_joints))
        return T.reshape(*q.shape[:-1], 4, 4)

    def jacobian(self, q: ArrayLike) -> FloatArray:
        """Geometric Jacobian (..., 6, J) at the TCP, in the world frame.

        Rows ``[v; omega]``: TCP linear velocity [m/s] then angular velocity
        [rad/s] (UR speedl order), ``[v; omega] = J(q) @ qdot``.
        """
        q = self._joints(q)
        Jm = self._chain().jacobian(q.reshape(-1, self.n_joints))
        return Jm.reshape(*q.shape[:-1], 6, self.n_joints)

    def link_points(self, q: ArrayLike) -> FloatArray:
        """The DH skeleton of configurations (..., J) in the world frame: (..., 2J + 1, 3).

        Point 0 is the base frame origin; joint ``i`` adds the point reached by
        ``d_i`` along the previous z axis and then its frame origin (``a_i`` along
        x_i).  Consecutive points bound the arm's links (the segments a collision
        model puts capsules on); zero-length legs repeat a point.  A calibrated arm
        uses its nominal table: the DH legs of a calibrated table run metres to
        hundreds of metres along the nearly parallel axes 2-4, the nominal skeleton
        lies within millimetres of the real arm.
        """
        q = self._joints(q)
        pts = self._chain(self._seed_dh).skeleton(q.reshape(-1, self.n_joints))
        return pts.reshape(*q.shape[:-1], 2 * self.n_joints + 1, 3)

    def within_limits(self, q: ArrayLike, tol: float = LIMIT_TOL) -> np.ndarray:
        """Return whether every joint of ``q`` (..., J) is inside its limits, (...) bool.

        Inside ``[lower - tol, upper + tol]`` [rad] (default the one slack,
        :data:`~ruledrobot.robot.ik.path.LIMIT_TOL`).
        """
        q = self._joints(q)
        return np.all((q >= self.lower - tol) & (q <= self.upper + tol), axis=-1)

    def position_ratio(self, q: ArrayLike) -> float:
        """Return the largest ``|q - centre| / (half range + LIMIT_TOL)`` over samples and joints.

        Over the samples of ``q`` (..., J) and the joints with finite limits (0 when none):
        at most 1 exactly when :meth:`within_limits` holds (1 = at a limit, within the one
        slack).
        """
        q = self._joints(q)
        fin = np.isfinite(self.lower) & np.isfinite(self.upper)
        if not fin.any() or q.size == 0:
            return 0.0
        lo, hi = self.lower[fin], self.upper[fin]
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        return float((np.abs(q[..., fin] - mid) / (half + LIMIT_TOL)).max())


def _calibration_of(name: str, cal: object) -> Calibration:
    """``cal`` when it is a :class:`Calibration` of the model called ``name``; ValueError
    naming both models otherwise (the one check of :meth:`RobotModel.with_calibration`
    and of a model built with a calibration)."""
    if not isinstance(cal, Calibration):
        raise ValueError(
            f"calibration: expected a Calibration or None (read files with "
            f"ruledrobot.io.load_calibration), got {type(cal).__name__}"
        )
    if cal.model != name:
        raise ValueError(
            f"calibration: it belongs to a {cal.model} (source {cal.source!r}), this model is "
            f"a {name}"
        )
    return cal


def _check_calibration(model: RobotModel) -> tuple[tuple[FloatArray, ...], bool]:
    """The nominal table (d, a, alpha, offset) of a calibrated model and whether its IK
    needs the Newton finish; ValueError when the calibration does not fit the model."""
    cal = _calibration_of(model.name, model.calibration)
    for f in ("theta_offset", "a", "d", "alpha"):
        mine, theirs = getattr(model, f), getattr(cal, f)
        if not np.array_equal(mine, theirs):
            i = int(np.argmax(mine != theirs))
            raise ValueError(
                f"{f}[{i}] = {float(mine[i])!r} is not the calibration's effective value "
                f"{float(theirs[i])!r}; "
                "attach calibrations with with_calibration()"
            )
    nom = nominal_dh(cal.model)
    seed_dh = (nom.d, nom.a, nom.alpha, nom.theta_offset)
    return seed_dh, not cal.is_nominal


def _ur_geometry(
    d: FloatArray, a: FloatArray, alpha: FloatArray
) -> tuple[_ik.URGeometry | None, str]:
    """The closed-form parameters of a UR-type table, or None and the reason it is not one."""
    if d.shape[0] != 6:
        return None, f"needs 6 joints, the table has {d.shape[0]}"
    for i in range(6):
        if abs(float(alpha[i]) - _UR_ALPHA[i]) > 1e-12:
            return None, f"alpha[{i}] = {alpha[i]:.12g}, the UR structure needs {_UR_ALPHA[i]:.12g}"
    for i in (0, 3, 4, 5):
        if a[i] != 0.0:
            return None, f"a[{i}] = {a[i]:g}, the UR structure needs 0"
    for i in (1, 2):
        if a[i] == 0.0:
            return None, f"a[{i}] = 0, the UR structure needs a non-zero link length"
    geom = _ik.URGeometry(
        d1=float(d[0]),
        a2=float(a[1]),
        a3=float(a[2]),
        d4=float(d[1] + d[2] + d[3]),
        d5=float(d[4]),
        d6=float(d[5]),
    )
    return geom, ""
