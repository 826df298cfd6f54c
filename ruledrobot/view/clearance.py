"""Collisions and near misses along a motion: where and when, from MuJoCo's collision detection.

The plan's reports say *that* and *when* parts collided (geom names, times,
depth); the viewer also needs *where*.  :func:`contacts_along` runs MuJoCo's
own collision detection (``mj_kinematics`` + ``mj_collision``) at given
joint positions with every geom's margin set to ``margin``: each contact it
reports is a pair of geoms closer than ``margin`` (``dist`` < 0 is a
penetration) with the point midway between them.  The contact filter is the
scene's own: the wire never meets the stock it cuts, joint neighbours and the
excluded link pairs never meet (``docs/sim.md``).

:func:`near_misses` merges those contacts into events per geom pair;
pairs whose distance never changes (a link turning about its own axis above
the table) are structure, not events, and are left out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["Contact", "Event", "contacts_along", "locate", "near_misses"]


@dataclass(frozen=True)
class Contact:
    """Two geoms closer than the margin at sample ``index``.

    ``distance`` m (< 0: penetration depth), ``position`` (3,) world m, midway between the
    surfaces."""

    index: int
    geom1: str
    geom2: str
    distance: float
    position: tuple[float, float, float]


@dataclass(frozen=True)
class Event:
    """A collision or a near miss, for the viewer's markers and list.

    ``kind``: ``"collision"`` or ``"near miss"``; ``what``: the two parts;
    ``start``, ``end``: s; ``time``: s, the worst moment; ``phase`` there;
    ``distance_mm``: smallest distance (negative: the deepest penetration);
    ``position``: (3,) world m where it happens, or None when the folder holds
    no motion to locate it on; ``source``: who found it.
    """

    kind: str
    what: str
    start: float
    end: float
    time: float
    phase: str
    distance_mm: float
    position: tuple[float, float, float] | None = field(default=None)
    source: str = ""

    @property
    def sentence(self) -> str:
        """The event in words: what, how close, when, in which phase."""
        span = (f"at t = {self.time:.2f} s" if self.end - self.start < 1e-9
                else f"from t = {self.start:.2f} s to {self.end:.2f} s")  # fmt: skip
        if self.distance_mm < 0:
            size = f"{-self.distance_mm:.1f} mm deep"
        else:
            size = f"{self.distance_mm:.1f} mm apart"
        return f"{self.kind}: {self.what}, {size}, {span} ({self.phase})"


def contacts_along(mj: Any, model: Any, q: ArrayLike, margin: float) -> list[Contact]:
    """MuJoCo contacts within ``margin`` (m) at each row of ``q`` (K, J).

    ``model`` is a compiled ``mujoco.MjModel`` of the scene; it is not changed
    (the margins are set on a copy).
    """
    import copy

    m = copy.copy(model)
    m.geom_margin[:] = float(margin)
    m.geom_gap[:] = 0.0
    d = mj.MjData(m)
    qa = np.atleast_2d(np.asarray(q, dtype=np.float64))
    J = qa.shape[1]
    names = [mj.mj_id2name(m, mj.mjtObj.mjOBJ_GEOM, g) or f"geom{g}" for g in range(m.ngeom)]
    out: list[Contact] = []
    for k in range(qa.shape[0]):  # one pass through MuJoCo per sample
        d.qpos[:J] = qa[k]
        mj.mj_kinematics(m, d)
        mj.mj_collision(m, d)
        for c in d.contact[: d.ncon]:
            g1, g2 = sorted((names[c.geom1], names[c.geom2]))
            out.append(Contact(k, g1, g2, float(c.dist), tuple(float(x) for x in c.pos)))
    return out


def near_misses(
    contacts: list[Contact],
    t: ArrayLike,
    phases: ArrayLike,
    threshold: float,
    *,
    samples: int | None = None,
) -> list[Event]:
    """Events from :func:`contacts_along` contacts.

    Per geom pair, each run of samples closer than ``threshold`` (m) becomes one event at its
    closest sample.

    ``t`` (K,) s and ``phases`` (K,) names of the samples the contacts were found
    at.  Penetrations are ``"collision"`` events, the rest ``"near miss"``.  A
    pair found at every one of the ``samples`` (default ``len(t)``) with a
    distance that varies by less than 1 mm is structure and is skipped.
    """
    ta = np.asarray(t, dtype=np.float64)
    ph = np.asarray(phases)
    n = ta.size if samples is None else samples
    by_pair: dict[tuple[str, str], list[Contact]] = {}
    for c in contacts:
        by_pair.setdefault((c.geom1, c.geom2), []).append(c)
    events: list[Event] = []
    for (g1, g2), cs in sorted(by_pair.items()):
        idx = np.array([c.index for c in cs])
        dist = np.array([c.distance for c in cs])
        # several contacts of one pair at one sample: keep the closest
        order = np.lexsort((dist, idx))
        idx, dist = idx[order], dist[order]
        first = np.r_[True, idx[1:] != idx[:-1]]
        keep = order[first]
        idx, dist = idx[first], dist[first]
        if np.unique(idx).size == n and np.ptp(dist) < 1e-3:
            continue
        close = dist < threshold
        if not close.any():
            continue
        # runs of consecutive sample indices that are close
        sel = np.flatnonzero(close)
        breaks = np.flatnonzero(np.diff(idx[sel]) > 1) + 1
        for run in np.split(sel, breaks):
            j = run[np.argmin(dist[run])]
            c = cs[keep[j]]
            events.append(Event(
                "collision" if dist[j] < 0 else "near miss", f"{g1} – {g2}",
                float(ta[idx[run[0]]]), float(ta[idx[run[-1]]]), float(ta[idx[j]]),
                str(ph[idx[j]]), float(dist[j] * 1e3), c.position, "viewer (MuJoCo)",
            ))  # fmt: skip
    return sorted(events, key=lambda e: e.time)


def locate(
    contacts: list[Contact], geom1: str, geom2: str
) -> tuple[int, float, tuple[float, float, float]] | None:
    """The deepest contact of the pair ``geom1``, ``geom2`` among ``contacts``.

    ``(index, distance m, position)``, or None when the pair is not among them."""
    pair = tuple(sorted((geom1, geom2)))
    cs = [c for c in contacts if (c.geom1, c.geom2) == pair]
    if not cs:
        return None
    c = min(cs, key=lambda c: c.distance)
    return c.index, c.distance, c.position
