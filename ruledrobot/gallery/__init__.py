"""The paper's six examples (Odehnal, section 4), with numbers: pictures and checks.

:func:`run_gallery` refines each example, measures what the example is meant
to show, writes one PNG per example and ``checks.json``, and returns the same
dictionary::

    {"examples": [{"name", "title", "algorithm", "scheme", "steps", "png",
                   "n_input", "n_refined", "closed", "flip", "seconds",
                   "checks": [{"name", "value", "op", "limit", "passed"}, ...],
                   "measurements": {...}}, ...],
     "passed": bool}

A check passes when ``value <op> limit`` holds (``op`` is ``"<"``, ``">"`` or
``"=="``); values are in metres and radians unless the name says otherwise.
``png`` is the file name relative to the output folder.  See
``docs/gallery.md`` for what each example checks and why.

The examples (surfaces from :mod:`ruledrobot.geometry.surfaces`):

1. cylindroid, 8 rulings ``phi = k pi/8`` (closed with a flip), projection /
   four_point, 5 steps: striction points on the double line (z axis);
2. helical developable, 6 / 12 / 24 tangents over one arc, projection /
   four_point, 4 steps: striction curve -> helix as the input gets denser;
3. four arbitrary lines (seed 7), combined / four_point, 1, 2, 4 steps: the
   input lines are kept exactly;
4. Möbius band, 12 rulings, combined / chaikin, 4 steps, closed with a flip:
   flip kept, line-manifold constraints, closeness to the true band;
5. hyperboloid of revolution, 8 rulings over half the circle, dh / four_point,
   4 steps: every refined ruling on the quadric;
6. helical ruled surface, 6 rulings, dh / four_point, 3 steps: every refined
   ruling (and DH frame) is an image of the first under the helical motion.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..io.atomic import atomic_write_bytes, atomic_write_json
from .examples import _EXAMPLES
from .render import _render

__all__ = ["run_gallery"]

Progress = Callable[[str], None]


def _json_safe(obj: Any) -> Any:
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    return obj


def run_gallery(out_dir: Path | str, progress: Progress | None = None) -> dict[str, Any]:
    """Run the six examples; write ``NN_<name>.png`` and ``checks.json`` into ``out_dir``.

    ``progress(message)`` is called once per finished example.  Pictures are
    drawn on matplotlib's Agg canvas directly (no pyplot, no global backend
    change); every file is written atomically.  Returns the dictionary stored in
    ``checks.json`` (module doc); ``"passed"`` is True when every check passed.
    Non-finite values are stored as ``null`` in the file.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    examples: list[dict[str, Any]] = []
    for k, make in enumerate(_EXAMPLES, 1):
        t0 = time.perf_counter()
        ex = make()
        png = f"{k:02d}_{ex.record['name']}.png"
        atomic_write_bytes(out / png, _render(ex.scene, ex.record["checks"]))
        rec = {**ex.record, "png": png, "seconds": round(time.perf_counter() - t0, 3)}
        examples.append(rec)
        if progress is not None:
            ok = all(c["passed"] for c in rec["checks"])
            progress(
                f"{k}/{len(_EXAMPLES)} {rec['name']}: {'ok' if ok else 'FAILED'} "
                f"({rec['seconds']:.1f} s)"
            )
    result = {
        "format": "ruledrobot.gallery/1",
        "examples": examples,
        "passed": all(c["passed"] for ex in examples for c in ex["checks"]),
    }
    atomic_write_json(out / "checks.json", _json_safe(result))
    return result
