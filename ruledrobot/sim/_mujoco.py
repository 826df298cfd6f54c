"""Lazy MuJoCo import and the choice of the headless OpenGL backend.

MuJoCo reads ``MUJOCO_GL`` once, when ``mujoco`` is first imported, so the
backend must be chosen before that.  :func:`configure_gl` sets a default
(``egl``, else ``osmesa``) only when the variable is unset *and* ``mujoco``
has not been imported yet; every function of :mod:`ruledrobot.sim` imports
MuJoCo through :func:`mujoco`, which calls it first.
"""

from __future__ import annotations

import ctypes
import os
import sys
from types import ModuleType

__all__ = ["RenderUnavailable", "configure_gl", "mujoco"]

#: Shared libraries probed (with ``dlopen``) to choose the default backend.
_EGL_LIBS = ("libEGL.so.1", "libEGL.so")
_OSMESA_LIBS = ("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so")

#: What to install for each backend (Debian/Ubuntu package names).
INSTALL_HINT = (
    "install a headless OpenGL backend and select it before mujoco is imported: "
    "either EGL (apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1; "
    "export MUJOCO_GL=egl) or OSMesa (apt-get install libosmesa6; export MUJOCO_GL=osmesa)"
)


class RenderUnavailable(RuntimeError):
    """No OpenGL context can be made for off-screen rendering (message says what to do)."""


def _loadable(names: tuple[str, ...]) -> bool:
    for name in names:
        try:
            ctypes.CDLL(name)
        except OSError:
            continue
        return True
    return False


def configure_gl(default: str | None = None) -> str | None:
    """Choose MuJoCo's OpenGL backend if nobody has: returns the value of ``MUJOCO_GL``.

    When ``MUJOCO_GL`` is unset and ``mujoco`` is not imported yet, sets it to
    ``default`` if given, else to ``"egl"`` when ``libEGL`` loads, else to
    ``"osmesa"`` when ``libOSMesa`` loads (else leaves it unset).  Never
    overrides a user's setting; after ``import mujoco`` it changes nothing
    (MuJoCo has read the variable already).
    """
    current = os.environ.get("MUJOCO_GL")
    if current or "mujoco" in sys.modules:
        return current or None
    choice = default
    if choice is None:
        if _loadable(_EGL_LIBS):
            choice = "egl"
        elif _loadable(_OSMESA_LIBS):
            choice = "osmesa"
    if choice:
        os.environ["MUJOCO_GL"] = choice
    return choice


def mujoco() -> ModuleType:
    """``import mujoco`` after :func:`configure_gl` (physics never needs GL; rendering does).

    Raises ImportError with an install hint when the package is missing.
    """
    if "mujoco" not in sys.modules:
        configure_gl()
    try:
        import mujoco as mj
    except ImportError as exc:  # pragma: no cover - mujoco is a dependency
        raise ImportError(f"ruledrobot.sim needs MuJoCo (pip install mujoco): {exc}") from exc
    except RuntimeError as exc:
        # mujoco refuses to import at all with an unknown MUJOCO_GL value
        value = os.environ.get("MUJOCO_GL", "")
        raise RenderUnavailable(
            f"mujoco cannot be imported with MUJOCO_GL={value!r} ({exc}); unset it or "
            f"set it to 'egl' or 'osmesa'; {INSTALL_HINT}"
        ) from None
    return mj
