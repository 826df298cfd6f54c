"""Branch and bound over the options of many groups at once: the best option of each
group when every option's value is at most a known bound (the reachability map: the
IK branches of a cell; the placement search: the columns of a candidate)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...geometry.checks import FloatArray

__all__ = ["best_of"]


def best_of(
    bound: FloatArray,
    evaluate: Callable[[np.ndarray, np.ndarray, FloatArray], FloatArray],
    per_round: int = 1,
    max_rounds: int | None = None,
) -> tuple[FloatArray, np.ndarray, np.ndarray]:
    """Per group the best option's value, where each option's value is at most its bound.

    ``bound`` (n, k): an upper bound of each option's value; ``evaluate(g, o, floor)``
    the values (len(g),) of options ``o`` of groups ``g`` (index arrays), where an
    option that cannot beat ``floor`` (the group's best so far) may get any value
    ``<= floor``.  Options are
    evaluated best bound first, ``per_round`` per group and round, for the groups
    whose next bound still exceeds their best value (branch and bound: the result is
    exact).  Returns ``(best (n,), option (n,), exact (n,))``; ``exact`` is False for
    the groups whose search ``max_rounds`` stopped (``best`` is then a lower bound).
    """
    n, k = bound.shape
    order = np.argsort(-bound, axis=1, kind="stable")
    best = np.full(n, -np.inf)
    arg = order[:, 0].copy()
    rounds = 0
    for start in range(0, k, per_round):
        opts = order[:, start:start + per_round]
        b = np.take_along_axis(bound, opts, axis=1)
        active = b > best[:, None]
        if not active.any():
            break
        if max_rounds is not None and rounds >= max_rounds:
            return best, arg, ~active.any(axis=1)
        g, j = np.nonzero(active)
        o = opts[g, j]
        val = np.minimum(evaluate(g, o, best[g]), bound[g, o])
        # the best new value per group
        srt = np.lexsort((-val, g))
        g, o, val = g[srt], o[srt], val[srt]
        head = np.r_[True, g[1:] != g[:-1]]
        g, o, val = g[head], o[head], val[head]
        better = val > best[g]
        best[g[better]] = val[better]
        arg[g[better]] = o[better]
        rounds += 1
    return best, arg, np.ones(n, bool)
