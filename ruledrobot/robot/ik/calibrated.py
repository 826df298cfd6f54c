r"""Inverse kinematics of a calibrated UR arm: analytic nominal seeds, damped Newton finish.

With the factory corrections the UR closed form no longer holds: joints 2-4 are not
exactly parallel, the wrist axes do not exactly intersect.  The corrections are
small in the arm's geometry, so each of the 8 nominal analytic solutions of a pose
lies within about 1e-2 rad of the calibrated solution of the same branch.  This
module refines all of them; for batches of more than :data:`NUMPY_POSES` poses both
steps run in compiled kernels (:mod:`ruledrobot.robot.ik._calibrated_kernel`, numba, loaded
by the first such batch or by :func:`load_kernels`); smaller batches run the same steps
in numpy (:mod:`ruledrobot.robot.ik._calibrated_numpy`, see :func:`uses_kernel`):

1. **Seeds.**  The nominal closed form of the flange pose (the formulas of
   :mod:`~ruledrobot.robot.ik.analytic`) gives up to 8 seeds.  Branches the nominal
   arm cannot reach (the pose lies just beyond its reach, inside its shoulder cylinder
   or closer than its folded elbow) are seeded from the closed form of a nominal arm
   that reaches 1 cm further in each direction (:func:`fallback_geometry`; 3 cm for
   poses with no seed at all), so that poses only the calibrated arm reaches are
   solved too.  This matters: near the stretched elbow a millimetre of reach is a wide
   band of ``q3`` (``dD ~ q3^2``), and about 2.5 % of the (pose, branch) pairs of
   random configurations of a calibrated UR5e lie there.  Poses whose wrist is within
   ``analytic_ik.RESCUE_W`` of singular (where ``q6_seed`` and the singular-wrist rules
   apply) are seeded by the numpy closed form itself (:func:`numpy_seeds`).
2. **Newton / Levenberg-Marquardt** on the calibrated DH chain, per (pose, branch)
   pair, 8 pairs side by side in vectorised lanes (a lane whose pair finishes takes the
   next one).  The residual is the flange's position error and its rotation error (the
   small rotation vector), both in the frame turned with joint 1.  The Jacobian is
   taken at the wrist point ``p5`` in that frame, where the nominal UR Jacobian is
   block triangular (``det J = a2 a3 sin q3 sin q5 s``): the linear system is solved by
   block elimination in the order shoulder (1x1), wrist (2x2), q4 (1x1), elbow (2x2),
   which is exact for any matrix and well conditioned for a near-UR one.  Each pivot
   block is damped Levenberg-Marquardt style (``1/p -> p / (p^2 + mu^2)``, ``mu^2 =
   lambda * |e|``), so the iteration converges quadratically away from singularities
   and stays bounded next to them; a step that raises the residual more than
   thousandfold over the pair's best is undone and taken again at half length from the
   best iterate; a step longer than 0.5 rad is shortened (trust region).
3. **Result.**  A pair is converged when the position error is below ``tol`` [m]
   and the rotation error below ``tol`` [rad] (default 1e-11).  Pairs that do not
   converge within ``max_iter`` iterations, or stall (8 iterations without reducing
   their best residual by 30 %), are NaN rows flagged in :class:`CalibratedIKSolutions`.
   A branch keeps its identity: the iteration starts at the nominal solution of the
   branch and moves by about the calibration's size, more next to a singularity (the
   calibration moves it: a UR3 seed 3.4 mm outside the nominal shoulder cylinder can
   end next to the calibrated one, 0.24 rad away).  There the nominal flags of the
   solution may differ from the branch's; the branch is the one the calibration, grown
   from zero, carries the seed to without crossing a singularity, so ``det J`` keeps
   its sign.

Sines and cosines come from a branch-free polynomial (Cody-Waite reduction by pi/2,
the fdlibm kernels; within 1 ulp of libm here), so that the lane loops vectorise.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from .._checks import FloatArray
from . import analytic as _ik

__all__ = [
    "DEFAULT_MAX_ITER",
    "DEFAULT_TOL",
    "CalibratedIKSolutions",
    "kernels_loaded",
    "load_kernels",
    "nominal_seeds",
    "refine_solutions",
    "uses_kernel",
]

#: Convergence tolerance: position error [m] and rotation error [rad] of a solution.
DEFAULT_TOL = 1e-11
#: Largest number of Newton iterations per (pose, branch).
DEFAULT_MAX_ITER = 40
#: Batches of at most this many poses are solved in numpy (``_calibrated_numpy``), larger
#: ones by the compiled kernels (see :func:`uses_kernel`).
NUMPY_POSES = 1024
_FALLBACK = 0.01  # m: links lengthened / shoulder shortened for the fallback seeds


@dataclass(frozen=True, eq=False)
class CalibratedIKSolutions(_ik.IKSolutions):
    """:class:`~ruledrobot.robot.IKSolutions` of a calibrated arm, with convergence information.

    Extra attributes (batch shape ``S`` of the input poses)
    ----------
    converged : (*S, 8) bool, the Newton iteration reached the tolerance (equal to
        ``valid``).
    seeded : (*S, 8) bool, the branch had a seed (a nominal solution, or one of the
        fallback seeds).  ``seeded & ~converged`` is a reported non-convergence.
    residual : (*S, 8) the larger of the position error [m] and the rotation error
        [rad] at the last iterate (NaN where not seeded).
    iterations : (*S, 8) int16, Newton iterations used (0 where not seeded).

    The singularity factors ``wrist``, ``elbow``, ``shoulder`` and ``measure`` are
    those of the nominal structure at the calibrated solution (the formulas of
    ``docs/robot.md`` with the nominal ``a2, a3, d5``).
    """

    converged: np.ndarray
    seeded: np.ndarray
    residual: FloatArray
    iterations: np.ndarray


# ---------------------------------------------------------------------- kernels


def kernels_loaded() -> bool:
    """Whether the compiled kernels (numba) are loaded in this process."""
    return "ruledrobot.robot.ik._calibrated_kernel" in sys.modules


def load_kernels() -> None:
    """Load (or, the first time after an install, compile: 10-20 s) the compiled kernels.

    The first calibrated IK of more than :data:`NUMPY_POSES` poses does this by itself.
    A process with a clock thread (the emulator's 500 Hz loop) calls it at start-up, at a
    moment that can wait: importing numba and loading the kernels takes about a second, in
    C calls that hold the interpreter lock up to about 0.1 s at a time.
    """
    from . import _calibrated_kernel as _kernel

    flange = np.broadcast_to(np.eye(4), (1, 4, 4)).copy()
    flange[0, :3, 3] = (0.3, 0.2, 0.1)
    geoms = np.array([(0.16, -0.4, -0.4, 0.13, 0.1, 0.1)] * 3)
    out = np.empty((1, 8, 6))
    _kernel.seeds(geoms, flange, out, np.empty((1, 8), bool), np.empty(1, bool))
    ch = np.array([np.zeros(6), np.zeros(6), np.ones(6), np.zeros(6)])
    _kernel.refine(
        ch, np.zeros(6), flange, np.zeros((1, 8, 6)), np.zeros(6), DEFAULT_TOL, 1,
        np.empty((1, 8, 6)), np.empty((1, 8), bool), np.empty((1, 8)),
        np.empty((1, 8), np.int16),
    )  # fmt: skip


def uses_kernel(n: int) -> bool:
    """Whether a batch of ``n`` poses runs in the compiled kernels: ``n > NUMPY_POSES``.

    Smaller batches run the same iteration in numpy (:mod:`ruledrobot.robot.ik._calibrated_numpy`):
    a process that solves single poses and short moves, such as the emulator in its clock
    thread, then never waits a second for numba; and the choice depends on the batch alone,
    so that a job planned in a worker thread gives the bytes the main thread gives.  Both
    converge to ``tol``; their solutions agree to rounding.
    """
    return n > NUMPY_POSES


# ---------------------------------------------------------------------- seeds


def fallback_geometry(g: _ik.URGeometry, e: float = 0.01) -> _ik.URGeometry:
    """A nominal geometry that reaches a little further than ``g`` in every direction.

    The longer link gets ``e`` [m] more, the shorter twice that (the stretched arm
    reaches ``3 e`` further out, the folded one ``e`` further in) and the shoulder
    offset ``d4`` is shortened by ``e`` (wrist points just inside the shoulder cylinder).
    """

    def longer(x: float, by: float) -> float:
        return float(x + np.copysign(by, x))

    if abs(g.a2) >= abs(g.a3):
        a2, a3 = longer(g.a2, e), longer(g.a3, 2 * e)
    else:
        a2, a3 = longer(g.a2, 2 * e), longer(g.a3, e)
    d4 = float(g.d4 - np.copysign(min(e, 0.5 * abs(g.d4)), g.d4))
    return g._replace(a2=a2, a3=a3, d4=d4)


def nominal_seeds(
    g: _ik.URGeometry, flange: FloatArray, seed6: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """Return the IK seeds (n, 8, 6) from the nominal arm and their closed-form flags (n, 8).

    The seeds are DH angles of the nominal table; a flag says "from the closed form of the
    nominal arm".  Branches the nominal arm misses are filled from :func:`fallback_geometry`
    where that reaches (flag False), else NaN.

    Compiled closed form (``_calibrated_kernel.seeds``, the formulas of ``analytic_ik``);
    poses whose wrist is within ``analytic_ik.RESCUE_W`` of singular, where ``seed6`` and
    the singular-wrist rules apply, are seeded by :func:`numpy_seeds`.
    """
    n = flange.shape[0]
    if not uses_kernel(n):
        return numpy_seeds(g, flange, np.asarray(seed6, dtype=np.float64))
    from . import _calibrated_kernel as _kernel  # numba

    geoms = np.array([g, fallback_geometry(g, _FALLBACK), fallback_geometry(g, 3 * _FALLBACK)])
    out = np.empty((n, 8, 6))
    exact = np.empty((n, 8), dtype=bool)
    rows = np.empty(n, dtype=bool)
    _kernel.seeds(geoms, np.ascontiguousarray(flange, dtype=np.float64), out, exact, rows)
    if rows.any():
        rows = np.flatnonzero(rows)
        out[rows], exact[rows] = numpy_seeds(g, flange[rows], np.asarray(seed6)[rows])
    return out, exact


def numpy_seeds(
    g: _ik.URGeometry, flange: FloatArray, seed6: FloatArray
) -> tuple[FloatArray, np.ndarray]:
    """:func:`nominal_seeds` with the numpy closed form (:func:`analytic_ik.ur_ik_chunk`)."""
    n = flange.shape[0]
    out = np.empty((n, 8, 6))
    for lo in range(0, n, _ik._CHUNK):
        hi = min(lo + _ik._CHUNK, n)
        _ik.ur_ik_chunk(g, flange[lo:hi], seed6[lo:hi], out[lo:hi], None)
    exact = ~np.isnan(out[..., 0])
    # 1 cm further for every pose with a missing branch, 3 cm for poses with none
    for e in (_FALLBACK, 3 * _FALLBACK):
        have = ~np.isnan(out[..., 0])
        missing = np.flatnonzero(~have.any(axis=1) if e > _FALLBACK else ~have.all(axis=1))
        if missing.size == 0:
            continue
        gf = fallback_geometry(g, e)
        sub = np.empty((missing.size, 8, 6))
        for lo in range(0, missing.size, _ik._CHUNK):
            rows = missing[lo : lo + _ik._CHUNK]
            _ik.ur_ik_chunk(gf, flange[rows], seed6[rows], sub[lo : lo + rows.size], None)
        hole = ~have[missing]
        blk = out[missing]
        blk[hole] = sub[hole]
        out[missing] = blk
    return out, exact


def refine_solutions(
    d: FloatArray,
    a: FloatArray,
    alpha: FloatArray,
    offset: FloatArray,
    flange: FloatArray,
    seeds: FloatArray,
    seed_offset: FloatArray,
    *,
    tol: float = DEFAULT_TOL,
    max_iter: int = DEFAULT_MAX_ITER,
) -> tuple[FloatArray, np.ndarray, FloatArray, np.ndarray]:
    """Refine seeds (n, 8, 6) (NaN rows = none) on a calibrated DH chain.

    ``seeds`` are DH angles of a table with offsets ``seed_offset`` (the nominal one:
    joint positions ``seeds - seed_offset``); ``d, a, alpha, offset`` the calibrated
    table; ``flange`` (n, 4, 4) the flange poses in the robot base frame.  Returns joint
    positions (n, 8, 6) in (-pi, pi] (NaN where not converged), converged (n, 8),
    residual (n, 8) and iterations (n, 8).  Runs in the compiled kernel or in numpy
    (same iteration and rules) as :func:`uses_kernel` says.
    """
    n = flange.shape[0]
    off = np.asarray(offset, dtype=np.float64)
    shift = off - np.asarray(seed_offset, dtype=np.float64)
    if not uses_kernel(n):
        from . import _calibrated_numpy

        table = (d, a, alpha, off)
        return _calibrated_numpy.refine(table, flange, seeds, shift, tol=tol, max_iter=max_iter)
    from . import _calibrated_kernel as _kernel  # numba

    ch = np.array([d, a, np.cos(alpha), np.sin(alpha)], dtype=np.float64)
    theta = np.empty((n, 8, 6))
    conv = np.empty((n, 8), dtype=bool)
    res = np.empty((n, 8))
    its = np.empty((n, 8), dtype=np.int16)
    _kernel.refine(
        ch,
        off,
        np.ascontiguousarray(flange, dtype=np.float64),
        np.ascontiguousarray(seeds, dtype=np.float64),
        shift,
        float(tol),
        int(max_iter),
        theta,
        conv,
        res,
        its,
    )
    return theta, conv, res, its
