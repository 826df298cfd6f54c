"""The package's sizes stay where a reader can find things (docs/architecture.md): no
folder holds more than 20 modules side by side, and no module is over 600 lines."""

from __future__ import annotations

from pathlib import Path

import ruledrobot

ROOT = Path(ruledrobot.__file__).parent
MAX_MODULES = 20
MAX_LINES = 600


def test_no_folder_holds_more_than_20_modules():
    crowded = {}
    for folder in [ROOT, *(p for p in ROOT.rglob("*") if p.is_dir())]:
        if folder.name == "__pycache__":
            continue
        n = len(list(folder.glob("*.py")))
        if n > MAX_MODULES:
            crowded[str(folder.relative_to(ROOT.parent))] = n
    assert not crowded, crowded


def test_no_module_is_over_600_lines():
    long = {str(p.relative_to(ROOT.parent)): n for p in ROOT.rglob("*.py")
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}  # fmt: skip
    assert not long, long
