"""The browser viewer of a plan folder and its static export (``docs/view.md``).

Typical use::

    from ruledrobot import view

    scene = view.build_scene("out/cut")          # PlanScene: pure, no browser, no viser
    view.serve(scene, host="127.0.0.1", port=8080, ready=lambda s: print(s.url))
    view.export_html(scene, "scene.html")        # one self-contained file, no Python to open

Modules, one job each: :mod:`.folder` reads a plan folder; :mod:`.geoms` turns the
simulation's MuJoCo geoms into meshes and poses them with MuJoCo's kinematics;
:mod:`.clearance` finds where collisions and near misses happen; :mod:`.scene`
builds the scene description; :mod:`.draw` draws it with viser; :mod:`.server`
serves it on loopback; :mod:`.export` writes the static HTML.  viser (the
``view`` extra) is imported only by the last three, on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

_LAZY = {
    "NotAPlanFolder": ("folder", "NotAPlanFolder"),
    "PlanFolder": ("folder", "PlanFolder"),
    "read_plan_folder": ("folder", "read_plan_folder"),
    "PlanScene": ("scene", "PlanScene"),
    "Timeline": ("scene", "Timeline"),
    "build_scene": ("scene", "build_scene"),
    "ViewServer": ("server", "ViewServer"),
    "RemoteRefused": ("server", "RemoteRefused"),
    "check_host": ("server", "check_host"),
    "serve": ("server", "serve"),
    "export_html": ("export", "export_html"),
    "ViewerUnavailable": ("_viser", "ViewerUnavailable"),
}


def __getattr__(name: str) -> Any:
    """Import the sub-modules on first use (``import ruledrobot.view`` stays cheap)."""
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(f".{module}", __name__), attr)
    raise AttributeError(f"module 'ruledrobot.view' has no attribute {name!r}")


__all__ = sorted(_LAZY)
