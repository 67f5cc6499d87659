"""Simulation: the world around the controller.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations (the default data);
  :mod:`sim.regime_free` and :mod:`sim.hidden_regime` — data without hidden modes and with
  weakly cued ones, for calibrating the analysis; :mod:`sim.world_family` — the randomised family of
  worlds (structure drawn per seed), on which the closed-loop claims are checked.
- :mod:`sim.scene` — the MuJoCo scene (swaying torso with the SuperLimb, table, plate, food, fork).
  :mod:`sim.arm_mounts` — where each preset arm of :mod:`robot.presets` stands in it.
- :mod:`sim.servo` — the joint servo at the physics rate, limits held in MuJoCo.
- :mod:`sim.wearer_protocol` — what the closed loop needs from a wearer (:class:`~sim.wearer_protocol.Wearer`,
  a factory of one); :mod:`sim.wearer` — the simulated wearer (their own plan when leading, delayed
  corrections); :mod:`sim.wearer_presets` — its presets from the literature (unimpaired, mild and
  severe hemiparesis), their numbers in :mod:`sim.wearer_preset_values`.
- :mod:`sim.closed_loop` — ``run_episode``; :mod:`sim.episode` — its record and run file;
  :mod:`sim.metrics` — episode metrics; :mod:`sim.task` — the task (eating): its modes, sawing, body zones,
  shoulder layout and figures;
  :mod:`sim.keepout_metrics` — how close the knife came to the wearer's body;
  :mod:`sim.run_mcap` — a run as MCAP for Foxglove.
- :mod:`sim.render` — offscreen video; :mod:`sim.offscreen_gl` — the OpenGL back-end, chosen on import.
- :mod:`sim.errors` — :class:`~sim.errors.SimError`, the root of the errors ``sim`` raises.

``sim`` imports ``learning`` and ``robot``, never ``mpcshare``: the command line
that runs it (``mpcshare generate``, ``mpcshare sim``, ``mpcshare demo``) lives in
:mod:`mpcshare.cli`. Importing ``sim`` changes one thing in the process: with no
``MUJOCO_GL`` and no display it sets ``MUJOCO_GL=egl`` (:mod:`sim.offscreen_gl`), before any
module of ``sim`` imports MuJoCo, so that video renders headless whatever is imported first.
"""

from sim.offscreen_gl import prefer_offscreen_gl

prefer_offscreen_gl()
