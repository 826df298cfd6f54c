"""Drawing a :class:`~ruledrobot.view.scene.PlanScene` with viser: one painter for the
live server and the static export.

Scene tree (world frame, z up):

* ``/cell/<geom>`` — the static geoms of the MuJoCo model (table, legs, floor,
  stock — the stock translucent, so that the cut inside shows);
* ``/robot/<geom>`` — the moving geoms (arm, bow, wire), posed at each frame from
  the timeline's MuJoCo poses;
* ``/plan/surface``, ``/plan/part``, ``/plan/removed`` — the plan's meshes;
  ``/plan/rulings`` — the refined rulings inside the stock;
* ``/motion/wire`` — the wire, drawn thick; ``/motion/cut/<k>`` — the cut
  surface the wire has swept inside the stock up to frame k (appears as the
  wire passes); ``/motion/trail/<k>`` — the whole wire's swept trail,
  coloured by phase; ``/motion/caption`` — time, phase, feed, joint speed,
  singularity at the wire (and, with a heat model, the heat and the predicted kerf);
* ``/plan/kerf`` — with a ``[material]``: the trace of the wire's two chord ends on the
  part's face, coloured by the kerf predicted there (:mod:`.kerf`), burns as magenta balls;
* ``/events/<i>`` — collisions (red) and near misses (amber) where they happen.

:meth:`Painter.show` moves everything to a frame; only what changes is sent.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..robot.motion.trajectory import CUTTING_PHASES
from ..robot.motion.trajectory import PHASE_COLOURS as PHASE_HEX
from .kerf import (
    BURN_COLOUR,
    BURN_RADIUS,
    burn_points,
    heat_words,
    kerf_colours,
    kerf_range,
    kerf_trace,
    kerf_words,
)
from .scene import PlanScene

__all__ = ["PHASE_COLOURS", "Painter", "caption", "figures_markdown"]

#: RGB of the phases (trail, labels): the plots' colours (one home, the trajectory's phases)
PHASE_COLOURS = {p: tuple(int(c[k:k + 2], 16) for k in (1, 3, 5))
                 for p, c in PHASE_HEX.items()}  # fmt: skip
_CUT_COLOUR = (235, 110, 30)
_SURFACE_COLOUR = (70, 150, 230)
_WIRE_COLOUR = (230, 20, 20)
_RULING_COLOUR = (40, 90, 200)


def _rgb(rgba: np.ndarray) -> tuple[int, int, int]:
    return tuple(round(255 * float(c)) for c in rgba[:3])  # type: ignore[return-value]


def _quad_strip(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two triangles between segments ``a`` (2, 3) and ``b`` (2, 3)."""
    v = np.concatenate([a, b]).astype(np.float32)
    return v, np.array([[0, 1, 3], [0, 3, 2]], dtype=np.uint32)


def _caption_at(wire: np.ndarray) -> np.ndarray:
    """Where the caption hangs: 2 cm above the wire's upper end (clear of the stock)."""
    return wire[np.argmax(wire[:, 2])] + np.array([0.0, 0.0, 0.02])


def caption(scene: PlanScene, k: int) -> str:
    """The words at the wire at frame ``k``: time, phase, feed, joint speed, singularity."""
    tl = scene.timeline
    assert tl is not None
    lim = scene.limits
    phase = str(tl.phase[k]).replace("_", "-")
    lines = [f"t = {tl.t[k]:.2f} s · {phase}"]
    if np.isfinite(tl.feed[k]):
        lines.append(f"feed {1e3 * tl.feed[k]:.2f} mm/s (set {1e3 * lim['feed_set']:.1f})")
    lines += [w for w in (heat_words(tl, k), kerf_words(tl, k)) if w is not None]
    j = int(np.argmax(tl.speed_ratio[k]))
    lines.append(f"joint speed {100 * tl.speed_ratio[k, j]:.0f} % of limit (J{j + 1})")
    lines.append(f"singularity {tl.singularity[k]:.3f} (≥ {lim['singularity']:.2f})")
    return "\n".join(lines)


def figures_markdown(scene: PlanScene, k: int) -> str:
    """The live figures at frame ``k`` as a markdown table (the server's panel)."""
    tl = scene.timeline
    assert tl is not None
    lim = scene.limits
    feed = (f"{1e3 * tl.feed[k]:.2f} mm/s (limits {1e3 * lim['feed_min']:.1f}–"
            f"{1e3 * lim['feed_max']:.1f})" if np.isfinite(tl.feed[k])
            else "— (wire outside the stock)")  # fmt: skip
    bars = " ".join(f"J{j + 1} {100 * r:.0f}%" for j, r in enumerate(tl.speed_ratio[k]))
    sing_ok = tl.singularity[k] >= lim["singularity"]
    rows = [
        ("time", f"{tl.t[k]:.2f} s of {tl.t[-1]:.2f} s (sample {int(tl.sample[k])})"),
        ("phase", f"**{tl.phase[k]}**"),
        ("feed", feed),
        *[(w.split(" ", 1)[0], w.split(" ", 1)[1] + note) for w, note in (
            (heat_words(tl, k), " (set-point; the wire after the lag)"),
            (kerf_words(tl, k), " (predicted at the wire's start / end side)"))
          if w is not None],
        ("joint speed / limit", bars),
        ("singularity measure", f"{tl.singularity[k]:.3f} "
         f"({'ok' if sing_ok else 'BELOW'} ≥ {lim['singularity']:.2f})"),
    ]  # fmt: skip
    return "| | |\n|---|---|\n" + "\n".join(f"| {a} | {b} |" for a, b in rows)


class Painter:
    """Adds a plan scene to a viser server (its ``scene`` API) and poses it at frames."""

    def __init__(self, server: Any, scene: PlanScene) -> None:
        self.server = server
        self.scene = scene
        api = server.scene
        api.set_up_direction("+z")
        # no shadow maps: they cost seconds per frame in software WebGL and add little here
        api.configure_default_lights(True, cast_shadow=False)
        # no environment map either (its prefiltering takes ~10 s in software WebGL): a
        # hemisphere light in its place, so that faces turned from the lights stay readable
        api.configure_environment_map(None)
        api.add_light_hemisphere("/lights/sky", sky_color=(255, 255, 255),
                                 ground_color=(120, 110, 100), intensity=2.0)  # fmt: skip
        pos, target = scene.camera
        server.initial_camera.position = tuple(float(x) for x in pos)
        server.initial_camera.look_at = tuple(float(x) for x in target)
        server.initial_camera.up = (0.0, 0.0, 1.0)
        self.handles: dict[int, Any] = {}
        # the moving parts named in a collision are drawn red
        hit = {part for e in scene.events if e.kind == "collision" for part in e.what.split(" – ")}
        for i, g in enumerate(scene.geoms):
            if g.rgba[3] <= 0.0:
                continue
            root = "/cell" if g.static else "/robot"
            colour = (220, 30, 30) if g.name in hit and not g.static else _rgb(g.rgba)
            self.handles[i] = api.add_mesh_simple(
                f"{root}/{g.name}", g.vertices, g.faces, color=colour,
                opacity=None if g.rgba[3] >= 1.0 else float(g.rgba[3]),
                side="double" if g.rgba[3] < 1.0 else "front",
                wxyz=scene.rest_quat[i], position=scene.rest_pos[i],
                cast_shadow=False, receive_shadow=False,
            )  # fmt: skip
        for name, mesh in scene.meshes.items():
            colour = _SURFACE_COLOUR if name.startswith("surface") else (
                (200, 190, 150) if name == "part" else (150, 150, 150))  # fmt: skip
            api.add_mesh_simple(f"/plan/{name}", mesh.vertices, mesh.faces, color=colour,
                                opacity=0.45 if name.startswith("surface") else 0.35,
                                side="double", cast_shadow=False,
                                receive_shadow=False)  # fmt: skip
        if len(scene.rulings):
            api.add_line_segments("/plan/rulings", scene.rulings.astype(np.float32),
                                  _RULING_COLOUR, thickness=1.5,
                                  thickness_units="screen")  # fmt: skip
        self.markers: list[Any] = []
        for i, e in enumerate(scene.events):
            if e.position is None:
                continue
            colour = (220, 20, 20) if e.kind == "collision" else (240, 170, 0)
            self.markers.append(api.add_icosphere(f"/events/{i}", radius=0.012, color=colour,
                              position=e.position, cast_shadow=False))  # fmt: skip
            text = f"{e.kind} {abs(e.distance_mm):.1f} mm, t = {e.time:.2f} s ({e.phase})"
            self.markers.append(api.add_label(f"/events/{i}/label", text,
                                              position=(0.0, 0.0, 0.02),
                                              anchor="bottom-center"))  # fmt: skip
        trace = None if scene.timeline is None else kerf_trace(scene.timeline)
        rng = kerf_range(scene)
        if trace is not None and rng is not None:
            seg, w = trace
            api.add_line_segments("/plan/kerf", seg.astype(np.float32),
                                  kerf_colours(w, *rng), thickness=5.0,
                                  thickness_units="screen")  # fmt: skip
            for i, x in enumerate(burn_points(scene.timeline)):
                api.add_icosphere(f"/plan/kerf/burn{i}", radius=BURN_RADIUS, color=BURN_COLOUR,
                                  position=x, cast_shadow=False)  # fmt: skip
        self.frame = -1
        self.trail: list[Any] = []
        self.cut: list[Any | None] = []
        self.shown = 0  # trail pieces 0..shown-1 are visible
        self.enabled = {"trail": True, "cut": True}
        tl = scene.timeline
        if tl is None:
            return
        self.wire = api.add_line_segments("/motion/wire", tl.wire[0].astype(np.float32)[None],
                                          _WIRE_COLOUR, thickness=4.0,
                                          thickness_units="screen")  # fmt: skip
        for k in range(tl.t.size - 1):
            v, f = _quad_strip(tl.wire[k], tl.wire[k + 1])
            phase = str(tl.phase[k])
            self.trail.append(api.add_mesh_simple(
                f"/motion/trail/{k}", v, f, color=PHASE_COLOURS.get(phase, (120, 130, 145)),
                opacity=0.18, side="double", visible=False, cast_shadow=False,
                receive_shadow=False))  # fmt: skip
            c0, c1 = tl.chord[k], tl.chord[k + 1]
            if np.isfinite(c0).all() and np.isfinite(c1).all() and phase in CUTTING_PHASES:
                v, f = _quad_strip(c0, c1)
                self.cut.append(api.add_mesh_simple(
                    f"/motion/cut/{k}", v, f, color=_CUT_COLOUR, opacity=0.85, side="double",
                    visible=False, cast_shadow=False, receive_shadow=False))  # fmt: skip
            else:
                self.cut.append(None)
        self.caption = api.add_label("/motion/caption", caption(scene, 0),
                                     position=_caption_at(tl.wire[0]), anchor="bottom-left",
                                     font_screen_scale=1.0)  # fmt: skip

    def show(self, k: int) -> None:
        """Pose the scene at frame ``k`` of the timeline (no-op without one)."""
        tl = self.scene.timeline
        if tl is None:
            return
        k = int(np.clip(k, 0, tl.t.size - 1))
        if k == self.frame:
            return
        with self.server.atomic():
            for i, h in self.handles.items():
                if not self.scene.geoms[i].static:
                    h.position = tl.geom_pos[k, i]
                    h.wxyz = tl.geom_quat[k, i]
            self.wire.points = tl.wire[k].astype(np.float32)[None]
            lo, hi = sorted((self.shown, k))
            for j in range(lo, hi):
                vis = j < k
                self.trail[j].visible = vis and self.enabled["trail"]
                if self.cut[j] is not None:
                    self.cut[j].visible = vis and self.enabled["cut"]
            self.shown = k
            self.caption.position = _caption_at(tl.wire[k])
            self.caption.text = caption(self.scene, k)
        self.frame = k

    def set_visible(self, group: str, visible: bool) -> None:
        """Show or hide a group of nodes.

        ``"trail"``, ``"cut"``, ``"rulings"``, ``"surface"``, ``"stock"``, ``"events"``,
        ``"kerf"``."""
        api = self.server.scene
        if group in ("trail", "cut"):
            self.enabled[group] = visible
            nodes = self.trail if group == "trail" else self.cut
            for j, h in enumerate(nodes):
                if h is not None:
                    h.visible = visible and j < self.shown
            return
        if group == "events":
            for h in self.markers:
                h.visible = visible
            return
        name = {"rulings": "/plan/rulings", "surface": "/plan/surface",
                "stock": "/cell/stock", "kerf": "/plan/kerf"}[group]  # fmt: skip
        h = api.get_handle_by_name(name)
        if h is not None:
            h.visible = visible
