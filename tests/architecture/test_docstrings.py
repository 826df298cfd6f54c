"""Every public function, class and method of the documented packages has a docstring.

The convention (numpydoc with shapes, units and frames) is in
``docs/conventions.md``, section "Docstrings".  Public means: no leading
underscore and defined at module level (or a method of such a class), or named
in the module's ``__all__``.  ``@overload`` stubs are left out (the
implementation carries the docstring); functions nested in functions are
private by construction.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2] / "ruledrobot"
#: packages whose every public definition and module has a docstring
PACKAGES = ("subdivision", "algorithms", "geometry", "robot", "io", "sim", "export", "wirecut",
            "place", "batch", "cli", "protocol", "view",
            "carve", "gallery", "ursim")  # fmt: skip
#: every package of ruledrobot (found on disk, so that a new one is held too): their
#: docstrings open with a one-line summary (numpydoc)
SUMMARY_PACKAGES = tuple(sorted(p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file()))
#: definitions whose docstring still opens with a paragraph (``path qualified.name``, one a
#: line): a ratchet, not a licence.  A definition not listed must hold the rule; a listed
#: one that holds it now fails until its line is removed.  Issue 34 rewrote the summaries
#: that split mechanically (the first sentence, or its head before a colon, fits a line);
#: these have a first sentence too long for one line, or sit in modules other helpers were
#: rewriting at the time.
PENDING_FILE = Path(__file__).with_name("summary_pending.txt")

Definition = ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef


def _files(packages: tuple[str, ...] = PACKAGES) -> list[Path]:
    return sorted(p for pkg in packages for p in (ROOT / pkg).rglob("*.py"))


def _all_names(tree: ast.Module) -> set[str]:
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else []
        if isinstance(node, ast.AnnAssign):
            targets = [node.target]
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            value = node.value
            if isinstance(value, (ast.List, ast.Tuple)):
                return {e.value for e in value.elts if isinstance(e, ast.Constant)}
    return set()


def _is_overload(node: Definition) -> bool:
    return any(ast.unparse(d).split(".")[-1] == "overload" for d in node.decorator_list)


def public_definitions(path: Path) -> Iterator[tuple[str, Definition]]:
    """Yield (qualified name, node) of every public definition in ``path``."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    exported = _all_names(tree)

    def walk(body: list[ast.stmt], prefix: str) -> Iterator[tuple[str, Definition]]:
        for node in body:
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            public = not node.name.startswith("_") or (not prefix and node.name in exported)
            if not public or _is_overload(node):
                continue
            yield prefix + node.name, node
            if isinstance(node, ast.ClassDef):
                yield from walk(node.body, f"{prefix}{node.name}.")

    yield from walk(tree.body, "")


def _where(path: Path, node: ast.AST | None = None) -> str:
    line = f":{node.lineno}" if node is not None and hasattr(node, "lineno") else ""
    return f"{path.relative_to(ROOT.parent)}{line}"


def test_packages_have_modules() -> None:
    files = _files()
    for pkg in PACKAGES:
        assert any(p.parent.name == pkg for p in files), f"no modules found in {pkg}"


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_public_definitions_have_docstrings(path: Path) -> None:
    missing = [
        f"{_where(path, node)} {name}"
        for name, node in public_definitions(path)
        if not ast.get_docstring(node)
    ]
    assert not missing, (
        "public functions/classes without a docstring (numpydoc, see docs/conventions.md "
        "'Docstrings'):\n  " + "\n  ".join(missing)
    )


@pytest.mark.parametrize("path", _files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_modules_have_docstrings(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    assert ast.get_docstring(tree), f"{_where(path)}: module without a docstring"


def _pending() -> set[str]:
    lines = PENDING_FILE.read_text(encoding="utf-8").splitlines()
    return {ln.strip() for ln in lines if ln.strip() and not ln.startswith("#")}


def _summary_offences(path: Path) -> list[tuple[str, str]]:
    """(``path qualified.name``, where and first line) of docstrings without a summary line."""
    out = []
    for name, node in public_definitions(path):
        doc = ast.get_docstring(node)
        if not doc:
            continue  # reported by test_public_definitions_have_docstrings
        lines = doc.splitlines()
        if not lines[0].strip().endswith(".") or (len(lines) > 1 and lines[1].strip()):
            key = f"{path.relative_to(ROOT.parent).as_posix()} {name}"
            out.append((key, f"{_where(path, node)} {name}: {lines[0]!r}"))
    return out


def _summary_files() -> list[Path]:
    return sorted({*_files(SUMMARY_PACKAGES), *ROOT.glob("*.py")})


@pytest.mark.parametrize("path", _summary_files(), ids=lambda p: str(p.relative_to(ROOT)))
def test_docstrings_start_with_a_summary_line(path: Path) -> None:
    """The first line is the summary: a full sentence, then a blank line or the end."""
    pending = _pending()
    bad = [where for key, where in _summary_offences(path) if key not in pending]
    assert not bad, "docstrings whose first line is not a one-line summary:\n  " + "\n  ".join(bad)


def test_the_pending_summaries_are_still_pending() -> None:
    """Every line of ``summary_pending.txt`` names a definition that still breaks the rule
    (fixed or removed ones leave the list, so that it only shrinks)."""
    found = {key for path in _summary_files() for key, _ in _summary_offences(path)}
    stale = sorted(_pending() - found)
    assert not stale, (f"{PENDING_FILE.name}: these now hold the summary rule (or are gone); "
                       "remove their lines:\n  " + "\n  ".join(stale))  # fmt: skip


def test_every_package_is_held_to_the_summary_rule() -> None:
    assert {"geometry", "robot", "wirecut", "ursim", "cli"} <= set(SUMMARY_PACKAGES)
