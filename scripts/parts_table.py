"""Issue 32's proof table: each closed-form part made by ``ruledrobot make`` in the demo cell.

For every part of :data:`ruledrobot.carve.samples.PARTS` (or those named) this writes the
part and its cell file (the 200 x 200 x 150 mm block, UR5e, 0.4 m bow, 12 mm/s), runs
:func:`ruledrobot.make.make` on it, one part at a time, and prints one row per part: the
cuts (exact / rough), the setups, each setup's verdict with its failing checks, the excess
material, the cutting time and make's wall time.  ``--json FILE`` keeps the rows.

    PYTHONPATH=. python scripts/parts_table.py [PART ...] [--out DIR] [--json FILE]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from ruledrobot.carve.samples import PARTS, write_part_cell
from ruledrobot.make import make


def row(name: str, out: Path) -> dict:
    """Make part ``name`` under ``out``; its row of the table."""
    cell = write_part_cell(out / f"{name}-part", name)
    t = time.perf_counter()
    try:
        res = make(cell, out / name)
    except ValueError as exc:  # bad input: make wrote nothing
        return {"part": name, "error": str(exc).splitlines()[0],
                "wall_s": round(time.perf_counter() - t, 1)}  # fmt: skip
    wall = time.perf_counter() - t
    doc = res.document
    c = doc["carve"]
    setups = [{"setup": s["setup"], "cuts": s["cuts"], "ok": s["ok"],
               "failed": [f["name"] for f in s["failed"]],
               "why": [f["detail"][:160] for f in s["failed"]],
               "cut_s": s["cut_duration_s"]} for s in doc["setups"]]  # fmt: skip
    return {"part": name, "ok": res.ok, "exact": c["exact_cuts"], "rough": c["rough_cuts"],
            "setups": c["setups"], "carve_ok": c["ok"], "carve_failed": c["failed"],
            "excess_pct": round(100 * c["excess"], 2), "per_setup": setups,
            "cut_s": doc["totals"]["cut_duration_s"], "wall_s": round(wall, 1),
            "timings_s": doc["timings_s"]}  # fmt: skip


def line(r: dict) -> str:
    """One row as text."""
    if "error" in r:
        return f"{r['part']:15s} exit 2: {r['error']}  ({r['wall_s']} s)"
    verdicts = "; ".join(f"{s['setup']}:{'PASS' if s['ok'] else 'FAIL ' + ','.join(s['failed'])}"
                         for s in r["per_setup"]) or ("carve FAIL " + ",".join(r["carve_failed"]))
    cut = "-" if r["cut_s"] is None else f"{r['cut_s']:.1f}"
    return (f"{r['part']:15s} {r['exact']:>2d}e/{r['rough']}r {r['setups']:>2d} setups  "
            f"{verdicts:40s} excess {r['excess_pct']:6.2f} %  cutting {cut:>6s} s  "
            f"make {r['wall_s']:6.1f} s")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("parts", nargs="*", default=list(PARTS), help="parts (default: all)")
    ap.add_argument("--out", type=Path, help="folder for the parts and make's output")
    ap.add_argument("--json", type=Path, help="write the rows here")
    a = ap.parse_args(argv)
    unknown = [p for p in a.parts if p not in PARTS]
    if unknown:
        print(f"unknown part(s) {unknown}; expected from {list(PARTS)}", file=sys.stderr)
        return 2
    out = a.out or Path(tempfile.mkdtemp(prefix="parts-table-"))
    rows = []
    for name in a.parts:
        r = row(name, out)
        rows.append(r)
        print(line(r), flush=True)
        for s in r.get("per_setup", []):
            for f, why in zip(s["failed"], s["why"], strict=True):
                print(f"    setup {s['setup']} {f}: {why}")
        if a.json:
            a.json.write_text(json.dumps(rows, indent=1))
    return 0 if all(r.get("ok") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
