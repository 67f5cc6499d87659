"""Simulation: the world around the controller.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations.
- :mod:`sim.scene` — the MuJoCo scene (swaying torso with the SuperLimb, table, plate, food, fork).
- :mod:`sim.servo` — the joint servo at the physics rate, limits held in MuJoCo.
- :mod:`sim.wearer` — the simulated wearer (their own plan when leading, delayed corrections);
  :mod:`sim.wearer_presets` — its presets from the literature (unimpaired, mild and severe hemiparesis).
- :mod:`sim.closed_loop` — ``run_episode``; :mod:`sim.episode` — its record and run file;
  :mod:`sim.metrics` — episode metrics.
- :mod:`sim.render` — offscreen video.

``sim`` imports ``learning`` and ``robot``, never ``mpcshare``: the command line
that runs it (``mpcshare generate``, ``mpcshare sim``, ``mpcshare demo``) lives in
:mod:`mpcshare.cli`. Importing ``sim`` changes nothing in the process; to render
headless, set ``MUJOCO_GL=egl`` before MuJoCo is first imported (the ``mpcshare``
command line does this when the variable is unset and there is no display).
"""
