"""The ``view`` command: a plan folder in the browser (``docs/view.md``)."""

from __future__ import annotations

from pathlib import Path

import typer

from ._common import app, console, fail


def show(folder: Path, export: Path | None = None, **options) -> None:
    """Serve the viewer of a plan folder until Ctrl-C, or write its static export.

    Exit 2 on a folder that is not a plan folder, a refused address or a missing viewer extra."""
    from ..view import ViewerUnavailable, export_html, serve

    try:
        if export is not None:
            path = export_html(folder, export)
            console.print(f"wrote {path}  ({path.stat().st_size / 1e6:.1f} MB, opens in a "
                          "browser with no Python and no network)", highlight=False,
                          markup=False)  # fmt: skip
            return
        serve(folder, ready=lambda srv: console.print(
            f"viewer of {folder} at {srv.url}  (open it in a browser; Ctrl-C stops)",
            highlight=False, markup=False), **options)  # fmt: skip
    except (ValueError, ViewerUnavailable, OSError) as exc:
        raise fail(str(exc)) from None


@app.command(epilog="Example:  ruledrobot view out/cut     or:  ruledrobot view out/cut "
             "--export scene.html")
def view(
    folder: Path = typer.Argument(..., help="Plan folder (what `ruledrobot plan` writes)."),
    export: Path | None = typer.Option(None, "--export", help="Write one self-contained HTML "
                                       "file of the scene instead of serving it."),
    host: str = typer.Option("127.0.0.1", help="Address to serve on (loopback only, unless "
                             "--allow-remote)."),
    port: int = typer.Option(8080, min=0, max=65535, help="Port (0: any free port)."),
    allow_remote: bool = typer.Option(False, "--allow-remote", help="Serve on a non-loopback "
                                      "address (the viewer has no authentication)."),
    duration: float | None = typer.Option(None, min=0.0, help="Stop after this many seconds "
                                          "(default: run until Ctrl-C)."),
) -> None:
    """Show a plan folder in the browser.

    The arm, bow and wire moving through the stock, the cut surface, the rulings, a timeline to
    play and scrub, phase and live figures, collisions and near misses, the table of checks.
    Never plans anything."""
    show(folder, export, host=host, port=port, allow_remote=allow_remote, duration=duration)
