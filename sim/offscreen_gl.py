"""The OpenGL back-end MuJoCo renders with, chosen before MuJoCo is imported.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, and defaults to GLFW, which needs
a display. :func:`prefer_offscreen_gl` sets ``MUJOCO_GL=egl`` (headless rendering through a GPU
driver's or Mesa's EGL) when the variable is unset and there is no ``DISPLAY``; a value set by
the user, or a display, is left alone. The :mod:`sim` package calls it on import, before any of
its modules imports MuJoCo, so the choice holds whatever imports ``sim`` first.
"""

from __future__ import annotations

import os

__all__ = ["gl_hint", "prefer_offscreen_gl"]


def prefer_offscreen_gl() -> None:
    """``MUJOCO_GL=egl`` when it is unset and there is no display (module docstring)."""
    if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"


def gl_hint() -> str:
    """What to do when no OpenGL context could be made, for the back-end in use."""
    backend = os.environ.get("MUJOCO_GL", "")
    if backend == "egl":
        return ("MUJOCO_GL=egl needs an EGL library (a GPU driver's, or Mesa's: apt install libegl1); "
                "or set MUJOCO_GL=osmesa")
    if backend == "osmesa":
        return "MUJOCO_GL=osmesa needs OSMesa (apt install libosmesa6); or set MUJOCO_GL=egl"
    return f"MUJOCO_GL={backend or '(unset: GLFW)'} needs a display; set MUJOCO_GL=egl (or osmesa) to render headless"
