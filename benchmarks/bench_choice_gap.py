"""How well the closed-loop rule choice predicts its rule: predicted against realised line ratio per world.

Per world (``family:<seed>`` of :mod:`sim.world_family` or a data kind of ``benchmarks/bench_task.py``, via
``benchmarks/worlds.py``): train a bundle (``--quick``: at most 20 LSTM epochs, the quick world sizes), choose
the gate's rule as ``mpcshare train`` does (:func:`mpcshare.calibration.rule_choice.choose_for_bundle`, 60 s a
trial or longer where one shows less than 3 s of the stroke; ``--no-stroke-window``: 60 s whatever they show;
``--choice-trials``), then simulate ``voluntary``, ``reactive`` and ``gate`` on the other held-out trials
(``--quick``: the first 30 s of 2). Prints one JSON line per world: the choice's predicted line ratio (and left
one trial out), the realised one, the gap realised − predicted, the gate's and the wearer alone's figures per
evaluation trial (RMS, effort, stroke correlation), the choice's seconds a trial, the episodes it simulated and its
CPU seconds, and the rule the criterion would have chosen on the pooled sawing figures (``pooled_sawing_choice``:
the criterion before sawing was required per cutting episode; its realised line ratio where it differs).

Usage: ``python benchmarks/bench_choice_gap.py [--worlds family:0 family:1 default] [--quick]
[--choice-trials N] [--trial-order] [--no-stroke-window]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from worlds import world_data  # noqa: E402


def _pooled_sawing_choice(choice: dict[str, Any]) -> dict[str, Any]:
    """The row the criterion chooses when only the pooled sawing figures are known (no ``saws_by_trial``)."""
    from mpcshare.calibration.choice_criterion import criterion

    strip = [{k: v for k, v in r.items() if k != "saws_by_trial"} for r in choice["candidates"]]
    vol = {k: v for k, v in choice["voluntary"].items() if k != "saws_by_trial"}
    best, _ = criterion(strip, vol, choice["reactive"], choice["max_effort"])
    return choice["candidates"][strip.index(best)]


def run_world(world: str, quick: bool, choice_trials: int | None, by_subject: bool = True,
              stroke_window: bool = True) -> dict[str, Any]:
    """Train, choose, evaluate (module docstring); the world's JSON row."""
    import torch

    torch.set_num_threads(1)
    from mpcshare.calibration.rule_choice import choose_for_bundle
    from mpcshare.calibration.trials import unseen_trials
    from mpcshare.evaluation import compare_strategies
    from mpcshare.run_table import StrategyRun
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig

    demos, mode_names, _ = world_data(world, quick)
    bundle = train_bundle(demos, TrainConfig(max_epochs=20) if quick else TrainConfig(), progress=False)
    c0 = time.process_time()
    choice = choose_for_bundle(bundle, demos, n_trials=choice_trials, mode_names=mode_names, log=None, workers=1,
                               by_subject=by_subject, **({} if stroke_window else {"stroke_seen_s": None}))
    choice_cpu = time.process_time() - c0
    rest = unseen_trials(bundle.heldout_trials, choice["trials"])
    trials = list(rest[:2] if quick else rest)
    runs = [StrategyRun(s, s) for s in ("voluntary", "reactive", "gate")]
    span = 30.0 if quick else None
    comp = compare_strategies(bundle, demos, trials, runs=runs, duration_s=span, log=None, mode_names=mode_names)
    old = _pooled_sawing_choice(choice)
    differs = old["settings"] != choice["settings"]
    old_realised = None
    if differs:  # the pooled-sawing rule evaluated on the same trials, its own settings given
        from mpcshare.control.types import ControllerConfig
        from mpcshare.line_ratio import line_ratio

        m = compare_strategies(bundle, demos, trials, runs=runs[2:], duration_s=span, log=None, mode_names=mode_names,
                               controller_options={"config": ControllerConfig(strategy_settings=dict(old["settings"]))}
                               ).strategies["gate"]
        vol, rea = comp.strategies["voluntary"], comp.strategies["reactive"]
        old_realised = line_ratio(m["tracking_rmse_m"], m["voluntary_effort"],
                                  (vol["voluntary_effort"], vol["tracking_rmse_m"]),
                                  (rea["voluntary_effort"], rea["tracking_rmse_m"]))
    check = comp.rule_check or {}
    return {"world": world, "choice_trials": choice["trials"], "eval_trials": trials,
            "wearer_modes": choice["wearer_modes"], "predicted": choice["predicted"],
            "cross_validated": choice.get("cross_validated"), "realised": check.get("realised"),
            "gap": check.get("line_ratio_gap"), "episodes_run": choice["episodes_run"], "choice_cpu_s": choice_cpu,
            "choice_duration_s": choice["duration_s"],
            "realised_by_trial": {str(t): {k: comp.per_trial["gate"][str(t)].get(k) for k in
                                           ("tracking_rmse_m", "voluntary_effort", "saw_correlation",
                                            "saw_amplitude_ratio")} for t in trials},
            "voluntary_by_trial": {str(t): {k: comp.per_trial["voluntary"][str(t)].get(k) for k in
                                            ("tracking_rmse_m", "voluntary_effort", "saw_correlation")}
                                   for t in trials},
            "mixes": [{k: m[k] for k in ("strategy", "line_ratio", "effort_vs_voluntary")} for m in choice["mixes"]],
            "pooled_sawing_choice": {"same": not differs, "line_ratio_predicted": old["line_ratio"],
                                     "line_ratio_realised": old_realised if differs
                                     else (check.get("realised") or {}).get("line_ratio")}}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--worlds", nargs="+", default=["default", "family:0", "family:1"])
    p.add_argument("--quick", action="store_true", help="quick world sizes, at most 20 epochs, 2 trials x 30 s")
    p.add_argument("--choice-trials", type=int, default=None, help="held-out trials the choice runs on")
    p.add_argument("--trial-order", action="store_true",
                   help="the choice on the last held-out trials (before 2026-12-01), not dealt round the subjects")
    p.add_argument("--no-stroke-window", action="store_true",
                   help="the choice on the first 60 s of each trial whatever they show of the stroke (before "
                        "2026-12-02), not longer where a trial shows less than 3 s of it")
    a = p.parse_args(argv)
    for world in a.worlds:
        print(json.dumps(run_world(world, a.quick, a.choice_trials, not a.trial_order, not a.no_stroke_window),
                         default=float), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
