"""mpcshare: shared control of a wearable robot arm from demonstrations.

- :mod:`mpcshare.cli` — the core subcommands of the ``mpcshare`` command line.
- :mod:`mpcshare.report` — analysis reports (JSON, Markdown) and plots.
"""

__version__ = "0.1.0"
