"""MuJoCo models, trajectory playback and headless rendering (the execution layer).

Typical use::

    import ruledrobot as rr
    from ruledrobot import sim

    robot = rr.robot.load("ur5e")
    xml = sim.robot_mjcf(robot)                           # MJCF of the arm (str)
    scene = sim.Scene(robot, tool=sim.BowTool([-0.2, 0, 0.25], [0.2, 0, 0.25]),
                      stock=Box(centre=[0.5, 0.1, 0.15], size=[0.2, 0.2, 0.3]))
    res = sim.play(scene, t, q)                          # PlaybackResult
    res.report(); res.write("out/sim")                   # dict; report.json + plots
    sim.render_video(res, "out/sim/video.mp4")           # needs EGL or OSMesa

    sim.write_chain("lines.json", "chain.xml")           # the chain of a line sequence

Importing this package is cheap: MuJoCo is imported on first use, after
:func:`configure_gl` has chosen a headless OpenGL backend (``MUJOCO_GL``:
``egl``, else ``osmesa``; a value set by the user is kept).  See ``docs/sim.md``.
"""

from __future__ import annotations

import importlib
from typing import Any

from ._mujoco import RenderUnavailable, configure_gl

_LAZY = {
    "mjcf": ("mjcf", None),
    "scene": ("scene", None),
    "playback": ("playback", None),
    "render": ("render", None),
    "robot_mjcf": ("mjcf", "robot_mjcf"),
    "chain_mjcf": ("chain", "chain_mjcf"),
    "write_chain": ("chain", "write_chain"),
    "write_models": ("models", "write_models"),
    "ServoGains": ("mjcf", "ServoGains"),
    "physics_timestep": ("mjcf", "physics_timestep"),
    "BowTool": ("scene", "BowTool"),
    "Scene": ("scene", "Scene"),
    "scene_mjcf": ("scene", "scene_mjcf"),
    "default_table": ("scene", "default_table"),
    "play": ("playback", "play"),
    "play_file": ("files", "play_file"),
    "simulate": ("files", "simulate"),
    "PlaybackResult": ("result", "PlaybackResult"),
    "Collision": ("contacts", "Collision"),
    "Renderer": ("render", "Renderer"),
    "render_frames": ("render", "render_frames"),
    "render_video": ("render", "render_video"),
    "render_strip": ("render", "render_strip"),
}


def __getattr__(name: str) -> Any:
    """Import the sub-modules on first use, keeping ``import ruledrobot.sim`` fast."""
    if name in _LAZY:
        module, attr = _LAZY[name]
        mod = importlib.import_module(f".{module}", __name__)
        return mod if attr is None else getattr(mod, attr)
    raise AttributeError(f"module 'ruledrobot.sim' has no attribute {name!r}")


__all__ = ["RenderUnavailable", "configure_gl", *sorted(_LAZY)]
