"""Headless rendering: frames are not blank, MP4 and PNG strip are written, and a missing
OpenGL backend raises RenderUnavailable with an actionable message (no crash trace)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from ruledrobot.sim import Renderer, RenderUnavailable, play, render_strip, render_video
from ruledrobot.sim.scene import example_scene

from .helpers import smooth_trajectory


def _renderer_or_skip(scene, **kw) -> Renderer:
    """A renderer; on a machine without EGL the test is skipped, except in CI (CI=true)
    where .ci/run installs Mesa EGL and a failure must show."""
    try:
        return Renderer(scene, **kw)
    except RenderUnavailable as exc:
        if os.environ.get("CI"):
            raise
        pytest.skip(f"no headless OpenGL here: {exc}")


def _run(code: str, **env: str) -> subprocess.CompletedProcess:
    full = {
        k: v
        for k, v in os.environ.items()
        if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY", "WAYLAND_DISPLAY")
    }
    full.update(env)
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        env=full,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_frame_is_not_blank():
    scene = example_scene()
    with _renderer_or_skip(scene, width=320, height=240) as r:
        img = r.frame([0.3, -1.6, 1.4, -1.4, -1.57, 0.0])
        img2 = r.frame([1.3, -1.2, 1.0, -1.4, -1.57, 0.0])
    assert img.shape == (240, 320, 3) and img.dtype == np.uint8
    assert img.std() > 10.0
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50
    assert np.abs(img.astype(int) - img2).mean() > 1.0  # the arm moved


def test_video_and_strip(tmp_path):
    scene = example_scene()
    _renderer_or_skip(scene, width=320, height=240).close()
    t, q, qd = smooth_trajectory(1.0)
    res = play(scene, t, q, qd, collisions=False)
    seen = []
    video = render_video(
        res,
        tmp_path / "v" / "cut.mp4",
        fps=25,
        width=320,
        height=240,
        progress=lambda f, s: seen.append(f),
    )
    data = video.read_bytes()
    assert len(data) > 2000 and data[4:8] == b"ftyp"
    assert seen[-1] == 1.0
    import imageio.v3 as iio

    frames = iio.imread(video, plugin="pyav") if _has_pyav() else None
    if frames is not None:
        assert frames.shape[0] == 26
    strip = render_strip(res, tmp_path / "strip.png", frames=3, width=320, height=240)
    img = iio.imread(strip)
    assert img.shape == (120, 3 * 160 + 2 * 4, 3)
    assert not list(tmp_path.glob("v/.*"))  # no temporary files left


def _has_pyav() -> bool:
    try:
        import av  # noqa: F401
    except ImportError:
        return False
    return True


def test_bad_resolution():
    with pytest.raises(ValueError, match="width"):
        Renderer(example_scene(), width=321)


@pytest.mark.parametrize(
    ("backend", "expect"),
    [("bogus", "MUJOCO_GL='bogus'"), ("glfw", "MUJOCO_GL=glfw")],
)
def test_render_unavailable_is_clean(backend, expect):
    """An unknown backend makes `import mujoco` fail; glfw without a display cannot make a
    context.  Both end in RenderUnavailable naming the packages and MUJOCO_GL values."""
    out = _run(
        """
        from ruledrobot.sim import RenderUnavailable, Renderer
        from ruledrobot.robot import load
        try:
            Renderer(load("ur5e"), width=64, height=48)
        except RenderUnavailable as exc:
            assert isinstance(exc, RuntimeError)
            print("CLEAN:", exc)
        """,
        MUJOCO_GL=backend,
    )
    assert out.returncode == 0, out.stderr
    assert "CLEAN:" in out.stdout
    assert expect in out.stdout and "libosmesa6" in out.stdout and "egl" in out.stdout
    assert "Traceback" not in out.stderr


def test_import_is_cheap_and_backend_defaults():
    out = _run(
        """
        import os, sys
        import ruledrobot.sim as s
        from ruledrobot.sim import _mujoco as g
        assert "mujoco" not in sys.modules, "import ruledrobot.sim imported mujoco"
        expected = ("egl" if g._loadable(g._EGL_LIBS)
                    else "osmesa" if g._loadable(g._OSMESA_LIBS) else None)
        assert s.configure_gl() == expected
        chosen = os.environ.get("MUJOCO_GL")
        assert chosen == expected
        s.robot_mjcf  # lazy attribute, still no mujoco
        assert "mujoco" not in sys.modules
        import mujoco
        os.environ.pop("MUJOCO_GL", None)
        assert s.configure_gl() is None  # too late: mujoco is imported, nothing is set
        assert "MUJOCO_GL" not in os.environ
        print("CHOSEN:", chosen)
        """
    )
    assert out.returncode == 0, out.stderr
    assert "CHOSEN:" in out.stdout
    out = _run("import ruledrobot.sim as s; print(s.configure_gl())", MUJOCO_GL="osmesa")
    assert out.stdout.strip() == "osmesa"  # a user's choice is kept
