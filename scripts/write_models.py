"""Regenerate the committed MJCF files under models/ (run after changing the catalogue or
the MJCF generator; the test suite checks the committed files equal this output)."""

from __future__ import annotations

from pathlib import Path

from ruledrobot.sim.models import write_models

if __name__ == "__main__":
    for path in write_models(Path(__file__).resolve().parents[1] / "models"):
        print(f"wrote {path}")
