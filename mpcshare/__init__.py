"""mpcshare: shared control of a wearable robot arm from demonstrations.

- :mod:`mpcshare.cli` — the ``mpcshare`` command line (registry :data:`mpcshare.cli.COMMANDS`);
- :mod:`mpcshare.commands` — its subcommands (``generate``, ``inspect``, ``analyze``, ``train``,
  ``sim``, ``demo``);
- :mod:`mpcshare.report` — analysis reports (JSON, Markdown) and plots.
- :mod:`mpcshare.bundle` — model bundles (:func:`load_bundle`, re-exported here lazily,
  so that ``import mpcshare`` does not import torch or scikit-learn); their JSON encodings,
  checksums and durable writes in :mod:`mpcshare.bundle_files`.
- :mod:`mpcshare.training`, :mod:`mpcshare.sweep`, :mod:`mpcshare.evaluation` — training a
  bundle, the K trade-off, held-out metrics; the settings in :mod:`mpcshare.train_config`.
- :mod:`mpcshare.streaming`, :mod:`mpcshare.arbitration`, :mod:`mpcshare.controller` — the
  online loop (:class:`~mpcshare.controller.SharedController`); :mod:`mpcshare.symbolic`,
  :mod:`mpcshare.mpc` — the CasADi model and MPC.
- :mod:`mpcshare.experiments`, :mod:`mpcshare.comparison_report`, :mod:`mpcshare.demo_report`,
  :mod:`mpcshare.html_report`, :mod:`mpcshare.episode_plot` — closed-loop comparisons and reports.

``python -m mpcshare`` runs the command line. Design: ``docs/design.md``.
"""

__version__ = "0.1.0"

__all__ = ["load_bundle", "__version__"]


def __getattr__(name: str):
    if name == "load_bundle":
        from mpcshare.bundle import load_bundle
        return load_bundle
    raise AttributeError(f"module 'mpcshare' has no attribute {name!r}")
