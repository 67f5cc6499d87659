"""mpcshare: shared control of a wearable robot arm from demonstrations.

- :mod:`mpcshare.cli` — the ``mpcshare`` command line (registry :data:`mpcshare.cli.COMMANDS`);
- :mod:`mpcshare.commands` — its subcommands (``generate``, ``inspect``, ``analyze``, ``train``,
  ``sim``, ``demo``);
- :mod:`mpcshare.reports.analysis` — analysis reports (JSON, Markdown) and plots.
- :mod:`mpcshare.bundle` — model bundles (:func:`load_bundle`, re-exported here lazily,
  so that ``import mpcshare`` does not import torch or scikit-learn); their JSON encodings,
  checksums and durable writes in :mod:`mpcshare.bundle.files`.
- :mod:`mpcshare.training`, :mod:`mpcshare.training.sweep`, :mod:`mpcshare.training.evaluation` — training a
  bundle, the K trade-off, held-out metrics; the settings in :mod:`mpcshare.training.config`.
- :mod:`mpcshare.control.frontend`, :mod:`mpcshare.control.arbitration`, :mod:`mpcshare.control.controller` — the
  online loop (:class:`~mpcshare.control.controller.SharedController`); :mod:`robot.mpc.symbolic`,
  :mod:`robot.mpc.tip_mpc` — the CasADi model and MPC.
- :mod:`mpcshare.experiments`, :mod:`mpcshare.reports.comparison`, :mod:`mpcshare.reports.demo`,
  :mod:`mpcshare.reports.html`, :mod:`mpcshare.reports.episode_plot` — closed-loop comparisons and reports.

``python -m mpcshare`` runs the command line. Design: ``docs/design.md``.
"""

__version__ = "0.1.0"

__all__ = ["load_bundle", "__version__"]


def __getattr__(name: str):
    if name == "load_bundle":
        from mpcshare.bundle import load_bundle
        return load_bundle
    raise AttributeError(f"module 'mpcshare' has no attribute {name!r}")
