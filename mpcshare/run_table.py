"""The one table of runs: every registered strategy, plus the runs that are not strategies.

Built from :data:`mpcshare.control.strategies.REGISTRY`, so that a new strategy is one
module there and appears in ``mpcshare sim --runs``, the comparison's default runs, ``tune``'s
swept strategies (``tunable``), the Pareto set, the plots' colours and the benchmarks:

* one :class:`StrategyRun` per strategy a user may choose (``voluntary``, ``reactive``, the
  constant mixtures ``mix25`` … ``mix75``, ``gate``, ``paper_gate``, ``blend``, …), in the
  registry's order (:data:`ALL_RUNS`; :data:`DEFAULT_RUNS` leaves out the registered candidates whose spec says
  ``default_run=False``, e.g. ``qp_blend``: they run when named);
* :data:`EXTRA_RUNS`: ``gate_mpc`` (the default strategy with the MPC), ``oracle_preview`` (the
  robot given the true intent as its preview), ``random_handover`` (the placebo, the mean over
  :data:`RANDOM_DRAWS` draws) and ``oracle_handover`` (the upper bound), see
  :mod:`mpcshare.evaluation.handover`.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

from mpcshare.control.strategies import DEFAULT_STRATEGY, REGISTRY, user_strategies

__all__ = ["ALL_RUNS", "DEFAULT_RUNS", "EXTRA_RUNS", "RANDOM_DRAWS", "REALISABLE", "RUN_COLORS", "RUN_NAMES",
           "TUNABLE", "StrategyRun", "strategy_code"]

#: Draws of the placebo per trial (and per pair in ``tune``): its figure is their mean.
RANDOM_DRAWS = 5


@dataclass(frozen=True)
class StrategyRun:
    """One simulated configuration: a name for the tables, the arbitration strategy, MPC on/off,
    and ``oracle``: the controller is given the wearer's true intent as its preview instead of
    the predictor's forecast (an upper bound, not realisable). ``schedule``: ``"random"`` or
    ``"oracle"``: the run replays a hand-over schedule computed from the default strategy's, or
    the pure runs', episodes on the same trial (:mod:`mpcshare.evaluation.handover`), ``draws`` times."""

    name: str
    strategy: str
    use_mpc: bool = False
    oracle: bool = False
    schedule: str | None = None
    draws: int = 1


EXTRA_RUNS: tuple[StrategyRun, ...] = (
    StrategyRun(f"{DEFAULT_STRATEGY}_mpc", DEFAULT_STRATEGY, use_mpc=True),
    StrategyRun("oracle_preview", "reactive", oracle=True),
    StrategyRun("random_handover", "schedule", schedule="random", draws=RANDOM_DRAWS),
    StrategyRun("oracle_handover", "schedule", schedule="oracle"),
)
#: every run a user may name (``mpcshare sim --runs``)
ALL_RUNS: tuple[StrategyRun, ...] = tuple(StrategyRun(n, n) for n in user_strategies()) + EXTRA_RUNS
#: the runs ``sim`` and ``demo`` make unless told otherwise
DEFAULT_RUNS: tuple[StrategyRun, ...] = tuple(r for r in ALL_RUNS if r.name not in REGISTRY
                                              or REGISTRY[r.name].default_run)
RUN_NAMES: tuple[str, ...] = tuple(r.name for r in ALL_RUNS)
#: The strategies ``tune`` sweeps over K and β (each gets a matched ``random_handover``).
TUNABLE: tuple[str, ...] = tuple(n for n, s in REGISTRY.items() if s.tunable and s.user)
#: The realisable strategies (a user's choices): the Pareto set is drawn from them.
REALISABLE: tuple[str, ...] = user_strategies()
#: Plot colour per run name (strategies: the registry's; the extra runs: their own).
#: One colour per run, no near-twins among :data:`RUN_NAMES` (tests check their distance in CIELAB).
RUN_COLORS: dict[str, str] = {**{n: s.color for n, s in REGISTRY.items()},
                              f"{DEFAULT_STRATEGY}_mpc": "#0a2a6b", "oracle_preview": "#9467bd",
                              "random_handover": REGISTRY["schedule"].color, "oracle_handover": "#000000",
                              "oracle_line": "#e7298a"}


def strategy_code(name: str) -> int:
    """A stable integer per strategy name (CRC-32) for seeding its placebo draws."""
    return zlib.crc32(name.encode())
