"""One home for a fact (issue 34): a second spelling of a run finder or of a JSON file
writer fails here, naming the file and line.

* runs of a boolean mask: :mod:`ruledrobot.geometry.ranges` (half-open ``(start, stop)``);
  nine spellings with half-open and inclusive ends mixed were found in review;
* the product's JSON files: :func:`ruledrobot.io.atomic.atomic_write_json` (atomic, one
  layout); thirteen writers each spelled ``json.dumps`` and its indent.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "ruledrobot"

#: a run finder's tell-tale: the diff of a mask padded with zeros, or its -1 edges
RUN_FINDER = re.compile(r"np\.diff\(\s*np\.(?:r_\[|concatenate\(\s*\[\s*\[)\s*(?:0|False)\b"
                        r"|flatnonzero\(\s*\w+\s*==\s*-1\s*\)")  # fmt: skip
#: a JSON file written by hand: json.dump to a file, or json.dumps handed to a writer
JSON_WRITER = re.compile(r"json\.dump\(|(?:write_text|atomic_write_text|\.write)\([^)]*json\.dumps")


def _offences(pattern: re.Pattern[str], home: str) -> list[str]:
    out = []
    for p in sorted(ROOT.rglob("*.py")):
        rel = p.relative_to(ROOT.parent).as_posix()
        if rel == home:
            continue
        text = p.read_text(encoding="utf-8")
        for m in pattern.finditer(text):
            out.append(f"{rel}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}")
    return out


def test_runs_of_a_mask_have_one_home() -> None:
    bad = _offences(RUN_FINDER, "ruledrobot/geometry/ranges.py")
    assert not bad, ("runs of a mask found outside geometry/ranges.py (use runs_of):\n"
                     + "\n".join(bad))  # fmt: skip


def test_json_files_have_one_writer() -> None:
    bad = _offences(JSON_WRITER, "ruledrobot/io/atomic.py")
    assert not bad, ("JSON written outside io/atomic.py (use atomic_write_json):\n"
                     + "\n".join(bad))  # fmt: skip


def test_the_patterns_catch_the_old_spellings() -> None:
    """The guards are not vacuous: the spellings they replaced match."""
    assert RUN_FINDER.search("d = np.diff(np.r_[0, m, 0])")
    assert RUN_FINDER.search("m = np.diff(np.concatenate([[False], mask, [False]]))")
    assert RUN_FINDER.search("stop = np.flatnonzero(d == -1) - 1")
    assert JSON_WRITER.search('atomic_write_text(p, json.dumps(doc, indent=1) + "\\n")')
    assert JSON_WRITER.search("json.dump(doc, fh)")
    assert not JSON_WRITER.search("h = hashlib.sha256(json.dumps(doc).encode())")
