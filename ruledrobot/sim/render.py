"""Headless rendering of a motion: MP4 video and a PNG strip of frames.

Rendering needs an OpenGL context without a display: EGL (Mesa llvmpipe on
a CPU machine) or OSMesa.  ``MUJOCO_GL`` must name it before ``mujoco`` is
imported; :func:`ruledrobot.sim.configure_gl` picks ``egl`` (else ``osmesa``)
when the variable is unset, and every function here calls it.  When no
context can be made, :class:`RenderUnavailable` (a RuntimeError) says which
packages to install and what to set.

Fast settings (``docs/sim.md``): no multisampling (``offsamples = 0`` in the
model), no shadows, no reflections.  The video is H.264 (libx264, yuv420p)
through the ffmpeg binary of ``imageio-ffmpeg``; its frame rate should divide
the physics rate (25 or 50 fps at 500 Hz) so that every frame is a sample.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import tempfile
import warnings
import weakref
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..geometry.checks import FloatArray
from ..geometry.interp import interp_linear
from ..io.atomic import atomic_write_bytes
from ..robot.arm.model import RobotModel
from ._mujoco import INSTALL_HINT, RenderUnavailable, mujoco
from .scene import Scene

__all__ = [
    "RenderUnavailable",
    "Renderer",
    "frame_times",
    "render_frames",
    "render_strip",
    "render_video",
]

Source = Any  # PlaybackResult | Scene | RobotModel


def _scene_of(source: Source, width: int, height: int) -> Scene:
    from .result import PlaybackResult

    if isinstance(source, PlaybackResult):
        scene = source.scene or Scene(source.robot)
    elif isinstance(source, Scene):
        scene = source
    elif isinstance(source, RobotModel):
        scene = Scene(source)
    else:
        raise ValueError(
            f"source: expected a PlaybackResult, Scene or RobotModel, got {type(source).__name__}"
        )
    if scene.width < width or scene.height < height:
        import dataclasses

        scene = dataclasses.replace(
            scene, width=max(scene.width, width), height=max(scene.height, height)
        )
    return scene


def _motion(
    source: Source, t: ArrayLike | None, q: ArrayLike | None
) -> tuple[FloatArray, FloatArray]:
    from .result import PlaybackResult

    if isinstance(source, PlaybackResult) and t is None and q is None:
        return source.t, source.q
    if q is None:
        raise ValueError("q: joint positions (M, J) are needed to render a Scene or RobotModel")
    qa = np.asarray(q, dtype=np.float64)
    if qa.ndim == 1:
        qa = qa[None]
    ta = (
        np.arange(qa.shape[0], dtype=np.float64) * 0.04
        if t is None
        else np.asarray(t, dtype=np.float64)
    )
    if ta.shape != (qa.shape[0],):
        raise ValueError(f"t: expected shape ({qa.shape[0]},) like q's rows, got {ta.shape}")
    if ta.size > 1 and np.any(np.diff(ta) <= 0):
        raise ValueError("t: times must increase strictly")
    return ta, qa


def frame_times(t: FloatArray, fps: float) -> FloatArray:
    """Frame times ``t0 + i / fps`` covering ``[t0, t_end]`` (s)."""
    if not fps > 0:
        raise ValueError(f"fps: must be positive, got {fps}")
    n = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    return t[0] + np.arange(n) / float(fps)


def _sample(t: FloatArray, q: FloatArray, times: FloatArray) -> FloatArray:
    """Joint positions at ``times``, linear between samples (exact on the samples)."""
    return interp_linear(times, t, q)


_OPEN: weakref.WeakSet[Renderer] = weakref.WeakSet()


@atexit.register
def _close_all() -> None:
    """Free GL contexts before interpreter teardown (OSMesa's finaliser fails after it)."""
    for r in list(_OPEN):
        r.close()


class Renderer:
    """An off-screen renderer of a scene (context manager; closes its GL context).

    ``Renderer(scene, width=640, height=480, camera="cell")``; ``frame(q)``
    returns an (H, W, 3) uint8 image of the arm at joint positions q (J,).
    Raises :class:`RenderUnavailable` when no OpenGL context can be made.
    """

    def __init__(
        self, source: Source, width: int = 640, height: int = 480, camera: str | int = "cell"
    ) -> None:
        for name, v in (("width", width), ("height", height)):
            if not isinstance(v, (int, np.integer)) or v < 16 or v % 2:
                raise ValueError(f"{name}: expected an even number of pixels >= 16, got {v!r}")
        scene = _scene_of(source, width, height)
        self.scene = scene
        self._mj = mj = mujoco()
        self.model = mj.MjModel.from_xml_string(scene.mjcf())
        self.data = mj.MjData(self.model)
        self.width, self.height, self.camera = int(width), int(height), camera
        self._r = _make_renderer(mj, self.model, self.height, self.width)
        self._flags_set = False
        _OPEN.add(self)

    def frame(
        self, q: ArrayLike, decorate: Any = None, camera: Any = None
    ) -> np.ndarray:
        """(H, W, 3) uint8 image at joint positions q (J,) [rad].

        ``decorate(scene)`` is called with the ``mjvScene`` before rendering (to add
        decorative geoms); ``camera`` overrides the renderer's camera (a name, an id
        or an ``MjvCamera``)."""
        mj = self._mj
        J = self.scene.robot.n_joints
        self.data.qpos[:J] = np.asarray(q, dtype=np.float64)
        mj.mj_kinematics(self.model, self.data)
        mj.mj_comPos(self.model, self.data)
        mj.mj_camlight(self.model, self.data)  # camera and light poses
        r = self._r
        r.update_scene(self.data, camera=self.camera if camera is None else camera)
        if decorate is not None:
            decorate(r.scene)
        if not self._flags_set:
            r.scene.flags[mj.mjtRndFlag.mjRND_SHADOW] = False
            r.scene.flags[mj.mjtRndFlag.mjRND_REFLECTION] = False
            self._flags_set = True
        return r.render()

    def close(self) -> None:
        """Free the GL context (errors while closing are ignored); idempotent."""
        r, self._r = getattr(self, "_r", None), None
        if r is not None:
            with contextlib.suppress(Exception):
                r.close()

    def __enter__(self) -> Renderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:  # pragma: no cover - best effort
        self.close()


def _make_renderer(mj: Any, model: Any, height: int, width: int) -> Any:
    backend = os.environ.get("MUJOCO_GL", "")
    model.vis.global_.offwidth = max(int(model.vis.global_.offwidth), width)
    model.vis.global_.offheight = max(int(model.vis.global_.offheight), height)
    try:
        with warnings.catch_warnings():  # glfw warns before it fails without a display
            warnings.simplefilter("ignore")
            return mj.Renderer(model, height=height, width=width)
    except Exception as exc:  # every GL failure means "no rendering here"
        reason = f"{type(exc).__name__}: {exc}".strip().splitlines()[0][:300]
        raise RenderUnavailable(
            f"cannot create an OpenGL context for off-screen rendering "
            f"(MUJOCO_GL={backend or 'unset'}; {reason}); {INSTALL_HINT}"
        ) from None


def _frames(
    source: Source,
    t: ArrayLike | None,
    q: ArrayLike | None,
    fps: float,
    width: int,
    height: int,
    camera: str | int,
    annotate: bool = True,
    phases: Any = None,
) -> Iterator[np.ndarray]:
    ta, qa = _motion(source, t, q)
    times = frame_times(ta, fps)
    qs = _sample(ta, qa, times)
    with Renderer(source, width, height, camera) as r:
        if not annotate or r.scene.tool is None or r.scene.stock is None:
            for qk in qs:
                yield r.frame(qk)
            return
        from .annotate import CutAnnotator

        with CutAnnotator(r, ta, qa, times, phases) as ann:
            for i, qk in enumerate(qs):
                yield ann.frame(i, qk)


def render_frames(
    source: Source,
    t: ArrayLike | None = None,
    q: ArrayLike | None = None,
    *,
    fps: float = 25.0,
    width: int = 640,
    height: int = 480,
    camera: str | int = "cell",
    annotate: bool = True,
    phases: Any = None,
) -> np.ndarray:
    """Frames (K, H, W, 3) uint8 of a motion at ``fps`` (K = duration x fps + 1).

    ``source`` is a :class:`~ruledrobot.sim.playback.PlaybackResult` (its
    scene and simulated motion) or a Scene / RobotModel with ``t`` (M,) [s]
    and ``q`` (M, J) [rad] (``t`` defaults to 25 samples per second).

    ``annotate`` (scenes with a bow and a stock): the cut surface the wire has
    swept appears in the stock, the wire's path stays as a trail, a caption
    gives time, phase and feed, and while the wire cuts a close-up camera on
    the wire is inset (:mod:`ruledrobot.sim.annotate`).  ``phases``: the
    motion's phases (``Phase`` sample ranges of ``t``, e.g. a trajectory's
    ``meta.phases``) for the caption.
    """
    return np.stack(list(_frames(source, t, q, fps, width, height, camera, annotate, phases)))


def render_video(
    source: Source,
    path: str | os.PathLike[str],
    t: ArrayLike | None = None,
    q: ArrayLike | None = None,
    *,
    fps: int = 25,
    width: int = 640,
    height: int = 480,
    camera: str | int = "cell",
    preset: str = "veryfast",
    progress: Any = None,
    annotate: bool = True,
    phases: Any = None,
) -> Path:
    """Render a motion to an MP4 file (H.264, yuv420p) at ``path``; returns the path.

    Arguments as :func:`render_frames` (annotated by default: cut surface, trail,
    caption, close-up during the cut).  Frames are streamed to ffmpeg, the
    file is moved into place only when complete.  ``progress(fraction,
    "render")`` is called every 25 frames.
    """
    import imageio_ffmpeg

    ta, qa = _motion(source, t, q)
    n_frames = frame_times(ta, fps).size
    out = Path(path)
    with tempfile.TemporaryDirectory(
        prefix=".render-", dir=out.parent if out.parent.exists() else None
    ) as tmp:
        tmp_path = os.path.join(tmp, "video.mp4")
        writer = None
        try:
            frames = _frames(source, ta, qa, fps, width, height, camera, annotate, phases)
            for i, frame in enumerate(frames):
                if writer is None:
                    writer = imageio_ffmpeg.write_frames(
                        tmp_path,
                        (width, height),
                        fps=fps,
                        codec="libx264",
                        macro_block_size=2,
                        quality=None,
                        ffmpeg_log_level="error",
                        output_params=["-preset", preset, "-crf", "23"],
                    )
                    writer.send(None)
                writer.send(np.ascontiguousarray(frame))
                if progress is not None and i % 25 == 0:
                    progress(i / n_frames, "render")
        finally:
            if writer is not None:
                writer.close()
        data = Path(tmp_path).read_bytes()
    if progress is not None:
        progress(1.0, "render")
    return atomic_write_bytes(out, data)


def render_strip(
    source: Source,
    path: str | os.PathLike[str],
    t: ArrayLike | None = None,
    q: ArrayLike | None = None,
    *,
    frames: int = 5,
    width: int = 640,
    height: int = 480,
    scale: float = 0.5,
    camera: str | int = "cell",
) -> Path:
    """A PNG of ``frames`` views side by side, evenly spaced in time from start to end.

    Each view is rendered at ``width`` x ``height`` and shrunk by ``scale``
    (nearest pixels).  Returns the path.
    """
    import imageio.v3 as iio

    if not isinstance(frames, (int, np.integer)) or frames < 1:
        raise ValueError(f"frames: expected an integer >= 1, got {frames!r}")
    ta, qa = _motion(source, t, q)
    times = np.linspace(ta[0], ta[-1], int(frames))
    qs = _sample(ta, qa, times)
    step = max(1, round(1.0 / scale)) if scale < 1.0 else 1
    with Renderer(source, width, height, camera) as r:
        images = [r.frame(qk)[::step, ::step] for qk in qs]
    gap = np.full((images[0].shape[0], 4, 3), 255, dtype=np.uint8)
    row = [images[0]]
    for img in images[1:]:
        row += [gap, img]
    strip = np.concatenate(row, axis=1)
    return atomic_write_bytes(path, iio.imwrite("<bytes>", strip, extension=".png"))
