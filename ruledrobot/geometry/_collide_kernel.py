"""Compiled (numba) kernels of the clearance rules: capsule pairs, segments and a box.

:func:`pairs_within` answers, for each of ``n`` configurations, whether any pair of a
group of capsule pairs is nearer than the pair's reach (the radii plus a margin): the
arm against itself and the bow against the arm (:func:`ruledrobot.wirecut.cut.clearance`,
a ``self_collision`` cell).  One loop over configurations and pairs, every intermediate
a scalar: a broad phase of bounding spheres (the centres' distance less both half
lengths, a lower bound of the axes' distance), then the exact distance of the axes
(:func:`segment_distance`, the formulas of :func:`ruledrobot.geometry.segments.segment_distance`:
Ericson, *Real-Time Collision Detection*, 5.1.9), and a group stops at its first hit.
The numpy path built (n, P, 3) temporaries and took 6.6 ms a call on the carve tests'
batches, a third of the robot check's time (measured, issue 34).

:func:`segments_hit_box` is :meth:`ruledrobot.geometry.box.Box.segment_hits` (the slab
method of :meth:`~ruledrobot.geometry.box.Box.clip_lines`, one segment at a time): 18
times faster than the numpy path's temporaries on the clearance's batches (54,000
segments: 0.9 ms against 16.7 ms, measured).

Imported on first use (``import ruledrobot`` does not load numba); compiled once and
cached next to this file (``cache=True``).  It imports nothing of the project so that
numba's cache stays valid.  No ``fastmath``.  ``tests/geometry/test_collide_kernel.py``
holds each kernel to its numpy formula.
"""

from __future__ import annotations

import math

import numba as nb
from numba import types

_TINY = 1e-18

_F8_4D = types.Array(types.float64, 4, "C", readonly=True)
_F8_1D = types.Array(types.float64, 1, "C", readonly=True)
_I8_1D = types.Array(types.int64, 1, "C", readonly=True)
_B_1D = types.Array(types.boolean, 1, "C", readonly=True)
_F8_2D = types.Array(types.float64, 2, "C", readonly=True)


@nb.njit(cache=True, nogil=True, error_model="numpy")
def segment_distance(p, q, r, s):  # pragma: no cover - compiled
    """Return the smallest distance between segments ``p -> q`` and ``r -> s`` (3,) each.

    The numpy path's formulas and cases, one pair (degenerate segments handled)."""
    d10, d11, d12 = q[0] - p[0], q[1] - p[1], q[2] - p[2]
    d20, d21, d22 = s[0] - r[0], s[1] - r[1], s[2] - r[2]
    r0, r1, r2 = p[0] - r[0], p[1] - r[1], p[2] - r[2]
    a = d10 * d10 + d11 * d11 + d12 * d12
    e = d20 * d20 + d21 * d21 + d22 * d22
    f = d20 * r0 + d21 * r1 + d22 * r2
    c = d10 * r0 + d11 * r1 + d12 * r2
    b = d10 * d20 + d11 * d21 + d12 * d22
    pa = a > _TINY
    pe = e > _TINY
    denom = a * e - b * b
    u = 0.0
    if pa and pe and denom > _TINY * max(a * e, _TINY):
        u = (b * f - c * e) / denom
    u = min(max(u, 0.0), 1.0)
    if pa and not pe:
        u = min(max(-c / a, 0.0), 1.0)
    elif not pa:
        u = 0.0
    v = (b * u + f) / e if pe else 0.0
    vc = min(max(v, 0.0), 1.0)
    if vc != v and pa:
        u = min(max((b * vc - c) / a, 0.0), 1.0)
    x = r0 + u * d10 - vc * d20
    y = r1 + u * d11 - vc * d21
    z = r2 + u * d12 - vc * d22
    return math.sqrt(x * x + y * y + z * z)


@nb.njit(
    types.void(_F8_4D, _I8_1D, _I8_1D, _F8_1D, _F8_1D, _B_1D, types.boolean[:, ::1]),
    cache=True, nogil=True, error_model="numpy",
)
def pairs_within(E, I, J, reach, half, group, out):  # pragma: no cover - compiled
    """Set ``out[i, g]`` when a pair ``p`` of group ``g`` is nearer than ``reach[p]``.

    ``E`` (n, C, 2, 3) the capsules' axes at each configuration [m]; ``I``, ``J`` (P,)
    the pairs' capsule indices; ``reach`` (P,) [m]; ``half`` (C,) each capsule's half
    length [m]; ``group`` (P,) True for group 1, False for group 0; ``out`` (n, 2) False
    on entry.
    """
    for i in range(E.shape[0]):
        e = E[i]
        for k in range(I.shape[0]):
            g = 1 if group[k] else 0
            if out[i, g]:
                continue
            a, b = e[I[k]], e[J[k]]
            cx = 0.5 * (a[0, 0] + a[1, 0] - b[0, 0] - b[1, 0])
            cy = 0.5 * (a[0, 1] + a[1, 1] - b[0, 1] - b[1, 1])
            cz = 0.5 * (a[0, 2] + a[1, 2] - b[0, 2] - b[1, 2])
            gap = math.sqrt(cx * cx + cy * cy + cz * cz) - half[I[k]] - half[J[k]]
            if gap >= reach[k]:
                continue
            if segment_distance(a[0], a[1], b[0], b[1]) < reach[k]:
                out[i, g] = True


@nb.njit(
    types.void(_F8_2D, _F8_2D, _F8_1D, _F8_1D, _F8_2D, _F8_1D, types.boolean[::1]),
    cache=True, nogil=True, error_model="numpy",
)
def segments_hit_box(a, b, margin, centre, R, half, out):  # pragma: no cover - compiled
    """Set ``out[i]``: segment ``a[i] -> b[i]`` (N, 3) touches the box grown by ``margin[i]``.

    The box: ``centre`` (3,), axes the columns of ``R`` (3, 3), half edge lengths
    ``half`` (3,) [m].  The slab method in box coordinates (``p = (a - centre) R``,
    ``d = (b - a) R``): the line meets slab ``k`` for ``t`` between ``(+-h_k - p_k) / d_k``,
    everywhere or nowhere when ``|d_k| <= 1e-15``; the segment touches when the chord
    ``t_in < t_out`` meets ``[0, 1]``.  A point segment: whether the point is inside.
    """
    for i in range(a.shape[0]):
        a0, a1, a2 = a[i, 0] - centre[0], a[i, 1] - centre[1], a[i, 2] - centre[2]
        e0, e1, e2 = b[i, 0] - a[i, 0], b[i, 1] - a[i, 1], b[i, 2] - a[i, 2]
        point = e0 == 0.0 and e1 == 0.0 and e2 == 0.0
        t_in, t_out = -math.inf, math.inf
        inside = True
        for k in range(3):
            p = a0 * R[0, k] + a1 * R[1, k] + a2 * R[2, k]
            h = half[k] + margin[i]
            if abs(p) > h:
                inside = False
            if point:
                continue
            d = e0 * R[0, k] + e1 * R[1, k] + e2 * R[2, k]
            if abs(d) <= 1e-15:
                if abs(p) > h:
                    t_in, t_out = math.inf, -math.inf
            else:
                t1 = (-h - p) / d
                t2 = (h - p) / d
                t_in = max(t_in, min(t1, t2))
                t_out = min(t_out, max(t1, t2))
        if point:
            out[i] = inside
        else:
            out[i] = t_out > t_in and t_out >= 0.0 and t_in <= 1.0
