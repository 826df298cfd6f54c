"""The placement search's candidates scored on the batch engine's workers.

``ruledrobot place --workers N`` (a local cluster of N processes) or ``--scheduler
tcp://HOST:8786`` (a running cluster) scores the candidate placements on Dask
workers instead of in the command's own process.  The evaluator — the job's passes
as sampled rulings and their wire poses, the cell, the rules; about 0.15 MB for the
demo job — goes to every worker once (``Client.scatter(broadcast=True)``); every
call of the search (the grid, each refinement round, the yaw sweep, each setup's
search) splits its candidates into about two chunks per worker thread, scores them
there (the candidates dealt out round robin: neighbours cost alike) and joins
the scores in order: the scores are those of one process, bit for
bit (``tests/batch/test_place_dask.py`` compares them).  A chunk whose worker dies
or fails is scored again here, and the lines say so.  The verification of the best
placement by the planner and MuJoCo runs here.

Decision: in-process stays the default.  The search of a 2,000-ruling job takes
about 10-20 s on one core, and a local cluster costs about 3 s to start (its
workers' imports): a cluster pays off on jobs of many cuts, fine grids, or a
machine with more cores than this one (docs/place.md, "Measured").
"""

from __future__ import annotations

import math
from itertools import pairwise
from typing import Any

import numpy as np

from ..wirecut.reach.evaluate import Evaluator, Scores
from .engine import Engine

__all__ = ["DistributedEvaluator"]

#: fewest candidates per chunk (smaller chunks cost more in dispatch than they save)
MIN_CHUNK = 8
#: chunks per worker thread (the last chunks balance the load)
CHUNKS_PER_THREAD = 4


def _score(ev: Evaluator, T: np.ndarray) -> Scores:
    """A worker's task: the scores of the candidates T (C, 4, 4)."""
    return ev(T)


class DistributedEvaluator:
    """An :class:`~ruledrobot.wirecut.reach.evaluate.Evaluator` that scores on Dask workers.

    Its calls score the candidates on the workers of ``engine`` (an open
    :class:`.engine.Engine`); every other attribute is the evaluator's own.  ``notes``
    collects what went wrong on the way (chunks scored here instead).
    """

    def __init__(self, ev: Evaluator, engine: Engine, notes: list[str] | None = None,
                 _shared: Any = None) -> None:  # fmt: skip
        self._ev = ev
        self._engine = engine
        self.notes = [] if notes is None else notes
        self._shared = _shared

    def __getattr__(self, name: str) -> Any:
        return getattr(self._ev, name)

    def subset(self, cuts: list[int]) -> DistributedEvaluator:
        """:meth:`Evaluator.subset` scored on the same workers."""
        return DistributedEvaluator(self._ev.subset(cuts), self._engine, self.notes)

    def engine_info(self) -> dict[str, Any]:
        """How the candidates were scored (for ``place.json``)."""
        return self._engine.describe()

    def __call__(self, T: np.ndarray) -> Scores:
        """Scores of candidate placements T (C, 4, 4), as :meth:`Evaluator.__call__`."""
        T = np.asarray(T, dtype=np.float64).reshape(-1, 4, 4)
        client = self._engine.client
        if self._shared is None:
            self._shared = client.scatter(self._ev, broadcast=True, hash=False)
        n = max(1, self._engine.threads())
        k = max(1, min(CHUNKS_PER_THREAD * n, math.ceil(len(T) / MIN_CHUNK)))
        # dealt out like cards: neighbouring candidates cost alike (the branch and bound
        # works longest near the edge of the feasible region), so every chunk gets a mix
        order = np.concatenate([np.arange(i, len(T), k) for i in range(k)])
        bounds = np.cumsum([0] + [len(range(i, len(T), k)) for i in range(k)])
        chunks = [T[order[a:b]] for a, b in pairwise(bounds)]
        futures = [client.submit(_score, self._shared, c, pure=False) for c in chunks]
        parts: list[Scores] = []
        for i, (chunk, fut) in enumerate(zip(chunks, futures, strict=True)):
            try:
                parts.append(fut.result())
            except Exception as exc:  # a dead or failing worker: score the chunk here
                self.notes.append(f"{len(chunk)} candidates (chunk {i + 1} of {k}) scored "
                                  f"in this process: the worker failed ({type(exc).__name__})")
                parts.append(self._ev(chunk))
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        return Scores.concat(parts).take(back)
