"""The ``ruledrobot`` command line (typer): parse, call one function, print.

Sub-commands live by subject: :mod:`.surfaces` (refine, gallery, chain), :mod:`.formats`
(convert), :mod:`.plan` (plan, simulate, demo), :mod:`.reach` (reach, place), :mod:`.carve`
(carve), :mod:`.make` (make), :mod:`.kerf` (kerf ladder, kerf fit), :mod:`.batch`,
:mod:`.view`, :mod:`.robot` (export, run, ursim, calibration).  Each prints an example in
``--help`` and says where it wrote its files.  Errors in user input exit with status 2 and
a one-line message (no traceback); a failing check exits 1.
"""

from __future__ import annotations

import importlib

from ._common import app, reflow_help

# importing a command module registers its commands; this order is the order of --help
for _module in ("surfaces", "formats", "plan", "reach", "carve", "make", "kerf", "batch",
                "view", "robot"):
    importlib.import_module(f".{_module}", __name__)
reflow_help(app)

__all__ = ["app", "main"]


def main() -> None:
    """Console-script entry point."""
    from ..sim import configure_gl

    configure_gl()  # choose EGL/OSMesa before anything imports MuJoCo
    app()

