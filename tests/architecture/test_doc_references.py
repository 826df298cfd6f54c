"""Every Sphinx cross reference in ``ruledrobot``'s documentation names a thing that exists.

The rule (``docs/conventions.md``, section "Docstrings"): a reference that starts with
``.`` is relative to the module's package, as a Python relative import is (``.x`` a
module or name of the same package, ``..x`` one package up); one that starts with
``ruledrobot.`` is absolute; anything else (a bare name in scope, ``numpy`` ...) is not
checked.  The documentation read is every docstring (module, class, function, parsed
with ``ast``) and every ``#:`` comment (Sphinx's documentation of an attribute).  A
target resolves when its longest importable prefix is a module and the rest are
attributes of it (a dataclass field or annotated class attribute counts).
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # ruledrobot.sim imports mujoco, which reads it once

import ast
import importlib
import io
import re
import tokenize
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "ruledrobot"
ROLE = re.compile(r":(mod|func|class|meth|attr|data|obj|exc|const):`~?([A-Za-z_.][\w.]*)`")
Documented = ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef


def module_name(path: Path) -> tuple[str, str]:
    """The dotted name of the module at ``path`` and of the package relative references
    start from (the module itself for a package's ``__init__``)."""
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    if parts[-1] == "__init__":
        name = ".".join(parts[:-1])
        return name, name
    name = ".".join(parts)
    return name, name.rsplit(".", 1)[0]


def documentation(text: str) -> Iterator[str]:
    """The docstrings and the ``#:`` comments of a module's source."""
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, Documented):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield doc
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type == tokenize.COMMENT and tok.string.startswith("#:"):
            yield tok.string


def absolute(target: str, package: str) -> str | None:
    """The dotted name a reference means, or None when the rule does not check it."""
    if target.startswith("."):
        lead = len(target) - len(target.lstrip("."))
        base = package.split(".")
        if lead - 1 >= len(base):
            return target  # beyond the top package: cannot resolve
        base = base[: len(base) - (lead - 1)]
        return ".".join([*base, target.lstrip(".")])
    if target == "ruledrobot" or target.startswith("ruledrobot."):
        return target
    return None


def _has(obj: object, name: str) -> tuple[bool, object]:
    if hasattr(obj, name):
        return True, getattr(obj, name)
    if isinstance(obj, type):  # a dataclass field or annotated attribute without a default
        for klass in obj.__mro__:
            if name in getattr(klass, "__dataclass_fields__", {}) or name in vars(klass).get(
                "__annotations__", {}
            ):
                return True, None
    return False, None


def resolves(full: str) -> bool:
    """Whether the longest importable prefix of ``full`` is a module holding the rest."""
    if full.startswith("."):
        return False
    parts = full.split(".")
    for i in range(len(parts), 0, -1):
        name = ".".join(parts[:i])
        try:
            obj = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name and (name == exc.name or name.startswith(exc.name + ".")):
                continue  # this prefix is not a module: try a shorter one
            raise  # a module that exists failed to import: a real error
        for attr in parts[i:]:
            if obj is None:
                return True  # a field, its value not a class attribute
            found, obj = _has(obj, attr)
            if not found:
                return False
        return True
    return False


def unresolved() -> list[str]:
    bad = []
    for path in sorted(ROOT.rglob("*.py")):
        _, package = module_name(path)
        rel = path.relative_to(ROOT.parent)
        for doc in documentation(path.read_text(encoding="utf-8")):
            for role, target in ROLE.findall(doc):
                full = absolute(target, package)
                if full is not None and not resolves(full):
                    bad.append(f"{rel}: :{role}:`{target}`")
    return bad


def test_relative_references_follow_the_import_rule() -> None:
    assert absolute(".grid.ROLLS", "ruledrobot.wirecut.reach") == (
        "ruledrobot.wirecut.reach.grid.ROLLS"
    )
    assert absolute("..cut.passes", "ruledrobot.wirecut.reach") == "ruledrobot.wirecut.cut.passes"
    assert absolute("ruledrobot.place.regions", "ruledrobot.wirecut") == "ruledrobot.place.regions"
    assert absolute("numpy.linalg", "ruledrobot.wirecut") is None
    assert absolute("BowTool.segments", "ruledrobot.wirecut") is None
    assert module_name(ROOT / "wirecut" / "reach" / "__init__.py") == (
        "ruledrobot.wirecut.reach",
        "ruledrobot.wirecut.reach",
    )
    assert module_name(ROOT / "wirecut" / "reach" / "grid.py")[1] == "ruledrobot.wirecut.reach"
    assert resolves("ruledrobot.wirecut.cut.cutpath.CutPath.cut")  # a dataclass field
    assert not resolves("ruledrobot.wirecut.reach_grid")
    assert not resolves("ruledrobot.wirecut.reach.grid.NO_SUCH_NAME")


def test_every_reference_resolves() -> None:
    bad = unresolved()
    assert not bad, f"{len(bad)} unresolved documentation references:\n" + "\n".join(bad)
