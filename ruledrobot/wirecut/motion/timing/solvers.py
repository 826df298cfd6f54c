"""Solvers of the path problem: toppra's controllable sets, the closed-form reachability
fallback, the forward pass."""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np

from .diagnose import TimingFailure, binding_at
from .problem import _Problem, _stage_rows, _static_bound, _x_upper
from .tolerances import FloatArray


class _SolverError(RuntimeError):
    """Internal: a solver could not produce a usable profile."""


class _StalledError(RuntimeError):
    """Internal: the path speed is zero at both ends of a stage (infinite duration)."""

    def __init__(self, stage: int) -> None:
        super().__init__(f"path speed is zero on the whole stage {stage}")
        self.stage = stage


def _backward(
    c: FloatArray, w: FloatArray, deltas: FloatArray, x_stage: FloatArray, x_end: float
) -> FloatArray:
    """Upper ends of the controllable sets K_i = [0, hi_i] (G,), in closed form.

    hi_i is the largest x ≤ x_stage_i from which some σ̈ in the stage's interval lands
    in [0, hi_{i+1}]: ``c_r x − w_r ≤ (hi_{i+1} − x)/(2Δ)`` for every row r.
    """
    G = deltas.shape[0] + 1
    inv2d = (1.0 / (2.0 * deltas))[:, None]
    k = c + inv2d
    pos = k > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        ka = np.where(pos, inv2d / k, 0.0)
        kb = np.where(pos, w / k, np.inf)
    hi = np.empty(G)
    hi[-1] = x_end
    for i in range(G - 2, -1, -1):
        hi[i] = min(x_stage[i], float(np.min(ka[i] * hi[i + 1] + kb[i])))
    return hi


def _forward(
    c: FloatArray, w: FloatArray, deltas: FloatArray, hi: FloatArray, x0: float
) -> FloatArray:
    """Greedy forward pass: the largest σ̈ keeping x_{i+1} ≤ hi_{i+1}. Returns x (G,)."""
    G = hi.shape[0]
    x = np.empty(G)
    x[0] = x0
    cl = c.tolist()
    wl = w.tolist()
    two_d = (2.0 * deltas).tolist()
    hil = hi.tolist()
    xi = x0
    for i in range(G - 1):
        ci, wi = cl[i], wl[i]
        umax = min(a * xi + b for a, b in zip(ci, wi, strict=True))
        umin = max(a * xi - b for a, b in zip(ci, wi, strict=True))
        nxt = min(hil[i + 1], xi + two_d[i] * umax)
        floor = xi + two_d[i] * umin
        if nxt < floor:  # K_{i+1} slightly optimistic (LP round-off): brake at the limit
            nxt = floor
        xi = max(nxt, 0.0)
        x[i + 1] = xi
    return x


@lru_cache(maxsize=1)
def _toppra_xbound_class() -> type:
    from toppra.constraint import LinearConstraint

    class XBoundConstraint(LinearConstraint):  # type: ignore[misc]
        """Path-velocity bound ``0 <= x <= x_hi(s_i)`` at the grid points."""

        def __init__(self, x_hi: FloatArray, dof: int) -> None:
            super().__init__()
            self.xbound = np.stack([np.zeros_like(x_hi), x_hi], axis=1)
            self.dof = dof
            self._format_string = "    path-velocity bound (joint velocity and feed)\n"

        def compute_constraint_params(self, path: Any, gridpoints: Any) -> tuple:
            return None, None, None, None, None, None, self.xbound

    return XBoundConstraint


def _toppra_controllable(
    prob: _Problem, x_hi: FloatArray, alim: FloatArray, x_end: float
) -> FloatArray:
    """Upper ends of toppra's controllable sets (G,); raises _SolverError on failure."""
    try:
        import toppra
        from toppra.algorithm import TOPPRA
        from toppra.constraint import DiscretizationType, JointAccelerationConstraint

        path = toppra.SplineInterpolator(prob.sigma, prob.q_w)
        vel = _toppra_xbound_class()(x_hi, prob.q.shape[1])
        acc = JointAccelerationConstraint(
            alim, discretization_scheme=DiscretizationType.Interpolation
        )
        inst = TOPPRA([vel, acc], path, gridpoints=prob.grid, solver_wrapper="seidel")
        K = inst.compute_controllable_sets(0.0, math.sqrt(x_end))
    except Exception as exc:  # toppra raises assorted errors on bad conditioning
        raise _SolverError(f"toppra raised {type(exc).__name__}: {exc}") from exc
    K = np.asarray(K, dtype=np.float64)
    bad = ~np.isfinite(K).all(axis=1) | (K[:, 1] < -1e-9) | (K[:, 1] < K[:, 0] - 1e-9)
    if bad.any():
        i = int(np.flatnonzero(bad)[-1])
        raise _SolverError(f"toppra: controllable set {i} of {K.shape[0]} is empty or NaN")
    return np.maximum(K[:, 1], 0.0)


def _solve(
    prob: _Problem,
    vlim: FloatArray,
    alim: FloatArray,
    start_at_rest: bool,
    end_at_rest: bool,
    use_toppra: bool = True,
) -> tuple[FloatArray, str]:
    """x = σ̇² at the grid (G,) and the method used."""
    x_hi = _x_upper(prob, vlim)
    c, w, x_only = _stage_rows(prob, alim)
    x_end = 0.0 if end_at_rest else float(x_hi[-1])
    method = "toppra"
    hi = None
    if use_toppra:
        try:
            hi = _toppra_controllable(prob, x_hi, alim, x_end)
        except _SolverError as exc:
            method = f"reachability (fallback: {exc})"
    else:
        method = "reachability"
    if hi is None:
        x_stage = np.minimum(np.minimum(x_hi[:-1], x_only), _static_bound(c, w, prob.deltas))
        hi = _backward(c, w, prob.deltas, x_stage, x_end)
    x0 = 0.0 if start_at_rest else float(hi[0])
    x = _forward(c, w, prob.deltas, hi, x0)
    if end_at_rest:  # the forward pass may end a round-off above 0 (LP tolerance of K)
        x[-1] = 0.0
    if not np.isfinite(x).all():
        i = int(np.flatnonzero(~np.isfinite(x))[0])
        s_i = float(prob.s_at(prob.grid[i : i + 1])[0])
        b = binding_at(prob, i, vlim, alim)
        raise TimingFailure(
            f"time_path: no finite path speed at s = {s_i:.6g}; binding constraint: "
            f"{b.words()} (ds/dt <= {b.ds_dt:.3g} there)",
            reason="no_speed", duration=float("nan"), s_range=(s_i, s_i), binding=b,
        )
    return x, method
