"""The closed-loop sweep ``mpcshare tune``: K × β × strategy against matched random hand-overs.

- :mod:`mpcshare.evaluation.tuning.episodes` — the episodes of a sweep and one episode in any process;
- :mod:`mpcshare.evaluation.tuning.runner` — bundles per K, the local pool or Ray, resumable rows;
- :mod:`mpcshare.evaluation.tuning.stats` — summaries with bootstrap CIs, the gate against chance, Pareto set;

its files (``tune.json``, ``tune.md``, ``pareto.png``) are written by :mod:`mpcshare.reports.tune`.
"""
