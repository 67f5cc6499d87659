"""Test-suite configuration: render MuJoCo offscreen (EGL) on a machine without a display.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, so it is set here,
before any test module imports ``mujoco``; the product never sets it on import.
"""

import os

if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"
