"""One home for a fact (issue 34): a second spelling of a run finder, a JSON file writer,
a rotation angle, the wire's ends from the flange or a moved or grown box fails here,
naming the file and line.

* runs of a boolean mask: :mod:`ruledrobot.geometry.ranges` (half-open ``(start, stop)``);
  nine spellings with half-open and inclusive ends mixed were found in review;
* the product's JSON files: :func:`ruledrobot.io.atomic.atomic_write_json` (atomic, one
  layout); thirteen writers each spelled ``json.dumps`` and its indent;
* the angle of a rotation, between two rotations:
  :mod:`ruledrobot.geometry.rotations` (``rotation_angle``, ``angle_between``); three
  formulas were found (``arccos`` of the trace, trace and skew part, the norm of the
  rotation vector);
* the wire's ends from flange poses:
  :func:`ruledrobot.robot.wire.in_stock.flange_wire_ends`; the playback, the video, the
  viewer and the plan's picture each carried ``wire_start`` / ``wire_end`` themselves;
* a box moved by a rigid motion or grown by a margin: :meth:`ruledrobot.geometry.box.Box.moved`,
  :meth:`~ruledrobot.geometry.box.Box.grown`; three moved and five grown by hand.
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
#: a rotation's angle by hand: a trace (np.trace or its diagonal summed), the norm of a
#: rotation vector, scipy's magnitude, twice an inverse cosine or sine (quaternions)
_INDEX = r"\[(?:\.\.\.|:)?,?\s*"  # R[..., i, j], R[:, i, j] or R[i, j]
_INVERSE = r"(?:np\.|math\.)?(?:arccos|acos|arcsin|asin)\("
ROTATION_ANGLE = re.compile(r"\btrace\(|" + _INDEX + r"0,\s*0\]\s*\+\s*\w+" + _INDEX + r"1,\s*1\]"
                            + r"|norm\(\s*(?:\w+\.)?rotvec_from_matrix\(|\.magnitude\(\)"
                            + r"|\b2(?:\.0)?\s*\*\s*" + _INVERSE)  # fmt: skip
#: the wire from the flange by hand: flange @ W, the bow's two ends stacked to be
#: transformed, or the midpoint -+ half the length along z
WIRE_ENDS = re.compile(r"@\s*[\w.]*wire_frame\(\)"
                       r"|stack\(\[\s*[\w.]*wire_start,\s*[\w.]*wire_end\s*\]\)"
                       r"|half\s*\*\s*\w+\[[^\]]*:3,\s*2\]")  # fmt: skip
#: a box moved or grown by hand: Box(R @ centre + p, ...), Box(c, size + margin, ...)
BOX_COPY = re.compile(r"Box\((?:centre=)?\s*[\w\[\]:, ]*@\s*[\w.]*centre"
                      r"|Box\([^()]*?\bsize\s*[+-]"
                      r"|replace\([^()]*\bsize\s*=\s*[\w.]*size\s*[+-]")  # fmt: skip


def _offences(pattern: re.Pattern[str], *homes: str) -> list[str]:
    out = []
    for p in sorted(ROOT.rglob("*.py")):
        rel = p.relative_to(ROOT.parent).as_posix()
        if rel in homes:
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


def test_rotation_angles_have_one_formula() -> None:
    bad = _offences(ROTATION_ANGLE, "ruledrobot/geometry/rotations.py",
                    # the quaternion of a matrix (Shepperd), not an angle
                    "ruledrobot/geometry/screw.py")  # fmt: skip
    assert not bad, ("a rotation angle computed outside geometry/rotations.py (use "
                     "rotation_angle / angle_between):\n" + "\n".join(bad))  # fmt: skip


def test_the_wire_from_the_flange_has_one_derivation() -> None:
    bad = _offences(WIRE_ENDS, "ruledrobot/robot/wire/in_stock.py")
    assert not bad, ("the wire's ends derived outside robot/wire/in_stock.py (use "
                     "flange_wire_ends / wire_ends):\n" + "\n".join(bad))  # fmt: skip


def test_boxes_are_moved_and_grown_by_their_methods() -> None:
    bad = _offences(BOX_COPY, "ruledrobot/geometry/box.py")
    assert not bad, ("a box moved or grown by hand (use Box.moved / Box.grown):\n"
                     + "\n".join(bad))  # fmt: skip


def test_the_patterns_catch_the_old_spellings() -> None:
    """The guards are not vacuous: the spellings they replaced match."""
    assert RUN_FINDER.search("d = np.diff(np.r_[0, m, 0])")
    assert RUN_FINDER.search("m = np.diff(np.concatenate([[False], mask, [False]]))")
    assert RUN_FINDER.search("stop = np.flatnonzero(d == -1) - 1")
    assert JSON_WRITER.search('atomic_write_text(p, json.dumps(doc, indent=1) + "\\n")')
    assert JSON_WRITER.search("json.dump(doc, fh)")
    assert not JSON_WRITER.search("h = hashlib.sha256(json.dumps(doc).encode())")
    # the rotation angles the review found, and their cousins
    assert ROTATION_ANGLE.search("rot = math.acos(min(1.0, (float(np.trace(R)) - 1.0) / 2.0))")
    assert ROTATION_ANGLE.search("cos = (R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2] - 1) / 2")
    assert ROTATION_ANGLE.search("return np.linalg.norm(se3.rotvec_from_matrix(R), axis=-1)")
    assert ROTATION_ANGLE.search("a = Rotation.from_matrix(R).magnitude()")
    assert ROTATION_ANGLE.search("a = 2.0 * np.arccos(np.abs(q @ p))")
    assert not ROTATION_ANGLE.search("rel = rotvec_from_matrix(Ri.T @ Rj)")
    assert not ROTATION_ANGLE.search("tilt = math.atan2(norm(cross(zn, zc)), zn @ zc)")
    # the wire's ends the review found in sim, view and the planner
    assert WIRE_ENDS.search("ends = wire_ends(model.fk(q) @ bow.wire_frame(), bow.wire_length)")
    assert WIRE_ENDS.search("ends = np.stack([tool.wire_start, tool.wire_end])  # (2, 3)")
    assert WIRE_ENDS.search("e = np.stack([G[:, :3, 3] - half * G[:, :3, 2], G[:, :3, 3]], 1)")
    assert not WIRE_ENDS.search("robot = model.with_tool(bow.wire_frame()).with_base(np.eye(4))")
    # the boxes moved and grown by hand
    assert BOX_COPY.search("stock = Box(T[:3, :3] @ st.centre + T[:3, 3], st.size, R)")
    assert BOX_COPY.search("return Box(centre=R @ s.centre + p, size=s.size, rotation=R)")
    assert BOX_COPY.search("grown = Box(stock.centre, stock.size + 2.0 * lead, stock.rotation)")
    assert BOX_COPY.search("b = dataclasses.replace(stock, size=stock.size + 0.004)")
    assert not BOX_COPY.search("self.local = Box(np.zeros(3), box.size)")
    assert not BOX_COPY.search("stock = Box(centre, size, rot)")
