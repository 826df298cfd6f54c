"""The arm's inverse side, a mixin of :class:`~ruledrobot.robot.arm.model.RobotModel`:
world TCP poses to flange poses, the 8 closed-form IK solutions (nominal, or seeded by the
nominal closed form and refined on a calibrated chain, :mod:`ruledrobot.robot.ik.calibrated`),
singularity factors and measure, and path IK.

The model's own fields (DH table, base and tool inverses, the nominal seed table) are
read from ``self``; this module imports nothing of the model (no import circle).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from .._checks import FloatArray, as_array, as_poses
from ..ik import analytic as _ik
from ..ik.path import PathIKResult, path_ik

__all__ = ["InverseKinematics"]


def _left_mul(L: FloatArray, X: FloatArray) -> FloatArray:
    """``L @ X[k]`` for a constant 4x4 ``L`` and poses X (n, 4, 4), as one GEMM."""
    return np.ascontiguousarray(np.tensordot(X, L, axes=([1], [1])).transpose(0, 2, 1))


def _right_mul(X: FloatArray, R: FloatArray) -> FloatArray:
    """``X[k] @ R`` for poses X (n, 4, 4) and a constant 4x4 ``R``, as one GEMM."""
    return (X.reshape(-1, 4) @ R).reshape(X.shape)


def _measure_scale(g: _ik.URGeometry) -> float:
    return abs(g.a2) + abs(g.a3) + abs(g.d5)


class InverseKinematics:
    """IK methods of :class:`~ruledrobot.robot.arm.model.RobotModel`.

    See there for the frames: world, robot base, flange, TCP.
    """

    if TYPE_CHECKING:  # read from the model (its dataclass fields and derived values)
        d: FloatArray
        a: FloatArray
        alpha: FloatArray
        theta_offset: FloatArray
        _base_inv: FloatArray | None
        _tool_inv: FloatArray | None
        _seed_dh: tuple[FloatArray, ...]
        _refine: bool

        @property
        def ur_geometry(self) -> _ik.URGeometry: ...

        def _joints(self, q: ArrayLike, name: str = "q") -> FloatArray: ...

    def flange_poses(self, T: ArrayLike, check: bool = True) -> FloatArray:
        """World TCP poses (..., 4, 4) -> flange poses in the robot base frame.

        ``inv(base) @ T @ inv(tool)``: what the closed-form IK solves for.
        """
        T = as_poses(T, "poses") if check else np.asarray(T, dtype=np.float64)
        shape = T.shape[:-2]
        flat = T.reshape(-1, 4, 4)
        if self._base_inv is not None:
            flat = _left_mul(self._base_inv, flat)
        if self._tool_inv is not None:
            flat = _right_mul(flat, self._tool_inv)
        return flat.reshape(*shape, 4, 4)

    @overload
    def ik(
        self,
        T: ArrayLike,
        *,
        q6_seed: ArrayLike = ...,
        return_info: Literal[False] = ...,
        check: bool = ...,
    ) -> FloatArray: ...

    @overload
    def ik(
        self,
        T: ArrayLike,
        *,
        q6_seed: ArrayLike = ...,
        return_info: Literal[True],
        check: bool = ...,
    ) -> _ik.IKSolutions: ...

    def ik(
        self,
        T: ArrayLike,
        *,
        q6_seed: ArrayLike = 0.0,
        return_info: bool = False,
        check: bool = True,
    ) -> FloatArray | _ik.IKSolutions:
        """All 8 analytic IK solutions of TCP poses in the world frame.

        Parameters
        ----------
        T : (..., 4, 4) TCP poses in the world frame (m).
        q6_seed : scalar or (...) value of q6 [rad] used where the wrist is
            singular (``|sin q5| < 1e-12``: only ``q4 +- q6`` is determined).
            If the elbow cannot reach with it, the q6 nearest to it with
            which the elbow reaches is used instead.
        return_info : also return the singularity factors (:class:`IKSolutions`).
        check : validate the poses (shape, finite, rigid); ValueError names the
            first bad pose.  Switch off only for poses known to be valid.

        Returns
        -------
        (..., 8, 6) joint positions in (-pi, pi] [rad], branch index
        ``4 * shoulder + 2 * wrist + elbow`` (``docs/robot.md``), NaN rows
        where a branch has no solution; or :class:`IKSolutions` with
        ``return_info=True``.  Each solution reproduces the pose to better than
        1e-10 (typically 1e-15; the bound is reached only next to singularities).
        """
        g = self.ur_geometry
        Tf = self.flange_poses(T, check=check)
        shape = Tf.shape[:-2]
        flat = Tf.reshape(-1, 4, 4)
        n = flat.shape[0]
        seed = as_array(q6_seed, "q6_seed")
        try:
            seed = np.broadcast_to(seed, shape).reshape(n)
        except ValueError:
            raise ValueError(
                f"q6_seed: expected a scalar or the batch shape {shape}, got {seed.shape}"
            ) from None
        if self._refine:
            return self._ik_calibrated(flat, shape, seed, return_info)
        seed = seed + self.theta_offset[5]
        out = np.empty((n, 8, 6))
        info = np.empty((n, 8, 3)) if return_info else None
        for lo in range(0, n, _ik._CHUNK):
            hi = min(lo + _ik._CHUNK, n)
            _ik.ur_ik_chunk(
                g, flat[lo:hi], seed[lo:hi], out[lo:hi], None if info is None else info[lo:hi]
            )
        if np.any(self.theta_offset != 0.0):
            ok = ~np.isnan(out[..., 0])
            out[ok] = _ik.wrap_angle(out[ok] - self.theta_offset)
        q = out.reshape(*shape, 8, 6)
        if info is None:
            return q
        info = info.reshape(*shape, 8, 3)
        valid = ~np.isnan(q[..., 0])
        measure = info[..., 0] * info[..., 1] * info[..., 2] / _measure_scale(g)
        return _ik.IKSolutions(
            q=q,
            valid=valid,
            wrist=info[..., 0],
            elbow=info[..., 1],
            shoulder=info[..., 2],
            measure=measure,
        )

    def _ik_calibrated(
        self, flat: FloatArray, shape: tuple, seed: FloatArray, return_info: bool
    ) -> FloatArray | _ik.IKSolutions:
        """Nominal closed-form seeds refined on the calibrated chain (see ``calibrated_ik``)."""
        from ..ik import calibrated as _cik

        g = self.ur_geometry
        offset = self._seed_dh[3]
        seeds, _ = _cik.nominal_seeds(g, flat, seed + offset[5])
        q, conv, res, its = _cik.refine_solutions(
            self.d, self.a, self.alpha, self.theta_offset, flat, seeds, offset
        )
        q = q.reshape(*shape, 8, 6)
        if not return_info:
            return q
        f = self.singularity_factors(np.where(conv.reshape(*shape, 8)[..., None], q, 0.0))
        nan = np.where(conv, 0.0, np.nan).reshape(*shape, 8)
        wrist, elbow, shoulder = (f[..., k] + nan for k in range(3))
        return _cik.CalibratedIKSolutions(
            q=q,
            valid=conv.reshape(*shape, 8),
            wrist=wrist,
            elbow=elbow,
            shoulder=shoulder,
            measure=wrist * elbow * shoulder / _measure_scale(g),
            converged=conv.reshape(*shape, 8),
            seeded=~np.isnan(seeds[..., 0]).reshape(*shape, 8),
            residual=res.reshape(*shape, 8),
            iterations=its.reshape(*shape, 8),
        )

    def singularity_factors(self, q: ArrayLike) -> FloatArray:
        """(..., 3) singularity factors of joint configurations (..., 6).

        ``[|sin q5|, |sin q3|, |a2 c2 + a3 c23 + d5 sin q234|]`` (DH angles):
        wrist, elbow and shoulder (metres: distance of the wrist point from the
        plane of the base z axis and the shoulder axis).  Each is 0 at its
        singularity; ``det J = a2 a3 sin q3 sin q5 s``.  A calibrated arm uses its
        nominal table (its singularities lie within about 1e-2 rad of those).
        """
        g = self.ur_geometry
        th = self._joints(q) + self._seed_dh[3]
        t2, t3, t4 = th[..., 1], th[..., 2], th[..., 3]
        s = g.a2 * np.cos(t2) + g.a3 * np.cos(t2 + t3) + g.d5 * np.sin(t2 + t3 + t4)
        return np.stack([np.abs(np.sin(th[..., 4])), np.abs(np.sin(t3)), np.abs(s)], axis=-1)

    def singularity_measure(self, q: ArrayLike) -> FloatArray:
        """Scaled ``|det J|`` in [0, 1] of configurations (..., 6): 0 at any singularity.

        ``|sin q3 sin q5 s| / (|a2| + |a3| + |d5|)`` = ``|det J| / (|a2 a3| (|a2| + |a3| + |d5|))``.
        """
        f = self.singularity_factors(q)
        return f[..., 0] * f[..., 1] * f[..., 2] / _measure_scale(self.ur_geometry)

    def path_ik(self, poses: ArrayLike, **options: Any) -> PathIKResult:
        """One continuous IK solution per TCP pose (N, 4, 4) of a path.

        ``options`` (``q_start``, ``jump_threshold``, ``singular_tol``, ``weights``,
        ``max_messages``) and the rules: :func:`ruledrobot.robot.path_ik`.
        """
        return path_ik(self, poses, **options)
