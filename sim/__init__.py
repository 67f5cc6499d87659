"""Simulation: the world around the controller.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations.
- :mod:`sim.scene` — the MuJoCo scene (swaying torso with the SuperLimb, table, plate, food, fork).
- :mod:`sim.kinematics` — closed-form knife-tip kinematics (reachability, start pose).
- :mod:`sim.servo` — the joint servo at the physics rate, limits held in MuJoCo.
- :mod:`sim.wearer` — the simulated wearer (shoulder commands toward the intent).
- :mod:`sim.closed_loop` — ``run_episode`` and the run file; :mod:`sim.metrics` — episode metrics.
- :mod:`sim.render` — offscreen video; :mod:`sim.cli` — the console script's simulator subcommands.

Importing ``sim`` sets ``MUJOCO_GL=egl`` when it is unset and there is no display:
MuJoCo picks its OpenGL backend once, when it is first imported, and EGL is what
renders offscreen on a headless machine.
"""

import os as _os

if "MUJOCO_GL" not in _os.environ and not _os.environ.get("DISPLAY"):
    _os.environ["MUJOCO_GL"] = "egl"
