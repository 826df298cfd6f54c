"""Optional dependencies of the CAD formats, imported only where they are used."""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["MissingExtraError", "require"]

_PIP_NAME = {"ezdxf": "ezdxf", "rhino3dm": "rhino3dm"}


class MissingExtraError(ValueError):
    """An optional package a format needs is not installed.

    A ValueError, so that commands report it like any other unusable input (exit status 2, one
    line)."""


def require(module: str, what: str) -> ModuleType:
    """Import ``module`` for ``what``, or raise :class:`MissingExtraError`.

    ``what``: e.g. "reading DXF files"; the error names the extra that installs the module.
    """
    try:
        return importlib.import_module(module)
    except ImportError:
        pip = _PIP_NAME.get(module, module)
        raise MissingExtraError(
            f"{what} needs the Python package {pip!r}, which is not installed; "
            f"install the CAD extra: pip install 'ruledrobot[cad]' (or: pip install {pip})"
        ) from None
