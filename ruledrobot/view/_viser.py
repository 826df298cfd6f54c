"""The optional viewer library, imported only where it is used."""

from __future__ import annotations

from types import ModuleType

__all__ = ["EXTRA_HINT", "ViewerUnavailable", "viser"]

EXTRA_HINT = "install the viewer extra: pip install 'ruledrobot[view]' (viser)"


class ViewerUnavailable(ImportError):
    """The viewer library (viser) is not installed; the message names the extra."""


def viser() -> ModuleType:
    """``import viser``, or :class:`ViewerUnavailable` naming the ``view`` extra."""
    try:
        import viser as v
    except ImportError as exc:
        raise ViewerUnavailable(f"the 3-D viewer needs viser, which is missing ({exc}); "
                                f"{EXTRA_HINT}") from None  # fmt: skip
    return v
