"""Simulation: the world around the controller.

- :mod:`sim.demonstrator` — synthetic bimanual-eating demonstrations (the default data); :mod:`sim.regime_free`,
  :mod:`sim.hidden_regime` — data without hidden modes and with weakly cued ones (calibrating the analysis);
  :mod:`sim.world_family` — the randomised family of worlds, on which the closed-loop claims are checked.
- :mod:`sim.scene` — the MuJoCo scene (swaying torso with the arm, table, plate, food, fork);
  :mod:`sim.arm_mounts` — where each preset arm of :mod:`robot.presets` stands; :mod:`sim.servo` — the joint servo.
- :mod:`sim.wearer_protocol` — what the closed loop needs from a wearer; :mod:`sim.wearer` — the simulated
  wearer; :mod:`sim.wearer_presets` — its presets from the literature, numbers in :mod:`sim.wearer_preset_values`.
- :mod:`sim.closed_loop` — ``run_episode``; :mod:`sim.episode` — its record and run file; :mod:`sim.metrics` —
  episode metrics; :mod:`sim.keepout_metrics` — how close the knife came to the wearer's body;
  :mod:`sim.task` — the task (eating): modes, sawing, body zones, shoulder layout, figures;
  :mod:`sim.run_mcap` — a run as MCAP for Foxglove.
- :mod:`sim.render` — offscreen video; :mod:`sim.offscreen_gl` — the OpenGL back-end, chosen on import.
- :mod:`sim.errors` — :class:`~sim.errors.SimError`, the root of the errors ``sim`` raises.

``sim`` imports ``learning`` and ``robot``, never ``mpcshare`` (its commands live in :mod:`mpcshare.cli`).
Importing ``sim`` sets ``MUJOCO_GL=egl`` when it is unset and there is no display (:mod:`sim.offscreen_gl`),
before any module of ``sim`` imports MuJoCo, so that video renders headless whatever is imported first.
"""

from sim.offscreen_gl import prefer_offscreen_gl

prefer_offscreen_gl()
