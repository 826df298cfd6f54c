"""A video worth watching: the cut appears, the trail stays, a caption, a close-up on the wire.

:class:`CutAnnotator` wraps a :class:`~ruledrobot.sim.render.Renderer` of a
hot-wire cell (a scene with a bow and a stock) and renders frame ``i`` of a
motion with:

* the **cut surface** the wire has swept inside the stock so far: the wire's
  chord in the stock at every earlier frame, drawn as a thin orange rod (a box
  1.6 mm square; at 25 fps and 10 mm/s they lie 0.4 mm apart: a surface);
* the **trail** of the wire's middle (the TCP), a line that stays, coloured by
  phase;
* a **caption**: time, phase and feed (the speed of the fastest wire point in
  the stock, :mod:`ruledrobot.robot.wire.in_stock`, the one model);
* while the wire cuts (phases lead-in, cut, lead-out, or in the stock when the
  phases are not given) a **close-up** of the wire inset in the lower right
  corner, seen from the side of the cut surface facing the main camera.

Everything is read from MuJoCo's own kinematics (the ``wire_start`` /
``wire_end`` sites) and the samples; decorations are ``mjvScene`` geoms added
after ``update_scene`` (visual only, never part of the model).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np

from ..geometry._arrays import FloatArray
from ..geometry.box import Box
from ..geometry.interp import interp_linear
from ..robot.motion.trajectory import CUTTING_PHASES
from ..robot.wire.in_stock import chord_fractions, flange_wire_ends, wire_in_stock

__all__ = ["CutAnnotator", "phase_labels"]

_MAX_DECOR = 1200  # decorative geoms per frame at most (older ones are thinned)
_CUT_RGBA = np.array([0.95, 0.45, 0.10, 1.0], np.float32)
_WIRE_RGBA = np.array([0.90, 0.05, 0.05, 1.0], np.float32)
_TRAIL_RGBA = {
    "approach": (0.35, 0.38, 0.45, 1.0), "retract": (0.35, 0.38, 0.45, 1.0),
    "lead_in": (0.20, 0.50, 0.85, 1.0), "lead_out": (0.20, 0.50, 0.85, 1.0),
    "cut": (0.90, 0.30, 0.05, 1.0),
}  # fmt: skip


def phase_labels(phases: Any, n: int) -> np.ndarray | None:
    """Return the (n,) phase names of the samples from ``Phase``-like ranges, or None.

    Ranges with ``name``, ``start``, ``stop``; None without phases; samples no phase names
    are ``"move"``.
    """
    if phases is None:
        return None
    labels = np.full(n, "move", dtype=object)
    for p in phases:
        labels[max(0, int(p.start)) : min(n, int(p.stop))] = str(p.name)
    return labels


class CutAnnotator:
    """Annotated frames of a motion (see the module doc); a context manager.

    ``renderer`` a Renderer of a scene with a bow and a stock; ``t`` (M,) s and
    ``q`` (M, J) rad the motion's samples; ``times`` (K,) s the frame times;
    ``phases`` ``Phase`` ranges of the samples or None.
    """

    def __init__(
        self, renderer: Any, t: FloatArray, q: FloatArray, times: FloatArray, phases: Any = None
    ) -> None:
        self.r = renderer
        mj = self.mj = renderer._mj
        scene = renderer.scene
        model = renderer.model
        self.stock: Box = scene.stock.moved(scene.robot.base)  # in the world frame
        # wire ends at the frames, from MuJoCo's sites
        s0 = mj.mj_name2id(model, mj.mjtObj.mjOBJ_SITE, "wire_start")
        s1 = mj.mj_name2id(model, mj.mjtObj.mjOBJ_SITE, "wire_end")
        data = mj.MjData(model)
        qs = interp_linear(times, t, q)
        J = scene.robot.n_joints
        ends = np.empty((times.size, 2, 3))
        for k, qk in enumerate(qs):
            data.qpos[:J] = qk
            mj.mj_kinematics(model, data)
            ends[k, 0], ends[k, 1] = data.site_xpos[s0], data.site_xpos[s1]
        self.ends = ends
        lo, hi = chord_fractions(ends, self.stock)
        inside = ~np.isnan(lo)
        a, b = ends[:, 0], ends[:, 1]
        self.chord = np.stack([a + np.nan_to_num(lo)[:, None] * (b - a),
                               a + np.nan_to_num(hi)[:, None] * (b - a)], axis=1)  # fmt: skip
        self.inside = inside
        # the chords as thin boxes: half sizes (w, w, L/2), centre, z along the chord
        axis = self.chord[:, 1] - self.chord[:, 0]
        length = np.linalg.norm(axis, axis=1)
        z = axis / np.maximum(length, 1e-12)[:, None]
        x = np.cross(z, [0.0, 0.0, 1.0])
        x[np.linalg.norm(x, axis=1) < 1e-9] = [1.0, 0.0, 0.0]
        x /= np.linalg.norm(x, axis=1, keepdims=True)
        self.rod_mat = np.stack([x, np.cross(z, x), z], axis=2).reshape(-1, 9)
        self.rod_pos = self.chord.mean(axis=1)
        self.rod_size = np.stack([np.full_like(length, 8e-4), np.full_like(length, 8e-4),
                                  0.5 * length], axis=1)  # fmt: skip
        # feed at every sample (forward kinematics of the samples), then at the frames
        flange = dataclasses.replace(scene.robot, tool=np.eye(4)).fk(q)
        all_ends = flange_wire_ends(flange, scene.tool)
        feed = wire_in_stock(t, all_ends, self.stock).feed
        k = np.clip(np.searchsorted(t, times - 1e-9), 0, t.size - 1)
        self.feed = feed[k]
        labels = phase_labels(phases, t.size)
        self.labels = None if labels is None else labels[k]
        self.cutting = (np.isin(self.labels, CUTTING_PHASES) if self.labels is not None
                        else inside)  # fmt: skip
        self.times = times
        self.close: Any = None
        if self.cutting.any():
            w_c = max(2 * (renderer.width // 6), 16)
            h_c = max(2 * (renderer.height // 6), 16)
            self.close = type(renderer)(scene, w_c, h_c)  # a second renderer, same kind
            self.close_camera = self._close_camera()

    def _close_camera(self) -> Any:
        """A free camera outside the block (half its diagonal plus 15 cm from the wire),
        on the side of the cut surface facing the main camera, a little above it."""
        mj = self.mj
        pts = self.chord[self.cutting & self.inside].reshape(-1, 3)
        if len(pts) < 3:
            pts = self.ends[self.cutting].reshape(-1, 3)
        centre = pts.mean(axis=0)
        _, _, vt = np.linalg.svd(pts - centre, full_matrices=False)
        normal = vt[-1]
        cam = self.r.model.cam_pos0[0] if self.r.model.ncam else centre + np.array([1.0, 0, 1])
        if normal @ (cam - centre) < 0:
            normal = -normal
        view = (cam - centre) / np.linalg.norm(cam - centre)
        d = normal + 0.7 * view + np.array([0.0, 0.0, 0.3])
        d /= np.linalg.norm(d)
        c = mj.MjvCamera()
        c.type = mj.mjtCamera.mjCAMERA_FREE
        # outside the block: its half diagonal plus a margin
        c.distance = float(0.5 * np.linalg.norm(self.stock.size) + 0.15)
        c.azimuth = float(np.degrees(np.arctan2(-d[1], -d[0])))
        c.elevation = float(np.degrees(np.arcsin(-d[2])))
        return c

    def _decorate(self, i: int) -> Any:
        mj = self.mj
        done = np.flatnonzero(self.inside[: i + 1] & (self.cutting[: i + 1] if self.labels
                                                       is not None else True))  # fmt: skip
        step = max(1, -(-done.size // (_MAX_DECOR // 2)))
        done = done[::-1][::step][::-1]
        path = self.ends[: i + 1].mean(axis=1)
        stride = max(1, -(-i // (_MAX_DECOR // 2)))
        idx = np.arange(0, i + 1, stride)
        if idx[-1] != i:
            idx = np.r_[idx, i]

        def add(scn: Any) -> None:
            eye = np.eye(3).ravel()
            zero = np.zeros(3)
            if scn.ngeom < scn.maxgeom:  # the wire itself, thick enough to see
                g = scn.geoms[scn.ngeom]
                mj.mjv_initGeom(g, mj.mjtGeom.mjGEOM_CAPSULE, zero, zero, eye, _WIRE_RGBA)
                mj.mjv_connector(g, mj.mjtGeom.mjGEOM_CAPSULE, 0.0025, self.ends[i, 0],
                                 self.ends[i, 1])  # fmt: skip
                scn.ngeom += 1
            for k in done:
                if scn.ngeom >= scn.maxgeom:
                    return
                g = scn.geoms[scn.ngeom]  # boxes: 12 triangles (a capsule costs ~5x the frame)
                mj.mjv_initGeom(g, mj.mjtGeom.mjGEOM_BOX, self.rod_size[k], self.rod_pos[k],
                                self.rod_mat[k], _CUT_RGBA)  # fmt: skip
                scn.ngeom += 1
            for a, b in itertools.pairwise(idx):
                if scn.ngeom >= scn.maxgeom:
                    return
                name = str(self.labels[a]) if self.labels is not None else "move"
                rgba = np.array(_TRAIL_RGBA.get(name, (0.35, 0.38, 0.45, 1.0)), np.float32)
                g = scn.geoms[scn.ngeom]
                mj.mjv_initGeom(g, mj.mjtGeom.mjGEOM_LINE, zero, zero, eye, rgba)
                mj.mjv_connector(g, mj.mjtGeom.mjGEOM_LINE, 2.0, path[a], path[b])
                scn.ngeom += 1

        return add

    def caption(self, i: int) -> str:
        """``t = 12.40 s   cut   feed 10.0 mm/s`` at frame ``i``."""
        text = f"t = {self.times[i]:6.2f} s"
        if self.labels is not None:
            text += f"   {str(self.labels[i]).replace('_', '-')}"
        if np.isfinite(self.feed[i]):
            text += f"   feed {1e3 * self.feed[i]:.1f} mm/s"
        elif self.labels is None or not self.cutting[i]:
            text += "   wire outside the stock"
        return text

    def frame(self, i: int, q: FloatArray) -> np.ndarray:
        """The annotated (H, W, 3) uint8 image of frame ``i`` at joints ``q``."""
        deco = self._decorate(i)
        img = self.r.frame(q, decorate=deco)
        if self.close is not None and self.cutting[i]:
            cam = self.close_camera
            cam.lookat[:] = self.ends[i].mean(axis=0) if not self.inside[i] \
                else self.chord[i].mean(axis=0)
            inset = self.close.frame(q, decorate=deco, camera=cam)
            h, w = inset.shape[:2]
            img = img.copy()
            y0, x0 = img.shape[0] - h - 8, img.shape[1] - w - 8
            img[y0 - 2 : y0 + h + 2, x0 - 2 : x0 + w + 2] = 255
            img[y0 : y0 + h, x0 : x0 + w] = inset
        return _write_text(img, self.caption(i), self.close is not None and self.cutting[i])

    def close_all(self) -> None:
        """Close the close-up's renderer (made by the annotator), if any; idempotent.

        The main renderer, the caller's, stays open.
        """
        if self.close is not None:
            self.close.close()
            self.close = None

    def __enter__(self) -> CutAnnotator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close_all()


def _write_text(img: np.ndarray, text: str, close_up: bool) -> np.ndarray:
    """The caption on a light band at the top of the frame (and the inset's label)."""
    from PIL import Image, ImageDraw, ImageFont

    h, w = img.shape[:2]
    size = max(10, h // 28)
    try:
        font = ImageFont.load_default(size=size)
    except TypeError:  # pragma: no cover - Pillow < 10.1
        font = ImageFont.load_default()
    pil = Image.fromarray(np.ascontiguousarray(img))
    draw = ImageDraw.Draw(pil)
    draw.rectangle([0, 0, w, size + 10], fill=(245, 245, 245))
    draw.text((8, 4), text, fill=(20, 20, 20), font=font)
    if close_up:
        label = "close-up on the wire"
        x = w - 8 - (w // 3 if w >= 96 else w)
        draw.text((max(4, x), h - 8 - 2 * (h // 6) - size - 6), label, fill=(20, 20, 20),
                  font=font)  # fmt: skip
    return np.asarray(pil)
