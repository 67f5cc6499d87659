"""mpcshare: shared control of a wearable robot arm from demonstrations (design: ``docs/design.md``).

- :mod:`mpcshare.control` — the online loop (:class:`~mpcshare.control.SharedController`, its output
  :class:`~mpcshare.control.ControlCommand`, the front end, arbitration, frames);
- :mod:`mpcshare.bundle` — model bundles and their files (:func:`load_bundle`, re-exported here lazily:
  ``import mpcshare`` imports neither torch nor scikit-learn);
- :mod:`mpcshare.training` — training a bundle, held-out evaluation, the K sweep;
  :mod:`mpcshare.calibration` — after training, the hand-over rule chosen in the closed loop;
- :mod:`mpcshare.evaluation` — closed-loop experiments: strategies compared on held-out trials, pooled
  metrics, placebo and oracle hand-overs, the ``tune`` sweep; :mod:`mpcshare.run_table` — the runs every
  command and report reads; :mod:`mpcshare.line_ratio` — tracking RMS over the voluntary–reactive line;
- :mod:`mpcshare.arms` — another arm set up for the task; :mod:`mpcshare.conflicts` — the scenarios of
  ``sim --scenario``; :mod:`mpcshare.channel_map` — channels in the roles the controller needs;
- :mod:`mpcshare.reports` — reports and plots; :mod:`mpcshare.runtime` — ``run`` on a real arm over ROS 2;
  :mod:`mpcshare.errors` — :class:`~mpcshare.errors.MpcshareError` and ``PROJECT_ERRORS``;
- :mod:`mpcshare.cli`, :mod:`mpcshare.commands` — the command line (:data:`mpcshare.cli.COMMANDS`:
  ``generate``, ``inspect``, ``analyze``, ``train``, ``sim``, ``tune``, ``demo``, ``import``, ``run``).

The MPC is :mod:`robot.mpc`'s, the learning :mod:`learning`'s, the world :mod:`sim`'s.
``python -m mpcshare`` runs the command line.
"""

__version__ = "0.1.0"

__all__ = ["load_bundle", "__version__"]


def __getattr__(name: str):
    if name == "load_bundle":
        from mpcshare.bundle import load_bundle
        return load_bundle
    raise AttributeError(f"module 'mpcshare' has no attribute {name!r}")
