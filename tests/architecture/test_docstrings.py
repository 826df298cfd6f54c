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
#: packages whose docstrings also open with a one-line summary (numpydoc); the others
#: still hold docstrings of the older style, a paragraph from the first line
SUMMARY_PACKAGES = ("subdivision", "algorithms")

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


@pytest.mark.parametrize("path", _files(SUMMARY_PACKAGES), ids=lambda p: str(p.relative_to(ROOT)))
def test_docstrings_start_with_a_summary_line(path: Path) -> None:
    """The first line is the summary: a full sentence, then a blank line or the end."""
    bad = []
    for name, node in public_definitions(path):
        doc = ast.get_docstring(node)
        if not doc:
            continue  # reported by test_public_definitions_have_docstrings
        lines = doc.splitlines()
        if not lines[0].strip().endswith(".") or (len(lines) > 1 and lines[1].strip()):
            bad.append(f"{_where(path, node)} {name}: {lines[0]!r}")
    assert not bad, "docstrings whose first line is not a one-line summary:\n  " + "\n  ".join(bad)
