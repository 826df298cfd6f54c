"""The paper's six examples: every check passes, pictures and checks.json are written."""

from __future__ import annotations

import json
import time

import numpy as np
from matplotlib.image import imread

from ruledrobot.gallery import run_gallery

EXPECTED = {
    "cylindroid": ("projection", "four_point"),
    "helical_developable": ("projection", "four_point"),
    "four_lines": ("combined", "four_point"),
    "mobius_band": ("combined", "chaikin"),
    "hyperboloid": ("dh", "four_point"),
    "helical_surface": ("dh", "four_point"),
}


def test_gallery_runs_passes_and_writes_pictures(tmp_path):
    messages: list[str] = []
    t0 = time.perf_counter()
    result = run_gallery(tmp_path / "gallery", progress=messages.append)
    elapsed = time.perf_counter() - t0
    assert elapsed < 30.0

    failed = [
        (ex["name"], c["name"], c["value"], c["limit"])
        for ex in result["examples"]
        for c in ex["checks"]
        if not c["passed"]
    ]
    assert failed == []
    assert result["passed"] is True
    assert len(messages) == 6
    assert [ex["name"] for ex in result["examples"]] == list(EXPECTED)

    out = tmp_path / "gallery"
    for ex in result["examples"]:
        assert (ex["algorithm"], ex["scheme"]) == EXPECTED[ex["name"]]
        assert ex["checks"], ex["name"]
        for c in ex["checks"]:
            assert set(c) >= {"name", "value", "limit", "passed", "op"}
            assert np.isfinite(c["value"]) and np.isfinite(c["limit"])
        png = out / ex["png"]
        data = png.read_bytes()
        assert data.startswith(b"\x89PNG\r\n\x1a\n")
        img = imread(png)
        assert img.ndim == 3 and img.shape[0] >= 400 and img.shape[1] >= 400
        assert img[..., :3].std() > 0.05  # not a blank canvas

    stored = json.loads((out / "checks.json").read_text())
    assert stored == json.loads(json.dumps(result))
    # nothing else left behind (atomic writes)
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(["checks.json", *(ex["png"] for ex in result["examples"])])

    by_name = {ex["name"]: ex for ex in result["examples"]}
    # the numbers the docs quote stay what they are
    dev = by_name["helical_developable"]["measurements"]
    assert dev["input_lines"] == [6, 12, 24]
    assert all(q > 4.0 for q in dev["ratios"])
    mob = by_name["mobius_band"]
    assert mob["flip"] is True and mob["closed"] is True
    assert by_name["cylindroid"]["n_refined"] == 8 * 2**5
    assert by_name["helical_surface"]["n_refined"] == 5 * 2**3 + 1
