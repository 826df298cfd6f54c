"""The live viewer: a plan's scene served to the browser on loopback (viser).

:class:`ViewServer` starts viser's HTTP + websocket server on ``host:port``
(``127.0.0.1`` by default), draws the scene (:class:`~ruledrobot.view.draw.Painter`)
and adds the panel: verdict and notes, the timeline (play / pause, a time
slider to scrub, speed, jump to a phase or an event), the figures at the
current time, the events, the table of checks and what to show.
:func:`serve` runs one until Ctrl-C (or ``duration`` seconds).

**Addresses.** The server refuses a non-loopback address unless
``allow_remote=True`` (:class:`RemoteRefused`, a ValueError): the viewer has
no authentication, and a plan folder describes a work cell.  viser's share
button (a tunnel through viser's own relay) is hidden.
"""

from __future__ import annotations

import contextlib
import io
import ipaddress
import os
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ._viser import viser
from .draw import Painter, figures_markdown
from .folder import PlanFolder
from .kerf import kerf_legend_html
from .scene import PlanScene, build_scene

__all__ = ["RemoteRefused", "ViewServer", "check_host", "serve"]

SPEEDS = ("0.25x", "0.5x", "1x", "2x", "4x", "8x")


class RemoteRefused(ValueError):
    """A non-loopback address without ``allow_remote`` (the message says what to do)."""


def check_host(host: str, allow_remote: bool = False) -> str:
    """``host`` if the server may bind it.

    A loopback address (127.0.0.0/8, ::1, ``localhost``), or any address with ``allow_remote``;
    else :class:`RemoteRefused`."""
    if host == "localhost":
        return host
    try:
        addr = ipaddress.ip_address(host)
        loopback = addr.is_loopback
    except ValueError:
        try:
            infos = socket.getaddrinfo(host, None)
            loopback = bool(infos) and all(ipaddress.ip_address(i[4][0]).is_loopback
                                           for i in infos)  # fmt: skip
        except OSError:
            loopback = False
    if not loopback and not allow_remote:
        raise RemoteRefused(
            f"--host {host}: not a loopback address; the viewer has no authentication and "
            "would show this work cell to anyone who can reach the address. Use 127.0.0.1 "
            "(the default), or pass --allow-remote to serve on it anyway"
        )
    return host


def _markdown_checks(scene: PlanScene) -> str:
    rows = []
    for c in scene.checks:
        mark = ("ok" if c.ok else "**FAIL**") if c.gating else "info"
        rows.append(f"| {c.label} | {c.value_text} | {c.limit_text} | {mark} |")
    failed = [f"- **{c.name}**: {line}" for c in scene.checks if c.gating and not c.ok
              for line in c.detail.splitlines()]  # fmt: skip
    table = "| check | value | limit | ok |\n|---|--:|--:|---|\n" + "\n".join(rows)
    return table + ("\n\n" + "\n".join(failed) if failed else "")


def _markdown_events(scene: PlanScene) -> str:
    if not scene.events:
        return (f"No collision; no two parts closer than {1e3 * scene.limits['near_miss']:.0f} "
                "mm along the motion.")  # fmt: skip
    return "\n".join(f"- {e.sentence}" + ("" if e.position else " (no motion to locate it on)")
                     for e in scene.events)  # fmt: skip


class ViewServer:
    """A running viewer of one plan scene (context manager: ``close()`` stops it).

    ``url`` is where to open it.  The timeline is driven by :meth:`tick` (called
    by :func:`serve`'s loop) and by the panel's controls.
    """

    def __init__(
        self, scene: PlanScene, host: str = "127.0.0.1", port: int = 8080,
        *, allow_remote: bool = False, play: bool = False,
    ) -> None:  # fmt: skip
        check_host(host, allow_remote)
        v = viser()
        self.scene = scene
        with contextlib.redirect_stdout(io.StringIO()):  # viser's banner: we print our own
            self.server = server = v.ViserServer(host=host, port=port, verbose=False)
        self.host = host
        self.port = int(server.get_port())
        shown = f"[{host}]" if ":" in host else host
        self.url = f"http://{shown}:{self.port}/"
        self._lock = threading.RLock()
        self.playing = bool(play) and scene.timeline is not None
        try:
            server.gui.configure_theme(show_share_button=False, control_width="large")
            self.painter = Painter(server, scene)
            self._panel()
            self.painter.show(0)
        except BaseException:
            self.close()
            raise

    # -- the panel ---------------------------------------------------------------------
    def _panel(self) -> None:
        scene, gui = self.scene, self.server.gui
        verdict = scene.verdict
        notes = "".join(f"\n- {n}" for n in scene.notes)
        gui.add_markdown(f"**{scene.title}**\n\n**verdict: {verdict}**{notes}")
        tl = scene.timeline
        legend = kerf_legend_html(scene)  # "" without a predicted kerf
        self.figures = None
        if tl is not None:
            with gui.add_folder("Timeline"):
                self.play_button = gui.add_button("Pause" if self.playing else "Play")
                step = float(np.median(np.diff(tl.t))) if tl.t.size > 1 else 0.05
                self.slider = gui.add_slider("time (s)", float(tl.t[0]), float(tl.t[-1]),
                                             step, float(tl.t[0]))  # fmt: skip
                self.speed = gui.add_dropdown("speed", SPEEDS, initial_value="1x")
                self._jumps = self._jump_targets()
                self.jump = gui.add_dropdown("jump to", tuple(self._jumps),
                                             initial_value=next(iter(self._jumps)))  # fmt: skip
            with gui.add_folder("At this time"):
                self.figures = gui.add_markdown(figures_markdown(scene, 0))
                if legend:
                    gui.add_html(legend)

            @self.play_button.on_click
            def _(_: Any) -> None:
                self.playing = not self.playing
                self.play_button.label = "Pause" if self.playing else "Play"

            @self.slider.on_update
            def _(_: Any) -> None:
                self.show_time(float(self.slider.value))

            @self.jump.on_update
            def _(_: Any) -> None:
                target = self._jumps.get(self.jump.value)
                if target is not None:
                    self.playing = False
                    self.play_button.label = "Play"
                    self.slider.value = target
        with gui.add_folder("Collisions and near misses", expand_by_default=bool(scene.events)):
            gui.add_markdown(_markdown_events(scene))
        with gui.add_folder("Checks", expand_by_default=not scene.ok):
            gui.add_markdown(_markdown_checks(scene))
        with gui.add_folder("Show", expand_by_default=False):
            for group, label in (("cut", "cut surface swept"), ("trail", "wire trail"),
                                 ("rulings", "rulings"), ("surface", "planned surface"),
                                 ("stock", "stock"), ("events", "event markers"),
                                 *((("kerf", "predicted kerf trace"),) if legend else ())
                                 ):  # fmt: skip
                box = gui.add_checkbox(label, True)
                box.on_update(self._toggle(group, box))

    def _toggle(self, group: str, box: Any) -> Callable[[Any], None]:
        def handler(_: Any) -> None:
            with self._lock:
                self.painter.set_visible(group, bool(box.value))

        return handler

    def _jump_targets(self) -> dict[str, float]:
        tl = self.scene.timeline
        assert tl is not None
        out: dict[str, float] = {"start": float(tl.t[0])}
        change = np.flatnonzero(np.r_[True, tl.phase[1:] != tl.phase[:-1]])
        for k in change:
            out.setdefault(f"{tl.phase[k]} (t = {tl.t[k]:.1f} s)", float(tl.t[k]))
        for e in self.scene.events:
            out.setdefault(f"{e.kind}: {e.what} (t = {e.time:.1f} s)", e.time)
        return out

    # -- the timeline ------------------------------------------------------------------
    def show_time(self, time_s: float) -> None:
        """Pose the scene and the figures at ``time_s`` (s)."""
        tl = self.scene.timeline
        if tl is None:
            return
        k = tl.frame_at(time_s)
        with self._lock:
            self.painter.show(k)
            if self.figures is not None:
                self.figures.content = figures_markdown(self.scene, k)

    def tick(self, dt: float) -> None:
        """Advance the timeline by ``dt`` seconds of wall time when playing (loops)."""
        tl = self.scene.timeline
        if tl is None or not self.playing:
            return
        speed = float(str(self.speed.value).rstrip("x"))
        t = float(self.slider.value) + dt * speed
        if t > tl.t[-1]:
            t = float(tl.t[0])
        self.slider.value = t

    def close(self) -> None:
        """Stop the server (idempotent)."""
        server, self.server = getattr(self, "server", None), None
        if server is not None:
            with contextlib.redirect_stdout(io.StringIO()):
                server.stop()

    def __enter__(self) -> ViewServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def serve(
    source: PlanScene | PlanFolder | str | os.PathLike[str],
    *,
    host: str = "127.0.0.1",
    port: int = 8080,
    allow_remote: bool = False,
    fps: float = 20.0,
    play: bool = True,
    duration: float | None = None,
    ready: Callable[[ViewServer], None] | None = None,
) -> None:
    """Serve the scene of a plan folder until Ctrl-C (or ``duration`` s).

    ``host`` must be loopback unless ``allow_remote`` (:func:`check_host`, checked
    before anything is read); ``port`` 0 takes a free one; ``fps`` display frames
    per second of trajectory time; ``play`` starts playing; ``ready(server)`` is
    called once the server listens (print ``server.url`` there).
    """
    check_host(host, allow_remote)
    scene = source if isinstance(source, PlanScene) else build_scene(source, fps=fps)
    with ViewServer(scene, host, port, allow_remote=allow_remote, play=play) as srv:
        if ready is not None:
            ready(srv)
        start = last = time.monotonic()
        try:
            while duration is None or time.monotonic() - start < duration:
                time.sleep(0.05)
                now = time.monotonic()
                srv.tick(now - last)
                last = now
        except KeyboardInterrupt:
            pass
