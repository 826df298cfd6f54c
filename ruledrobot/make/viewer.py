"""The viewer folder: each setup's scene as one self-contained HTML file.

``view/setupN.html`` is what ``ruledrobot view DIR/setupN --export view/setupN.html``
writes (docs/view.md): the arm, bow and wire moving through the block, the cut surface,
the checks; it opens in any browser with no Python and no network.  A failed setup is
drawn too (the cell, the checks and why).  Without the ``view`` extra (viser) no file is
written and the run says so in a note: the programs do not need it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

__all__ = ["VIEW_FOLDER", "ViewOutcome", "write_view"]

#: the viewer folder's name in the make folder
VIEW_FOLDER = "view"


@dataclass(frozen=True)
class ViewOutcome:
    """The HTML file written (None when none), and a note when it was not."""

    path: Path | None
    note: str = ""


def write_view(plan_folder: Path, target: Path) -> ViewOutcome:
    """Export the scene of ``plan_folder`` to ``target`` (module doc)."""
    from ..view import ViewerUnavailable, export_html

    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        return ViewOutcome(export_html(plan_folder, target))
    except ViewerUnavailable as exc:
        return ViewOutcome(None, f"no viewer file for {plan_folder.name}: {exc}")
    except (OSError, ValueError) as exc:  # a scene that cannot be built: said, not fatal
        return ViewOutcome(None, f"no viewer file for {plan_folder.name}: {exc}")
