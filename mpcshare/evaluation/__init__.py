"""Experiments in the closed loop: strategies compared on held-out trials, hand-over schedules, tuning.

- :mod:`mpcshare.evaluation.runs` — one episode (:func:`simulate_episode`) and the comparison of
  strategies on held-out trials (:func:`compare_strategies`), what ``mpcshare sim`` and ``demo`` run;
- :mod:`mpcshare.evaluation.pooling` — per-trial metrics pooled into one row per strategy;
- :mod:`mpcshare.evaluation.schedule` — given hand-over schedules: the matched-random placebo and the
  oracle's dynamic programme;
- :mod:`mpcshare.evaluation.handover` — the ``random_handover`` and ``oracle_handover`` runs built
  from a comparison's own episodes;
- :mod:`mpcshare.evaluation.tuning` — ``mpcshare tune``: K × β × strategy against random hand-overs
  (episodes, runner local or Ray, statistics, report).

The names of :mod:`~mpcshare.evaluation.runs` are importable from the package itself.
"""

from mpcshare.evaluation.runs import *  # noqa: F401,F403
from mpcshare.evaluation.runs import __all__  # noqa: F401
