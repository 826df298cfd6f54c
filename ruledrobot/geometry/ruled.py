"""Discrete ruled surfaces: striction curve, spherical image, Sannia and DH frames.

A :class:`RuledSurface` is a sequence of oriented lines (rulings), open or
closed; a closed sequence whose last ruling points against its first is closed
*with a flip* (a Möbius band): ruling ``n`` is ruling ``0`` reversed.

Common normals of consecutive rulings (paper section 2.4):

* skew rulings: the unique common normal;
* intersecting rulings: the normal through the intersection point along
  ``l_i x l_{i+1}`` (distance 0);
* parallel rulings (a *run* of consecutive parallel pairs): not unique.  As
  in the paper (Fig. 4) the outermost pedal points of the run — the foot on its
  first ruling of the normal with the ruling before the run and the foot on its
  last ruling of the normal with the ruling after it — are projected onto the
  run's rulings and averaged; the feet on every ruling of the run are the
  projections of the midpoint of those two outer pedal points (for two
  parallel rulings this is exactly the paper's ``M_i``).  When only one outer
  point exists it is used alone; when none does (a cylinder) the centroid of
  the rulings' points nearest the origin is used (documented as the one
  choice that is not translation-equivariant).

Discrete striction points (paper section 2.4, Fig. 5): midpoint of the two feet
on a ruling; the ends of an open surface take their single foot.  With
``at_intersection="intersection"`` a ruling that meets exactly one neighbour
takes the intersection point (the interpolating choice of the paper).

DH frames (``docs/conventions.md``): frame i has origin at the foot on ruling
i of the common normal with ruling i+1, z along ruling i, x along that normal
towards ruling i+1 (``l_i x l_{i+1}`` when they intersect).  The last frame of
an open surface is obtained by extrapolating the frame motion one step along
the screw geodesic through the two previous frames and then moving it onto the
last ruling (origin: orthogonal projection; rotation: the smallest rotation
taking its z axis to the ruling).  This keeps helical surfaces (one-parameter
subgroup orbits) exactly on their orbit, which the paper's rule (foot of the
common normal with the predecessor) does not; with two rulings the paper's
rule is used.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np

from . import se3
from ._arrays import cross, dot, norm
from .checks import FloatArray
from .lines import CommonNormal, Lines, common_normal
from .ranges import run_indices

__all__ = ["RuledSurface", "dh_transform"]


def dh_transform(theta: FloatArray, d: FloatArray, a: FloatArray, alpha: FloatArray) -> FloatArray:
    """Return ``Trans_x(a) Rot_x(alpha) Rot_z(theta) Trans_z(d)`` (..., 4, 4).

    One link of a DH row as returned by :meth:`RuledSurface.dh_parameters` (Craig's
    ordering).
    """
    theta, d, a, alpha = np.broadcast_arrays(
        *(np.asarray(v, dtype=np.float64) for v in (theta, d, a, alpha))
    )
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    T = np.zeros((*theta.shape, 4, 4))
    T[..., 0, 0] = ct
    T[..., 0, 1] = -st
    T[..., 0, 3] = a
    T[..., 1, 0] = ca * st
    T[..., 1, 1] = ca * ct
    T[..., 1, 2] = -sa
    T[..., 1, 3] = -sa * d
    T[..., 2, 0] = sa * st
    T[..., 2, 1] = sa * ct
    T[..., 2, 2] = ca
    T[..., 2, 3] = ca * d
    T[..., 3, 3] = 1.0
    return T


@dataclass(frozen=True)
class RuledSurface:
    """A discrete ruled surface: rulings ``lines`` (N), open or closed.

    ``flip`` (closed only): ``None`` detects it — closed with a flip when the
    last ruling points against the first (``l_{N-1} . l_0 < 0``).
    ``tol`` (m) decides intersecting rulings; ``angle_tol`` (rad) parallel ones.
    """

    lines: Lines
    closed: bool = False
    flip: bool | None = None
    tol: float = 1e-10
    angle_tol: float = 1e-10

    def __post_init__(self) -> None:
        if not isinstance(self.lines, Lines):
            object.__setattr__(self, "lines", Lines(np.asarray(self.lines)))
        n = len(self.lines)
        if n < 2:
            raise ValueError(f"ruled surface: needs at least 2 rulings, got {n}")
        if self.closed and n < 3:
            raise ValueError(f"ruled surface: a closed surface needs at least 3 rulings, got {n}")
        if self.flip is None:
            l = self.lines.direction
            object.__setattr__(self, "flip", bool(self.closed and l[-1] @ l[0] < 0.0))
        elif self.flip and not self.closed:
            raise ValueError("ruled surface: flip=True needs closed=True")

    # -- the successor sequence --------------------------------------------------

    @property
    def n_pairs(self) -> int:
        """Number of consecutive pairs: N - 1 (open) or N (closed)."""
        return len(self.lines) if self.closed else len(self.lines) - 1

    def _next_lines(self) -> FloatArray:
        """Plücker rows of ruling i+1 for every pair i (ruling 0 reversed after a flip)."""
        x = self.lines.plucker
        if not self.closed:
            return x[1:]
        nxt = np.roll(x, -1, axis=0)
        if self.flip:
            nxt[-1] = -nxt[-1]
        return nxt

    def common_normals(self) -> CommonNormal:
        """Common normals of consecutive rulings (pairs (i, i+1)), parallel rule applied."""
        return self._common_normals

    @cached_property
    def _common_normals(self) -> CommonNormal:
        x = self.lines.plucker
        first = x[: self.n_pairs]
        second = self._next_lines()
        cn = common_normal(first, second, angle_tol=self.angle_tol, dist_tol=self.tol)
        if np.any(cn.parallel):
            cn = self._parallel_rule(cn, first, second)
        return cn

    def _parallel_rule(
        self, cn: CommonNormal, first: FloatArray, second: FloatArray
    ) -> CommonNormal:
        m = self.n_pairs
        ref = np.full((m, 3), np.nan)
        fallback = None
        for run in run_indices(cn.parallel, self.closed):
            outer = []
            before, after = run[0] - 1, run[-1] + 1
            if self.closed:
                before, after = before % m, after % m
            if (0 <= before < m) and not cn.parallel[before]:
                outer.append(cn.foot2[before])
            if (0 <= after < m) and not cn.parallel[after]:
                outer.append(cn.foot1[after])
            if outer:
                ref[run] = np.mean(outer, axis=0)
            else:
                if fallback is None:
                    fallback = self.lines.point.mean(axis=0)
                ref[run] = fallback
        par = cn.parallel
        fixed = common_normal(first[par], second[par], reference=ref[par], angle_tol=np.inf)
        fields = {}
        for name in ("foot1", "foot2", "direction", "distance", "angle"):
            arr = getattr(cn, name).copy()
            arr[par] = getattr(fixed, name)
            fields[name] = arr
        return CommonNormal(parallel=cn.parallel, intersecting=cn.intersecting, **fields)

    # -- curves on the surface ----------------------------------------------------

    def striction_points(
        self, at_intersection: Literal["average", "intersection"] = "average"
    ) -> FloatArray:
        """Discrete striction points (N, 3).

        Midpoints of the feet of the common normals with both neighbours (paper section 2.4);
        see the module doc."""
        cn = self.common_normals()
        n = len(self.lines)
        plus = np.empty((n, 3))  # foot on ruling i of the normal with ruling i+1
        minus = np.empty((n, 3))  # foot on ruling i of the normal with ruling i-1
        inter_plus = np.zeros(n, dtype=bool)
        inter_minus = np.zeros(n, dtype=bool)
        if self.closed:
            plus[:] = cn.foot1
            minus[1:] = cn.foot2[:-1]
            minus[0] = cn.foot2[-1]
            inter_plus[:] = cn.intersecting
            inter_minus[:] = np.roll(cn.intersecting, 1)
        else:
            plus[:-1] = cn.foot1
            plus[-1] = cn.foot2[-1]
            minus[1:] = cn.foot2
            minus[0] = cn.foot1[0]
            inter_plus[:-1] = cn.intersecting
            inter_minus[1:] = cn.intersecting
        s = 0.5 * (plus + minus)
        if at_intersection == "intersection":
            only_plus = inter_plus & ~inter_minus
            only_minus = inter_minus & ~inter_plus
            s[only_plus] = plus[only_plus]
            s[only_minus] = minus[only_minus]
        elif at_intersection != "average":
            raise ValueError(
                f"at_intersection: expected 'average' or 'intersection', got {at_intersection!r}"
            )
        return s

    def spherical_image(self) -> FloatArray:
        """Unit directions of the rulings (N, 3): the spherical image."""
        return self.lines.direction.copy()

    def distribution_parameters(self) -> FloatArray:
        """Discrete distribution parameter per pair.

        Pitch ``a/alpha`` (m/rad) of the screw about the common normal taking ruling i to
        ruling i+1 (the paper's limit definition). 0 at torsal pairs; inf at parallel
        (cylindrical) ones; NaN for identical rulings."""
        cn = self.common_normals()
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(cn.parallel & (cn.distance <= self.tol), np.nan, cn.distance / cn.angle)

    def torsal(self) -> np.ndarray:
        """Per pair: consecutive rulings intersect (a discrete torsal ruling)."""
        return self.common_normals().intersecting.copy()

    def cylindrical(self) -> np.ndarray:
        """Per pair: consecutive rulings are parallel (a discrete cylindrical ruling)."""
        return self.common_normals().parallel.copy()

    # -- frames -----------------------------------------------------------------

    def sannia_frames(self) -> FloatArray:
        """Discrete Sannia frames (N, 4, 4) at the striction points (paper Eq. 8).

        ``e1 = l``, ``e2`` = unit part of ``l_{i+1} - l_{i-1}`` normal to ``l_i`` (one-sided at
        open ends), ``e3 = e1 x e2``. Where the spherical image stalls (cylindrical rulings)
        ``e3`` is taken along the common normal."""
        l = self.lines.direction
        n = len(l)
        if self.closed:
            nxt = np.roll(l, -1, axis=0)
            prv = np.roll(l, 1, axis=0)
            if self.flip:
                nxt[-1] = -nxt[-1]
                prv[0] = -prv[0]
        else:
            nxt = np.concatenate([l[1:], l[-1:]])
            prv = np.concatenate([l[:1], l[:-1]])
        d = nxt - prv
        e2 = d - np.einsum("ni,ni->n", d, l)[:, None] * l
        size = norm(e2)
        stalled = size <= self.angle_tol
        e2 = e2 / np.where(stalled, 1.0, size)[:, None]
        if np.any(stalled):
            x = self.common_normals().direction
            xs = np.concatenate([x, x[-1:]]) if not self.closed else x
            e2[stalled] = cross(xs[stalled], l[stalled])
        e3 = cross(l, e2)
        T = np.zeros((n, 4, 4))
        T[:, :3, 0], T[:, :3, 1], T[:, :3, 2] = l, e2, e3
        T[:, :3, 3] = self.striction_points()
        T[:, 3, 3] = 1.0
        return T

    def dh_frames(
        self, x_axis: Literal["towards_next", "continuous"] = "towards_next"
    ) -> FloatArray:
        """DH frames (N, 4, 4) of the rulings (see module doc for the end rule).

        ``x_axis="towards_next"`` (the DH convention of the design): x along the
        common normal pointing from ruling i to ruling i+1.  Where the
        distribution parameter changes sign (the cylindroid at its turning
        rulings; developables everywhere, by rounding) that direction flips by pi
        between neighbours.  ``x_axis="continuous"``: the same origins and z
        axes, with x = sigma (l_i x l_{i+1})/|l_i x l_{i+1}| and one global sign
        sigma (that of the first pair's DH x axis), which is continuous wherever
        the spherical image is regular.  The ``dh`` refinement uses it: the
        refined rulings depend only on origins and z axes, and the screw
        geodesics between frames no longer make half turns.
        """
        if x_axis not in ("towards_next", "continuous"):
            raise ValueError(f"x_axis: expected 'towards_next' or 'continuous', got {x_axis!r}")
        cn = self.common_normals()
        x = cn.direction if x_axis == "towards_next" else self._continuous_x(cn)
        l = self.lines.direction
        n = len(l)
        m = self.n_pairs
        T = np.zeros((n, 4, 4))
        T[:m, :3, 0] = x
        T[:m, :3, 1] = cross(l[:m], x)
        T[:m, :3, 2] = l[:m]
        T[:m, :3, 3] = cn.foot1
        T[:, 3, 3] = 1.0
        if not self.closed:
            T[-1] = self._last_frame(T, cn)
        return T

    def _continuous_x(self, cn: CommonNormal) -> FloatArray:
        """Sign-continuous common-normal directions per pair (see :meth:`dh_frames`)."""
        x = cn.direction.copy()
        m = self.n_pairs
        c = cross(self.lines.direction[:m], self._next_lines()[:, :3])
        ok = ~cn.parallel
        n_hat = c / np.where(ok, norm(c), 1.0)[:, None]
        ref = np.flatnonzero(ok & ~cn.intersecting)
        sigma = 1.0 if ref.size == 0 else float(np.sign(dot(x[ref[0]], n_hat[ref[0]])) or 1.0)
        x[ok] = sigma * n_hat[ok]
        if np.any(cn.parallel) and np.any(ok):
            # a parallel pair's normal is the gap direction: orient it like the
            # nearest non-parallel pair before it (or after it, at the start)
            idx = np.arange(m)
            before = np.maximum.accumulate(np.where(ok, idx, -1))
            after = np.minimum.accumulate(np.where(ok, idx, m)[::-1])[::-1]
            near = np.where(before >= 0, before, after)
            par = cn.parallel
            flip = dot(x[par], x[near[par]]) < 0.0
            x[np.flatnonzero(par)[flip]] *= -1.0
        return x

    def _last_frame(self, T: FloatArray, cn: CommonNormal) -> FloatArray:
        n = len(self.lines)
        if n == 2:
            # the paper's rule: foot of the common normal with the predecessor
            return T[0] @ dh_transform(0.0, 0.0, cn.distance[0], cn.angle[0])
        ext = se3.geodesic(T[n - 3], T[n - 2], 2.0)
        line = self.lines.plucker[-1]
        l, p0 = line[:3], cross(line[:3], line[3:])
        origin = p0 + ((ext[:3, 3] - p0) @ l) * l
        z = ext[:3, 2]
        axis = cross(z, l)
        s, c = norm(axis), float(z @ l)
        if s > 1e-15:
            R = se3.rotation_about_axis(axis / s, np.arctan2(s, c))
        elif c > 0:
            R = np.eye(3)
        else:  # opposite: turn by pi about the frame's x axis
            R = se3.rotation_about_axis(ext[:3, 0], np.pi)
        out = np.eye(4)
        out[:3, :3] = R @ ext[:3, :3]
        out[:3, 3] = origin
        return out

    def dh_parameters(self) -> FloatArray:
        """DH rows ``(theta, d, a, alpha)`` per pair: (N-1, 4) open, (N, 4) closed.

        With the frames of :meth:`dh_frames`,
        ``T_{i+1} = T_i @ Trans_x(a) Rot_x(alpha) Rot_z(theta) Trans_z(d)``
        (:func:`dh_transform`; Craig's "modified" ordering, which is what the
        frame placement of the design gives): ``a >= 0`` and ``alpha`` are the
        distance and twist of rulings i and i+1, ``theta`` and ``d`` the joint
        angle and offset on ruling i+1 between its incoming and outgoing
        normals.  For a closed surface the last row leads to frame 0 (turned by
        pi about x after a flip).
        """
        cn = self.common_normals()
        T = self.dh_frames()
        nxt = np.roll(T, -1, axis=0) if self.closed else T[1:]
        if self.closed and self.flip:
            nxt[-1] = nxt[-1] @ np.diag([1.0, -1.0, -1.0, 1.0])
        X = dh_transform(0.0, 0.0, cn.distance, cn.angle)
        Z = se3.inverse(X) @ se3.inverse(T[: self.n_pairs]) @ nxt
        theta = np.arctan2(Z[:, 1, 0], Z[:, 0, 0])
        return np.stack([theta, Z[:, 2, 3], cn.distance, cn.angle], axis=-1)
