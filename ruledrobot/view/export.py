"""The static export: one self-contained HTML file of a plan's scene, opened with no Python.

:func:`export_html` draws the scene with the same painter as the live server,
records it as viser's scene recording (every frame of the timeline, spaced by
trajectory time) and embeds the recording in viser's single-file client
(viser's ``as_html``: the client's JavaScript, styles and fonts are inlined, so
the file loads nothing from anywhere).  viser's own playback bar plays,
pauses and scrubs it; the caption at the wire carries time, phase, feed,
joint speed and singularity measure.  A fixed panel (plain HTML, no script)
adds the verdict, the table of checks, the events and the notes.

Recording needs a viser server object: it is bound to a loopback ephemeral
port for the time of the recording and no client ever connects to it.
"""

from __future__ import annotations

import contextlib
import html
import io
import os
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write_text
from ._viser import viser
from .draw import PHASE_COLOURS, Painter
from .folder import PlanFolder
from .kerf import kerf_legend_html
from .scene import PlanScene, build_scene

__all__ = ["export_html", "overlay_html"]


def _colour(rgb: tuple[int, int, int]) -> str:
    return "#{:02x}{:02x}{:02x}".format(*rgb)


def overlay_html(scene: PlanScene) -> str:
    """The fixed panel of the export: verdict, notes, checks, events, legend (HTML)."""
    e = html.escape
    ok_colour = "#1a7f37" if scene.ok else "#c62828"
    rows = []
    for c in scene.checks:
        mark = ("ok" if c.ok else "FAIL") if c.gating else "info"
        colour = {"ok": "#1a7f37", "FAIL": "#c62828", "info": "#666"}[mark]
        rows.append(f"<tr><td>{e(c.label)}</td><td class=n>{e(c.value_text)}</td>"
                    f"<td class=n>{e(c.limit_text)}</td>"
                    f"<td style='color:{colour};font-weight:600'>{mark}</td></tr>")  # fmt: skip
    failed = "".join(f"<li>{e(c.name)}: {e(line)}</li>" for c in scene.checks
                     if c.gating and not c.ok for line in c.detail.splitlines())  # fmt: skip
    events = "".join(f"<li>{e(ev.sentence)}</li>" for ev in scene.events) or \
        f"<li>no collision; nothing closer than {1e3 * scene.limits['near_miss']:.0f} mm</li>"
    notes = "".join(f"<li>{e(n)}</li>" for n in scene.notes)
    legend = " ".join(f"<span style='color:{_colour(c)}'>■</span> {e(p.replace('_', '-'))}"
                      for p, c in PHASE_COLOURS.items()
                      if p in ("approach", "lead_in", "cut", "retract"))  # fmt: skip
    return f"""
<div id="ruledrobot-panel" style="position:fixed;top:8px;right:8px;z-index:1000;max-width:430px;
 max-height:80vh;overflow:auto;background:rgba(255,255,255,0.93);border:1px solid #bbb;
 border-radius:6px;padding:6px 10px;font:12px/1.35 sans-serif;color:#222">
<style>#ruledrobot-panel td{{padding:1px 4px;border-bottom:1px solid #eee}}
#ruledrobot-panel td.n{{text-align:right;white-space:nowrap}}
#ruledrobot-panel ul{{margin:2px 0 4px 16px;padding:0}}</style>
<div style="font-weight:600">{e(scene.title)}</div>
<div style="color:{ok_colour};font-weight:700">verdict: {e(scene.verdict)}</div>
{f"<ul>{notes}</ul>" if notes else ""}
<details{"" if scene.ok else " open"}><summary>checks</summary>
<table style="border-collapse:collapse">{"".join(rows)}</table>
{f"<ul style='color:#c62828'>{failed}</ul>" if failed else ""}</details>
{kerf_legend_html(scene)}
<details><summary>collisions and near misses</summary><ul>{events}</ul></details>
<details><summary>how to read it</summary><div>Drag to turn, scroll to zoom, right-drag to
pan. The bar at the bottom plays, pauses and scrubs the motion; the caption at the wire
gives time, phase, feed, the heat and the predicted kerf (with a heat model), joint speed and
singularity measure. Red: the wire (and parts named
in a collision). Orange: the cut
surface the wire has swept in the stock. Trail of the whole wire by phase: {legend}.
Blue lines: the refined rulings; blue film: the planned surface. With a [material]: the
thick line along the part's face is the wire's chord ends' trace, coloured by the kerf
predicted there (the scale above).</div></details>
</div>"""


def export_html(
    source: PlanScene | PlanFolder | str | os.PathLike[str],
    path: str | os.PathLike[str],
    *,
    fps: float = 10.0,
) -> Path:
    """Write the scene of a plan folder as one self-contained HTML file at ``path``.

    ``source`` is a plan folder (path or :class:`PlanFolder`) or a built
    :class:`PlanScene`; ``fps`` frames per second of trajectory time in the
    recording (used when the scene is built here).  The file is written
    atomically; returns its path.  Raises
    :class:`~ruledrobot.view._viser.ViewerUnavailable` without viser.
    """
    scene = source if isinstance(source, PlanScene) else build_scene(source, fps=fps)
    v = viser()
    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner
        server = v.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        server.gui.configure_theme(show_share_button=False)
        painter = Painter(server, scene)
        painter.show(0)
        recording = server.get_scene_serializer()
        tl = scene.timeline
        if tl is not None:
            for k in range(1, tl.t.size):
                recording.insert_sleep(float(np.diff(tl.t[k - 1 : k + 1])[0]))
                painter.show(k)
        page = recording.as_html()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()
    cut = page.rfind("</body>")
    panel = overlay_html(scene)
    page = page[:cut] + panel + page[cut:] if cut >= 0 else page + panel
    return atomic_write_text(path, page)
