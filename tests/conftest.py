"""Test-suite configuration: render MuJoCo offscreen (EGL) on a machine without a display.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, so it is set here,
before any test module imports ``mujoco``; the product never sets it on import.
"""

from mpcshare.cli import prefer_offscreen_gl  # imports neither mujoco nor torch

prefer_offscreen_gl()
