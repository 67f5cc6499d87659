"""Reports and plots (matplotlib, Markdown, self-contained HTML).

- :mod:`mpcshare.reports.analysis` — the analysis report (``report.json``, ``report.md``, plots);
- :mod:`mpcshare.reports.comparison` — the closed-loop comparison of strategies;
- :mod:`mpcshare.reports.demo` — the demo's summary and its one report;
- :mod:`mpcshare.reports.html` — Markdown to one self-contained HTML file;
- :mod:`mpcshare.reports.rule_choice` — the closed-loop choice of the hand-over rule, for ``training.md``;
- :mod:`mpcshare.reports.sweep` — the K trade-off's trend sentences, ``sweep.json``, ``sweep.md`` and ``sweep.png``;
- :mod:`mpcshare.reports.episode_plot` — a plotted closed-loop trial;
- :mod:`mpcshare.reports.tune` — the ``tune`` sweep's ``tune.json``, ``tune.md`` and ``pareto.png``.
"""
