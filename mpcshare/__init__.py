"""mpcshare: shared control of a wearable robot arm from demonstrations.

- :mod:`mpcshare.control` — the online loop: :class:`~mpcshare.control.SharedController`, its
  output :class:`~mpcshare.control.ControlCommand`, the streaming front end, arbitration, frames;
- :mod:`mpcshare.bundle` — model bundles (:func:`load_bundle`, re-exported here lazily, so that
  ``import mpcshare`` does not import torch or scikit-learn) and their files;
- :mod:`mpcshare.training` — training a bundle, its settings, held-out evaluation, the K sweep;
- :mod:`mpcshare.calibration` — after training: the hand-over rule chosen in the closed loop;
- :mod:`mpcshare.reports` — the analysis, comparison and demo reports and their plots;
- :mod:`mpcshare.evaluation` — every closed-loop experiment in one package: the comparison of
  strategies on held-out trials (``runs``), their metrics pooled over trials (``pooling``), the
  placebo and oracle hand-over schedules (``schedule``, ``handover``) and the ``tune`` sweep of
  K × β × strategy, local or on Ray (``tuning``); :mod:`mpcshare.run_table` — the runs
  (the strategy registry's and the extra ones) every command and report reads; :mod:`mpcshare.line_ratio`
  — the tracking RMS over the straight voluntary–reactive line; :mod:`mpcshare.arms` — another arm (a preset or a
  file) set up for the task, its speed and acceleration caps chosen; :mod:`mpcshare.conflicts` — the conflict
  scenarios of ``sim --scenario`` (a command into the hand, a hand sweep, …); :mod:`mpcshare.channel_map`
  — which channels play the roles the controller and the simulator need (``--map NAME=CHANNEL``);
- :mod:`mpcshare.runtime` — ``run``: the shared controller on a real arm over ROS 2 topics (DDS),
  its configuration and watchdogs;
- :mod:`mpcshare.errors` — :class:`~mpcshare.errors.MpcshareError` and ``PROJECT_ERRORS``, the
  roots of every error the project raises;
- :mod:`mpcshare.cli` and :mod:`mpcshare.commands` — the ``mpcshare`` command line (registry
  :data:`mpcshare.cli.COMMANDS`; subcommands ``generate``, ``inspect``, ``analyze``, ``train``,
  ``sim``, ``tune``, ``demo``, ``import``, ``run``).

The MPC is the robot's (:mod:`robot.mpc`), the learning is :mod:`learning`'s and the world is
:mod:`sim`'s. ``python -m mpcshare`` runs the command line. Design: ``docs/design.md``.
"""

__version__ = "0.1.0"

__all__ = ["load_bundle", "__version__"]


def __getattr__(name: str):
    if name == "load_bundle":
        from mpcshare.bundle import load_bundle
        return load_bundle
    raise AttributeError(f"module 'mpcshare' has no attribute {name!r}")
