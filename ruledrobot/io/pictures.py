"""Time series thinned for a picture: what a line plot of ``N`` samples draws in a few
hundred pixel columns, in a fraction of the points (the M4 aggregation: Jugel et al.,
"M4: a visualization-oriented time series data aggregation", PVLDB 7(10), 2014).

Per bucket of consecutive samples the first, the lowest, the highest and the last are
kept in their order; a line through them crosses every pixel the whole line crosses in a
column as wide as the bucket.  The planner's and the playback's plots of 60,000-sample
motions draw under 5,000 points a series instead, and the same picture.

:func:`write_png` writes a figure as a PNG atomically, at :data:`PNG_COMPRESS_LEVEL`.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..geometry.checks import FloatArray
from .atomic import atomic_write_bytes

__all__ = ["BUCKETS", "PNG_COMPRESS_LEVEL", "thinned_series", "write_png"]

#: buckets per series: more than the pixel columns of the widest time axis drawn (the
#: playback's plots, 0.9 of 9 in at 100 dpi: 810 columns; the plan's, 600)
BUCKETS = 1200
#: zlib level of the PNGs written (Pillow's ``compress_level``; its default is 6).  The same
#: pixels; on the plan's and the playback's pictures level 3 encodes in about 0.7 of the
#: time of level 6 for files 2-10 % larger (``scripts/bench_pictures.py``)
PNG_COMPRESS_LEVEL = 3


def thinned_series(t: FloatArray, y: FloatArray, buckets: int = BUCKETS
                   ) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """Return ``t`` (N,) and ``y`` (N,) or (N, J) thinned to at most ``4 * buckets`` samples.

    Per series (module doc), for ``ax.plot(*thinned_series(t, y))``.

    Returns
    -------
    t_kept, y_kept : ndarray
        (M,) and (M,) for a single series; (M, J) each for ``J`` series (each column its
        own samples).  The input itself when it is short enough or holds a NaN or an
        infinity (a gap drawn as a gap).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    n = len(t)
    size = -(-n // buckets)  # samples per bucket, rounded up
    if size < 5 or not np.isfinite(y).all():
        return t, y
    one = y.ndim == 1
    Y = y[:, None] if one else y
    m = -(-n // size)  # buckets; the last one filled up with the last sample
    idx = np.minimum(np.arange(m * size), n - 1).reshape(m, size)
    V = Y[idx]  # (m, size, J)
    first = idx[:, :1, None] + np.zeros((1, 1, Y.shape[1]), dtype=np.intp)
    last = idx[:, -1:, None] + np.zeros((1, 1, Y.shape[1]), dtype=np.intp)
    low = idx[:, 0, None, None] + np.argmin(V, axis=1)[:, None, :]
    high = idx[:, 0, None, None] + np.argmax(V, axis=1)[:, None, :]
    keep = np.sort(np.concatenate([first, low, high, last], axis=1), axis=1)  # (m, 4, J)
    keep = keep.reshape(m * 4, -1)
    cols = np.arange(Y.shape[1])[None, :]
    tk, yk = t[keep], Y[keep, cols]
    return (tk[:, 0], yk[:, 0]) if one else (tk, yk)


def write_png(fig: Any, path: str | os.PathLike[str], dpi: float | str = "figure") -> Path:
    """Write the matplotlib Figure ``fig`` to ``path`` as a PNG, atomically; return the path.

    Drawn at ``dpi`` (the figure's own by default) and compressed at
    :data:`PNG_COMPRESS_LEVEL`."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, pil_kwargs={"compress_level": PNG_COMPRESS_LEVEL})
    return atomic_write_bytes(path, buf.getvalue())
