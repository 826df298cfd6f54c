"""Why a path cannot be timed within reason: where the time goes and what binds there.

:func:`~.time_law.time_path` raises :class:`TimingFailure` (a :class:`ValueError`, so
that callers that only know bad input still stop) when the joints and the feed leave
no usable trajectory: the path speed collapses to zero on a stage (``stall``), the
timed path would last longer than ``MAX_SAMPLES`` controller periods (``too_long``:
hours for a loop), or the sampled output still breaks a limit after every round of
refinement (``limits``).  None of these is bad input: the path is what the planner
made; the planner reports them as a failed plan (the ``timing`` check) with this
diagnosis — the stretch of the path where the time goes (in the caller's ``s``), its
share of the duration, and the constraint that holds the path speed down there: a
joint's velocity or acceleration limit (named) or the feed bound.

Where the time goes: the stage times ``τ_k = 2Δ_k / (σ̇_k + σ̇_{k+1})`` of the solved
law (σ the chordal parameter, ``σ̇ = sqrt(x)``); the stage that takes longest and the
stretch around it where the mean ``σ̇`` of a stage stays below :data:`SLOW_FACTOR`
times that stage's.  What binds at the slowest node: the least of the node's path-speed bounds,
each a function of one joint or of the feed — ``x ≤ (v_j / |q'_j|)²`` (joint ``j``'s
velocity), ``x ≤ (feed / sf_σ)²`` (the feed) and ``x ≤ a_j / |q''_j|`` (joint ``j``'s
acceleration where the path bends: the bound of a stage at constant path speed); when
the law's ``x`` there lies far below all of them, the path is slow because it cannot
change its speed any faster — ``|σ̈| ≤ a_j / |q'_j|``, the joint with the least.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .problem import _Problem
from .tolerances import FloatArray

__all__ = ["SLOW_FACTOR", "Binding", "TimingFailure", "binding_at", "where_time_goes"]

#: the slow stretch around the slowest node: where the path speed stays below this many
#: times its least value
SLOW_FACTOR = 10.0


@dataclass(frozen=True)
class Binding:
    """The tightest bound on the path speed at a node.

    ``kind`` ``"velocity"``, ``"acceleration"`` or ``"feed"``; ``joint`` (from 1) or None for
    the feed; ``x`` the bound on σ̇² there [rad²/s²]; ``ds_dt`` the caller's ``s`` per second
    it allows."""

    kind: str
    joint: int | None
    x: float
    ds_dt: float
    #: what makes the bound tight: ``|q'_j|`` [rad/rad] (velocity), ``|q''_j|``
    #: [rad/rad²] (acceleration where the joint path bends), ``a_j/|q'_j|`` [rad/s²]
    #: (acceleration where it cannot speed up: ``ramp``), ``sf_σ`` [m/rad] (feed)
    value: float = float("nan")
    #: the acceleration limit binds by the path's bend (``x <= a_j/|q''_j|``) or by the
    #: path speed's rate of change (``|σ̈| <= a_j/|q'_j|``: ``ramp``)
    ramp: bool = False

    def words(self) -> str:
        """Return the binding limit in words.

        ``"joint 3's acceleration limit (|q''| = 2.1e+04 rad/rad² there)"`` / ``"the feed
        bound"``.
        """
        if self.joint is None:
            return "the feed bound"
        if self.ramp:
            return (f"joint {self.joint}'s acceleration limit (the path speed may change by "
                    f"{self.value:.3g} rad/s² at most there)")  # fmt: skip
        what = {"velocity": "|q'|", "acceleration": "|q''|"}[self.kind]
        unit = {"velocity": "rad/rad", "acceleration": "rad/rad²"}[self.kind]
        return f"joint {self.joint}'s {self.kind} limit ({what} = {self.value:.3g} {unit} there)"


class TimingFailure(ValueError):
    """No usable time law for a path (module doc); a :class:`ValueError` with figures.

    ``reason``: ``"stall"``, ``"too_long"`` or ``"limits"``; ``duration`` [s] the law's
    (inf for a stall, the sampled one for ``limits``); ``s_range`` (2,) the stretch of
    the caller's ``s`` where the time goes (or the first place a limit is broken);
    ``share`` of the duration spent there (NaN: not measured); ``binding``: what holds
    the path speed down there (None for ``limits``); ``path_speed``: the least ``ds/dt``
    there.  ``str()`` is the whole sentence, starting ``time_path: ...``.
    """

    def __init__(self, message: str, *, reason: str, duration: float,
                 s_range: tuple[float, float], share: float = float("nan"),
                 binding: Binding | None = None,
                 path_speed: float = float("nan")) -> None:  # fmt: skip
        super().__init__(message)
        self.reason = reason
        self.duration = duration
        self.s_range = s_range
        self.share = share
        self.binding = binding
        self.path_speed = path_speed


def _ds_dsigma(prob: _Problem, sigma: FloatArray) -> FloatArray:
    """The caller's ``s`` per unit σ (G,) at ``sigma`` (the C¹ interpolation's slope)."""
    sig = np.clip(sigma, prob.sigma[0], prob.sigma[-1])
    return np.maximum(prob.s_map.derivative()(sig), 0.0)


def binding_at(
    prob: _Problem, i: int, vlim: FloatArray, alim: FloatArray, x: float | None = None
) -> Binding:
    """Return the tightest path-speed bound at grid node ``i`` (module doc).

    Joint limits ``vlim``, ``alim`` (J,) as the solver used them.  ``x``: the law's σ̇²
    there; when it lies far below every bound of the node (a tenth), the path is slow
    because it cannot speed up (or must brake early) — the acceleration limit of the joint
    that bounds σ̈ most (``a_j / |q'_j|`` least) binds (``ramp``).
    """
    d1, d2 = np.abs(prob.d1[i]), np.abs(prob.d2[i])
    with np.errstate(divide="ignore"):
        xv = np.where(d1 > 0, (vlim / np.maximum(d1, 1e-300)) ** 2, np.inf)
        xa = np.where(d2 > 0, alim / np.maximum(d2, 1e-300), np.inf)
    jv, ja = int(np.argmin(xv)), int(np.argmin(xa))
    sf_sigma = prob.feed_speed / np.sqrt(prob.x_feed[i]) if prob.x_feed[i] > 0 else np.inf
    cands = [(float(xv[jv]), "velocity", jv + 1, float(d1[jv])),
             (float(xa[ja]), "acceleration", ja + 1, float(d2[ja])),
             (float(prob.x_feed[i]), "feed", None, float(sf_sigma))]  # fmt: skip
    xb, kind, joint, value = min(cands, key=lambda c: c[0])
    rate = float(_ds_dsigma(prob, prob.grid[i : i + 1])[0])
    if x is not None and x < 0.1 * xb:  # not a bound of the node: the ramp to it
        with np.errstate(divide="ignore"):
            ur = np.where(d1 > 0, alim / np.maximum(d1, 1e-300), np.inf)
        j = int(np.argmin(ur))
        return Binding("acceleration", j + 1, x, float(np.sqrt(max(x, 0.0)) * rate),
                       float(ur[j]), ramp=True)  # fmt: skip
    return Binding(kind, joint, xb, float(np.sqrt(max(xb, 0.0)) * rate), value)


def where_time_goes(
    prob: _Problem, x: FloatArray, vlim: FloatArray, alim: FloatArray
) -> tuple[float, tuple[float, float], float, Binding, float]:
    """Of the solved law ``x`` (G,).

    Its duration [s], the slow stretch (caller's ``s``), its share of the duration, the binding
    at the slower node of the stage that takes longest and the least ``ds/dt`` there (module
    doc)."""
    sd = np.sqrt(np.maximum(x, 0.0))
    D = prob.deltas
    den = sd[:-1] + sd[1:]
    with np.errstate(divide="ignore"):
        tau = np.where(den > 0, 2.0 * D / np.maximum(den, 1e-300), np.inf)
    T = float(tau.sum())
    k = int(np.argmax(tau))  # the stage that takes longest (a stalled one: inf)
    stage_speed = 0.5 * den  # mean σ̇ per stage
    slow = stage_speed <= SLOW_FACTOR * stage_speed[k]  # the run of these around k
    before, after = np.flatnonzero(~slow[:k]), np.flatnonzero(~slow[k:])
    a = int(before[-1]) + 1 if before.size else 0
    b = k + int(after[0]) - 1 if after.size else slow.size - 1
    share = float(tau[a : b + 1].sum() / T) if np.isfinite(T) and T > 0 else 1.0
    node = k if sd[k] <= sd[k + 1] else k + 1  # its slower end, away from a rest end
    if prob.grid.size > 2:
        node = min(max(node, 1), prob.grid.size - 2)
    binding = binding_at(prob, node, vlim, alim, float(x[node]))
    s0, s1 = (float(v) for v in prob.s_at(prob.grid[[a, b + 1]]))
    speed = float(stage_speed[k] * _ds_dsigma(prob, prob.grid[k : k + 1])[0])
    return T, (s0, s1), share, binding, speed


def too_long(
    prob: _Problem, x: FloatArray, vlim: FloatArray, alim: FloatArray, dt: float,
    max_samples: int, stalled: bool = False,
) -> TimingFailure:  # fmt: skip
    """Return the :class:`TimingFailure` of a law that lasts too long, with its diagnosis.

    Too long: longer than ``max_samples`` periods of ``dt`` (or never ends: ``stalled``).
    """
    T, (s0, s1), share, b, speed = where_time_goes(prob, x, vlim, alim)
    if stalled or not np.isfinite(T):
        head = (f"time_path: the path speed collapses to zero between s = {s0:.6g} and "
                f"{s1:.6g}")  # fmt: skip
        reason, T = "stall", float("inf")
    else:
        head = (f"time_path: the timed path lasts {T:.6g} s = {int(np.ceil(T / dt)) + 1} "
                f"samples at dt = {dt} s, more than MAX_SAMPLES = {max_samples}; "
                f"{100 * share:.0f} % of it between s = {s0:.6g} and {s1:.6g}")  # fmt: skip
        reason = "too_long"
    msg = (f"{head}, where the path crawls at ds/dt = {speed:.3g} (least); binding "
           f"constraint: {b.words()}, ds/dt <= {b.ds_dt:.3g} there")  # fmt: skip
    return TimingFailure(msg, reason=reason, duration=T, s_range=(s0, s1), share=share,
                         binding=b, path_speed=speed)  # fmt: skip
