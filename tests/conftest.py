"""Test-suite configuration: MuJoCo renders offscreen (EGL) on a machine without a display.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported; importing :mod:`sim` chooses it
(:mod:`sim.offscreen_gl`), so it is imported here, before any test module imports ``mujoco`` directly.
"""

import sim  # noqa: F401  (chooses MUJOCO_GL; imports neither mujoco nor torch)
