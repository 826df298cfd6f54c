"""carve imports only the planner's top-level names (the planner's inside is being reshaped)."""

from __future__ import annotations

import ast
from pathlib import Path

import ruledrobot.carve

ROOT = Path(ruledrobot.carve.__file__).parent


def test_carve_imports_only_top_level_names_of_the_planner():
    bad = []
    for path in sorted(ROOT.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module and "wirecut" in node.module:
                if node.module not in ("wirecut", "ruledrobot.wirecut") or (
                        node.level not in (0, 2) and node.module == "wirecut"):
                    bad.append(f"{path.name}: from {'.' * node.level}{node.module}")
            if isinstance(node, ast.Import):
                bad += [f"{path.name}: import {a.name}" for a in node.names
                        if a.name.startswith("ruledrobot.wirecut.")]
    assert not bad, bad
