"""The predicted kerf and the heat in the viewer (docs/view.md, "Kerf and heat").

The trace of the wire's two chord ends on the part's face, coloured by the kerf predicted
there (:attr:`.scene.Timeline.kerf`, from ``Trajectory.face_errors``: the verdict's own
model on the folder's trajectory), its colour scale as HTML (the export's panel and the
live server's), and the words of the caption and the panel.  No viewer library here.
"""

from __future__ import annotations

import numpy as np

from ..geometry._arrays import FloatArray
from .scene import PlanScene, Timeline

__all__ = ["BURN_COLOUR", "BURN_RADIUS", "burn_points", "heat_words", "kerf_colours",
           "kerf_legend_html", "kerf_range", "kerf_trace", "kerf_words"]

#: the colour scale: viridis at five stops (RGB), narrow (dark) to wide (yellow)
STOPS = np.array([(68, 1, 84), (59, 82, 139), (33, 145, 140), (94, 201, 98), (253, 231, 37)])
#: a burn (the wire stops in the foam with the heat on: no finite kerf); its marker [m]
BURN_COLOUR, BURN_RADIUS = (255, 0, 255), 0.004
#: m: the scale spans at least this (a constant kerf shows one colour mid-scale)
MIN_SPAN = 1e-4


def kerf_range(scene: PlanScene) -> tuple[float, float] | None:
    """The colour scale's ends [m], None without a predicted kerf.

    The smallest and largest finite kerf of the timeline and the cut's planned kerf
    (``limits["kerf_set"]``), widened about their middle to :data:`MIN_SPAN`."""
    tl = scene.timeline
    finite = np.zeros(0) if tl is None or tl.kerf is None else tl.kerf[np.isfinite(tl.kerf)]
    if not finite.size:
        return None
    planned = scene.limits.get("kerf_set", np.nan)
    finite = np.r_[finite, planned] if np.isfinite(planned) else finite
    lo, hi = float(finite.min()), float(finite.max())
    mid = 0.5 * (lo + hi)
    half = max(0.5 * (hi - lo), 0.5 * MIN_SPAN)
    return mid - half, mid + half


def kerf_colours(w: FloatArray, lo: float, hi: float) -> np.ndarray:
    """RGB (..., 3) uint8 of kerfs ``w`` [m] on the scale ``[lo, hi]``.

    Clipped to the scale; :data:`BURN_COLOUR` where ``w`` is infinite."""
    w = np.asarray(w, dtype=np.float64)
    x = np.clip((np.where(np.isfinite(w), w, lo) - lo) / (hi - lo), 0.0, 1.0)
    at = np.linspace(0.0, 1.0, len(STOPS))
    rgb = np.stack([np.interp(x, at, STOPS[:, c]) for c in range(3)], axis=-1)
    rgb = np.where(np.isinf(w)[..., None], np.array(BURN_COLOUR, dtype=float), rgb)
    return np.rint(rgb).astype(np.uint8)


def kerf_trace(tl: Timeline) -> tuple[FloatArray, FloatArray] | None:
    """The chord ends' paths on the face between consecutive frames, both ends.

    Segments (S, 2, 3) world m and their kerf (S, 2) m at each segment's points (the
    frames' own); None without a predicted kerf on any frame."""
    if tl.kerf is None:
        return None
    on = ~np.isnan(tl.kerf) & np.isfinite(tl.chord).all(axis=2)  # (K, 2)
    both = on[:-1] & on[1:]  # (K-1, 2)
    k, j = np.nonzero(both)
    if not k.size:
        return None
    seg = np.stack([tl.chord[k, j], tl.chord[k + 1, j]], axis=1)
    return seg, np.stack([tl.kerf[k, j], tl.kerf[k + 1, j]], axis=1)


def burn_points(tl: Timeline) -> FloatArray:
    """The chord ends (B, 3) [world m] where a run of burning frames begins.

    A stop leaves no trace to colour: it gets a marker."""
    if tl.kerf is None:
        return np.zeros((0, 3))
    burn = np.isinf(tl.kerf)  # (K, 2)
    start = burn & ~np.vstack([np.zeros((1, 2), dtype=bool), burn[:-1]])
    return tl.chord[start]


def _mm(w: float) -> str:
    return "burn" if np.isinf(w) else f"{w * 1e3:.3f}"


def kerf_words(tl: Timeline, k: int) -> str | None:
    """The kerf at frame ``k`` in words: ``"kerf 0.800 / 0.925 mm"``.

    Wire start / end side; ``burn`` where the wire stands hot; None off the face or
    without a predicted kerf."""
    if tl.kerf is None or np.isnan(tl.kerf[k]).any():
        return None
    return f"kerf {_mm(tl.kerf[k, 0])} / {_mm(tl.kerf[k, 1])} mm"


def heat_words(tl: Timeline, k: int) -> str | None:
    """The heat at frame ``k`` in words: ``"heat 50.0 W/m (wire 48.2)"``.

    The set-point and the wire's power after the lag; None without a heat schedule."""
    if tl.heat_power is None:
        return None
    return f"heat {tl.heat_power[k]:.1f} W/m (wire {tl.wire_power[k]:.1f})"


def kerf_legend_html(scene: PlanScene) -> str:
    """The colour scale of the kerf trace as HTML ("" without a predicted kerf).

    A gradient bar, its ends and the cut's planned kerf in mm, the burn colour."""
    tl = scene.timeline
    rng = kerf_range(scene)
    if rng is None or tl is None or tl.kerf is None:
        return ""
    lo, hi = rng
    stops = ", ".join(f"rgb{tuple(int(c) for c in s)}" for s in STOPS)
    planned = scene.limits.get("kerf_set", np.nan)
    mark = ""
    if np.isfinite(planned):
        left = 100.0 * (planned - lo) / (hi - lo)
        mark = (f"<div style='position:absolute;left:{left:.1f}%;top:-2px;bottom:-2px;"
                "border-left:2px solid #000'></div>")  # fmt: skip
    burn = (f"<div><span style='color:rgb{BURN_COLOUR}'>■</span> burn (a stop with the heat "
            "on)</div>" if np.isinf(tl.kerf).any() else "")  # fmt: skip
    return (
        "<div style='font:12px/1.35 sans-serif'>predicted kerf on the part's face "
        "(the wire's chord ends' trace)"
        "<div style='position:relative;height:10px;margin:3px 0;border:1px solid #888;"
        f"background:linear-gradient(to right, {stops})'>{mark}</div>"
        f"<div style='display:flex;justify-content:space-between'><span>{lo * 1e3:.3f} mm"
        f"</span><span>{hi * 1e3:.3f} mm</span></div>"
        + (f"<div>black mark: the cut's kerf {planned * 1e3:.3f} mm</div>" if mark else "")
        + burn + "</div>"
    )
