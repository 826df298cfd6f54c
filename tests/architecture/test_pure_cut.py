"""The planner's stages below the job read no file (issue 34, docs/architecture.md "The job
is read whole, once"): ``wirecut.job`` reads every file a job names when it is loaded;
``wirecut.cut``, ``wirecut.motion`` and ``wirecut.plan`` import no reader of input files
and open nothing.  (The behaviour -- a job whose folder is gone plans -- is
``tests/wirecut/job/test_loaded_whole.py``; this is the static side.)"""

from __future__ import annotations

import ast
from pathlib import Path

from .imports import ROOT, graph

#: the stages that get data, not paths
PURE = ("ruledrobot.wirecut.cut", "ruledrobot.wirecut.motion", "ruledrobot.wirecut.plan")
#: modules that read a user's input files (the job's loader uses them)
READERS = ("ruledrobot.io.text", "ruledrobot.io.formats", "ruledrobot.io.calibration",
           "ruledrobot.io.paths")  # fmt: skip
#: functions that read a file: ``open``, the project's readers
READ_NAMES = {"open", "read_lines_document", "load_lines", "read_user_text", "read_user_bytes",
              "read_rulings", "load_calibration"}  # fmt: skip
#: methods that read a file: pathlib's, numpy's, json's and tomllib's
READ_METHODS = {"open", "read_text", "read_bytes", "load", "loadtxt", "genfromtxt", "fromfile"}


def _pure(name: str) -> bool:
    return any(name == p or name.startswith(p + ".") for p in PURE)


def file_reads(path: Path) -> list[str]:
    """The calls in ``path``'s source whose name reads a file (``line: name``)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Attribute) and f.attr in READ_METHODS | READ_NAMES:
                found.append(f"{node.lineno}: .{f.attr}")
            elif isinstance(f, ast.Name) and f.id in READ_NAMES:
                found.append(f"{node.lineno}: {f.id}")
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.endswith("lines"):
            found += [f"{node.lineno}: {a.name}" for a in node.names if a.name in READ_NAMES]
    return found


def test_the_stages_below_the_job_import_no_reader():
    edges = graph()
    bad = {m: sorted(t for t in targets if t.startswith(READERS))
           for m, targets in edges.items() if _pure(m)}  # fmt: skip
    assert any(_pure(m) for m in edges)
    assert not any(bad.values()), {m: t for m, t in bad.items() if t}


def test_the_stages_below_the_job_call_no_file_read():
    pure = [p for p in ROOT.joinpath("wirecut").rglob("*.py")
            if _pure(".".join(p.relative_to(ROOT.parent).with_suffix("").parts))]  # fmt: skip
    assert len(pure) > 10
    reads = {str(p.relative_to(ROOT)): file_reads(p) for p in pure}
    assert not any(reads.values()), {p: r for p, r in reads.items() if r}


def test_the_scan_sees_the_loaders_reads():
    """The scan is not blind: the job's loader and the lines reader are caught."""
    assert file_reads(ROOT / "io" / "lines.py")
    assert any("read_rulings" in r for r in file_reads(ROOT / "wirecut" / "job" / "sections.py"))
