"""Who leads, measured in the closed loop: the default ``gate`` against the paper's gate and the line (issue 28).

Prints one JSON object: per wearer preset, per run, the pooled figures of
:func:`mpcshare.evaluation.simulate_episode` on the held-out trials (the same trials, seed and
wearer for every run) and the **line ratio** RMS_s / RMS_line(e_s), where the line runs from
(effort_reactive, RMS_reactive) to (effort_voluntary, RMS_voluntary) and is evaluated at the run's
effort e_s (below 1: better than mixing the two parties). Runs: ``voluntary``, ``reactive``,
``paper_gate``, ``gate`` (with the bundle's settings, or each ``--variants`` setting), and
``true_mode_schedule``: the wearer leads the true cutting mode from ``--margin`` s before it begins
until ``--margin`` s after it ends (the anticipating bound of issue 28; it uses the future, not
a controller).

Usage: ``python benchmarks/bench_handover.py --bundle DIR --data NPZ [--presets ...] [--trials 2]
[--duration 30] [--variants '{"lead_s": 1.0}' ...]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

from learning.data import Demonstrations, load
from mpcshare.bundle import load_bundle
from mpcshare.calibration.rule_choice import line_ratio as _line
from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation import StrategyRun, pool_metrics, pool_task_metrics, simulate_episode
from mpcshare.evaluation.schedule import StepSchedule
from sim.demonstrator import CUTTING
from sim.task.eating import MODE_NAMES
from sim.wearer_presets import WEARER_PRESETS, wearer_preset

KEYS = ("tracking_rmse_m", "voluntary_effort", "saw_correlation", "saw_amplitude_ratio", "reactive_share",
        "handovers", "limit_violations", "step_p99_ms", "lag_s", "rms_by_mode_m", "wearer_share_by_mode")


def true_mode_schedule(trial: Any, margin_s: float) -> StepSchedule:
    """α target 0 (the wearer leads) from ``margin_s`` before each true cutting segment to ``margin_s`` after."""
    if trial.mode is None:
        raise ValueError(f"trial {trial.trial_id} has no mode labels")
    cut = np.asarray(trial.mode) == CUTTING
    dt = float(np.median(np.diff(trial.t)))
    m = int(round(margin_s / dt))
    wearer = np.convolve(cut.astype(float), np.ones(2 * m + 1), mode="same") > 0 if m else cut
    return StepSchedule(np.asarray(trial.t, dtype=float), ~wearer, 0.0)


def line_ratio(run: dict[str, float], vol: dict[str, float], rea: dict[str, float]) -> float | None:
    """RMS_s / RMS_line(e_s) (module docstring; :func:`mpcshare.calibration.rule_choice.line_ratio`)."""
    return _line(run["tracking_rmse_m"], run["voluntary_effort"], vol, rea)


def run_pooled(bundle: Any, demos: Demonstrations, trials: list[int], name: str, strategy: str,
               options: dict[str, Any] | None, preset: str, duration: float, margin: float) -> dict[str, Any]:
    """One run on every trial, pooled (``options``: the gate's settings)."""
    by_id = {tr.trial_id: tr for tr in demos.trials}
    metrics, steps, seconds = [], [], []
    for tid in trials:
        extra: dict[str, Any] = {}
        if strategy == "schedule":
            extra["schedule"] = true_mode_schedule(by_id[tid], margin)
        if options:
            extra["config"] = ControllerConfig(strategy_settings=dict(options))
        episode, m = simulate_episode(bundle, demos, by_id[tid], StrategyRun(name, strategy), extra, beta=0.5,
                                      duration_s=duration, seed=0, wearer=wearer_preset(preset),
                                      mode_names=MODE_NAMES)
        metrics.append(m)
        steps.append(np.asarray(episode.step_time, dtype=float))
        seconds.append(float(episode.t[-1] - episode.t[0]))
    pooled = {**pool_metrics(metrics, steps, seconds), **pool_task_metrics(metrics, steps)}
    return {k: pooled.get(k) for k in KEYS}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bundle", required=True)
    p.add_argument("--data", required=True)
    p.add_argument("--presets", nargs="+", default=["hemiparetic_mild"], choices=list(WEARER_PRESETS))
    p.add_argument("--trials", type=int, default=2)
    p.add_argument("--duration", type=float, default=30.0)
    p.add_argument("--margin", type=float, default=0.5)
    p.add_argument("--variants", nargs="*", default=[], help="JSON objects of gate settings, one run each")
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    bundle, demos = load_bundle(a.bundle), load(a.data)
    trials = [int(t) for t in bundle.heldout_trials[:a.trials]]
    runs: list[tuple[str, str, dict[str, Any] | None]] = [
        ("voluntary", "voluntary", None), ("reactive", "reactive", None), ("paper_gate", "paper_gate", None),
        ("gate", "gate", None), ("true_mode_schedule", "schedule", None)]
    runs += [(f"gate {v}", "gate", json.loads(v)) for v in a.variants]
    out: dict[str, Any] = {"bundle": a.bundle, "data": a.data, "trials": trials, "duration_s": a.duration,
                           "margin_s": a.margin, "presets": {}}
    for preset in a.presets:
        res = {name: run_pooled(bundle, demos, trials, name, strategy, opts, preset, a.duration, a.margin)
               for name, strategy, opts in runs}
        for r in res.values():
            r["line_ratio"] = line_ratio(r, res["voluntary"], res["reactive"])
            r["effort_vs_voluntary"] = r["voluntary_effort"] / res["voluntary"]["voluntary_effort"]
        out["presets"][preset] = res
        print(f"{preset}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    out["seconds"] = time.perf_counter() - t0
    print(json.dumps(out, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
