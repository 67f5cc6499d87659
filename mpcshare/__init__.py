"""mpcshare: shared control of a wearable robot arm from demonstrations.

- :mod:`mpcshare.cli` — the ``mpcshare`` command line (registry :data:`mpcshare.cli.COMMANDS`);
- :mod:`mpcshare.commands` — its subcommands (``generate``, ``inspect``, ``analyze``, ``demo``);
- :mod:`mpcshare.report` — analysis reports (JSON, Markdown) and plots.

``python -m mpcshare`` runs the command line. Design: ``docs/design.md``.
"""

__version__ = "0.1.0"
