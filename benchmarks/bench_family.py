"""Shared control on many worlds: the randomised family and the project's data kinds (issue 28).

For each world — ``family:<seed>`` (:mod:`sim.world_family`) and the data kinds of
``benchmarks/bench_task.py`` (``default``, ``other_seed``, ``other_structure``) — train a bundle
with the defaults a user gets (:class:`mpcshare.training.config.TrainConfig`; ``--quick``: at most
20 LSTM epochs), then simulate on its held-out *whole* trials (``--quick``: the first 30 s of 2)
with the default wearer (``--wearer``: another preset of :mod:`sim.wearer_presets`, for the choice and every
run), for each of ``--seeds`` sim seeds: ``voluntary``, ``reactive``, the
constant mixtures ``mix25``/``mix50``/``mix75``, ``paper_gate``, ``gate``, ``blend``,
``random_handover`` (matched to ``gate``, mean of 5 draws) and ``oracle_handover`` (best replay,
an upper bound); with ``--oracle-line`` also ``oracle_line`` (the effort-aware hand-over oracle: the lowest
line ratio a schedule that knows the future reaches within 0.75x the wearer's effort, replayed).
Per world it prints one JSON line (``"world"``): per run the tracking RMS [mm], the effort [rad], the line ratio
(:mod:`mpcshare.line_ratio`), the stroke-band correlation while cutting (pooled, and per cutting episode with the
number that sawed), the robot's share, the limit violations, the knife's lag behind the intent [s] (negative:
ahead) and its least clearance to a body zone [mm]; ``best_mix`` (the constant α with the lowest line ratio);
one-sided paired Wilcoxon p-values over (trial, seed) pairs of ``gate`` against ``random_handover``, ``paper_gate``
and the best mixture; and what the oracle guarantees. At the
end one JSON object: every world, and the distribution over the family's worlds and over all
(median, min, max, share ≤ 0.9 and ≤ 0.8 of the line ratios; effort against ``voluntary``).

Worlds run in parallel processes (``--workers``; each single-threaded). Sizes: family worlds
16 trials × 60 s (``--quick``: 12 × 40 s), 25 % of the trials held out (the default split); the
gate's rule is chosen in the closed loop on the last held-out trials (as ``mpcshare train``) and
every run is evaluated on the other held-out trials.

Cost: per world and seed about 17 episodes per held-out trial (the placebo's 5 draws, the
oracle's up to 4 replays); the full default (13 worlds, 3 whole trials of 60 s, 4 seeds) is hours
of CPU, ``--quick`` (3 family worlds, 2 trials × 30 s, 1 seed) about 35 min on 2 busy cores.

Usage: ``python benchmarks/bench_family.py [--worlds 0 1 2 ...] [--kinds default other_seed
other_structure] [--workers 2] [--seeds 4] [--quick] [--wearer PRESET]``; ``--worlds`` with no value and
``--kinds`` with no value leave that part out.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats as st

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from worlds import world_data  # noqa: E402

from sim.wearer_presets import DEFAULT_WEARER_PRESET, WEARER_PRESETS  # noqa: E402

MIXES = ("mix25", "mix50", "mix75")
RUNS = ("voluntary", "reactive", *MIXES, "paper_gate", "gate", "blend", "random_handover", "oracle_handover")
FIGURES = {"tracking_rmse_m": ("rms_mm", 1e3), "voluntary_effort": ("effort_rad", 1.0),
           "line_ratio": ("line_ratio", 1.0), "saw_correlation": ("stroke_correlation", 1.0),
           "reactive_share": ("robot_share", 1.0), "limit_violations": ("limit_violations", 1),
           "pickup_rms_m": ("pickup_rms_mm", 1e3), "pickup_error_share": ("pickup_error_share", 1.0),
           "lag_s": ("lag_s", 1.0), "keepout_min_clearance_m": ("clearance_mm", 1e3)}


def _one_sided(a: list[float], b: list[float]) -> dict[str, Any]:
    """Wilcoxon signed-rank of H1: a < b, paired (exact for small n); p None without a differing pair."""
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    p = float(st.wilcoxon(d, alternative="greater").pvalue) if d.size and np.any(d != 0) else None
    return {"p": p, "n_pairs": int(d.size), "mean_difference_mm": float(1e3 * d.mean()) if d.size else None}


def _candidates_on_eval(bundle: Any, demos: Any, trials: list[int], choice: dict[str, Any],
                        pooled: dict[str, dict[str, Any]], mode_names: Any, quick: bool,
                        wearer: Any = None) -> list[dict[str, Any]]:
    """Every candidate of the rule's choice run on the *evaluation* trials (sim seed 0): which wearer-mode
    set would have been best had the choice known the future (an upper bound on the choice, not a rule)."""
    from mpcshare.calibration.rule_choice import line_ratio, pooled_run, saws

    vol, rea = pooled["voluntary"], pooled["reactive"]
    rows = []
    for c in choice["candidates"]:
        m, _ = pooled_run(bundle, demos, trials, "gate", c["settings"], 30.0 if quick else None, wearer, 0,
                          mode_names)
        rows.append({"wearer_modes": c["wearer_modes"], "timing": c.get("timing"),
                     "wearer_alpha": c.get("wearer_alpha", 0.0),
                     "rms_mm": 1e3 * m["tracking_rmse_m"],
                     "effort_vs_voluntary": m["voluntary_effort"] / vol["voluntary_effort"],
                     "line_ratio": line_ratio(m["tracking_rmse_m"], m["voluntary_effort"], vol, rea),
                     "saws": saws(m), "chosen": c["settings"] == choice["settings"]})
    return rows


def _by_episode(row: dict[str, Any]) -> dict[str, Any]:
    """A run's stroke correlation per cutting episode (seed 0, the trials in order) and how many sawed."""
    from sim.task import EATING

    episodes = [e for e in row.get("saw_by_episode") or () if e.get("saw_correlation") is not None]
    return {"stroke_correlation_by_episode": [round(e["saw_correlation"], 3) for e in episodes],
            "episodes_sawn": [sum(bool(EATING.done(e)) for e in episodes), len(episodes)]}


def run_world(world: str, quick: bool, seeds: int, all_candidates: bool = False,
              oracle_line: bool = False, wearer: str | None = None) -> dict[str, Any]:
    """Train on the world, simulate every run on its held-out trials, summarise (module docstring); ``wearer``:
    the simulated wearer's preset of the rule's choice and of every run (None: the default preset)."""
    import torch

    torch.set_num_threads(1)
    from mpcshare.calibration.rule_choice import choose_for_bundle
    from mpcshare.calibration.trials import unseen_trials
    from mpcshare.evaluation import compare_strategies
    from mpcshare.run_table import DEFAULT_RUNS
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig
    from research.bound_runs import BOUND_RUNS
    from sim.wearer_presets import DEFAULT_WEARER_PRESET, wearer_preset

    wearer = wearer or DEFAULT_WEARER_PRESET
    t0 = time.perf_counter()
    demos, mode_names, info = world_data(world, quick)
    bundle = train_bundle(demos, TrainConfig(max_epochs=20) if quick else TrainConfig(), progress=False)
    # the gate's rule chosen in the closed loop as `mpcshare train` does, on the last held-out trials;
    # the runs below are evaluated on the other held-out trials only
    choice = choose_for_bundle(bundle, demos, mode_names=mode_names, log=None,  # as `mpcshare train`: 60 s a trial
                               workers=1, wearer_name=wearer)  # one process per world: the worlds run in parallel
    info["rule_choice"] = {k: choice[k] for k in ("wearer_modes", "settings", "why", "trials", "mode_costs",
                                                  "price_order", "cutting_modes", "seconds")}
    t_train = time.perf_counter() - t0
    rest = unseen_trials(bundle.heldout_trials, choice["trials"])
    trials = list(rest[:2] if quick else rest)
    names = RUNS + (("oracle_line",) if oracle_line else ())
    runs = [r for r in DEFAULT_RUNS + BOUND_RUNS if r.name in names]
    per_pair: dict[str, list[float]] = {r: [] for r in names}
    pooled: dict[str, dict[str, Any]] = {}
    for seed in range(seeds):
        comp = compare_strategies(bundle, demos, trials, runs=runs, duration_s=30.0 if quick else None, seed=seed,
                                  log=None, mode_names=mode_names, wearer=wearer_preset(wearer))
        for name in names:
            per_pair[name] += [comp.per_trial[name][str(t)]["tracking_rmse_m"] for t in trials]
        if seed == 0:
            pooled = comp.strategies
    out = {name: {k2: (None if pooled[name].get(k) is None else pooled[name][k] * s) for k, (k2, s) in FIGURES.items()}
           | _by_episode(pooled[name]) for name in names}
    best_mix = min(MIXES, key=lambda m: (pooled[m]["line_ratio"] is None, pooled[m]["line_ratio"] or 0.0,
                                         pooled[m]["tracking_rmse_m"]))
    better = min(pooled["voluntary"]["tracking_rmse_m"], pooled["reactive"]["tracking_rmse_m"])
    return {"world": world, "wearer": wearer, "data": info, "trials": trials, "seeds": seeds, "quick": quick,
            "runs": out,
            "best_mix": best_mix, "p_values": {
                "gate_below_random_handover": _one_sided(per_pair["gate"], per_pair["random_handover"]),
                "gate_below_paper_gate": _one_sided(per_pair["gate"], per_pair["paper_gate"]),
                "gate_below_best_mix": _one_sided(per_pair["gate"], per_pair[best_mix])},
            "oracle_over_better_party": pooled["oracle_handover"]["tracking_rmse_m"] / better,
            "gate_effort_over_voluntary": pooled["gate"]["voluntary_effort"] / pooled["voluntary"]["voluntary_effort"],
            "candidates_on_eval": _candidates_on_eval(bundle, demos, trials, choice, pooled, mode_names, quick,
                                                      wearer_preset(wearer))
            if all_candidates else None,
            "train_s": t_train, "seconds": time.perf_counter() - t0,
            "figures_of": "seed 0 pooled over the trials; p-values over (trial, seed) pairs"}


def distribution(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Median, min, max and the shares ≤ 0.9 and ≤ 0.8 of the line ratios over ``results``."""
    out: dict[str, Any] = {"n_worlds": len(results)}
    for name in ("gate", "paper_gate", "blend", "best_mix", "random_handover", "oracle_handover", "oracle_line"):
        key = lambda r: r["best_mix"] if name == "best_mix" else name  # noqa: E731
        v = np.array([r["runs"][key(r)]["line_ratio"] for r in results
                      if key(r) in r["runs"] and r["runs"][key(r)]["line_ratio"] is not None])
        if v.size:
            out[f"{name}_line_ratio"] = {"median": float(np.median(v)), "min": float(v.min()),
                                         "max": float(v.max()), "share_le_0.9": float(np.mean(v <= 0.9)),
                                         "share_le_0.8": float(np.mean(v <= 0.8))}
    e = np.array([r["gate_effort_over_voluntary"] for r in results])
    o = np.array([r["oracle_over_better_party"] for r in results])
    if e.size:
        out["gate_effort_over_voluntary"] = {"median": float(np.median(e)), "max": float(e.max())}
        out["oracle_over_better_party_max"] = float(o.max())
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--worlds", type=int, nargs="*", default=None, help="family seeds (default 0..9; quick 0..2)")
    p.add_argument("--kinds", nargs="*", default=["default", "other_seed", "other_structure"],
                   choices=["default", "other_seed", "other_structure"])
    p.add_argument("--workers", type=int, default=2, help="worlds in parallel processes (default 2)")
    p.add_argument("--seeds", type=int, default=None,
                   help="sim seeds per trial, pairs = held-out trials x seeds (default 4: 3 x 4 = 12 pairs, so that "
                        "p < 0.01 is reachable; --quick 1)")
    p.add_argument("--quick", action="store_true", help="smaller worlds, at most 20 epochs, 2 trials x 30 s")
    p.add_argument("--wearer", choices=list(WEARER_PRESETS), default=DEFAULT_WEARER_PRESET,
                   help=f"the simulated wearer's preset, of the rule's choice and of every run (default "
                        f"{DEFAULT_WEARER_PRESET})")
    p.add_argument("--out", help="also write the final JSON object to this file")
    p.add_argument("--all-candidates", action="store_true",
                   help="also run every candidate of the rule's choice on the evaluation trials (the best set in "
                        "hindsight: an upper bound on the choice)")
    p.add_argument("--oracle-line", action="store_true",
                   help="also run oracle_line, the effort-aware hand-over oracle (6 replays a trial)")
    a = p.parse_args(argv)
    a.seeds = a.seeds if a.seeds is not None else (1 if a.quick else 4)
    seeds = list(range(3 if a.quick else 10)) if a.worlds is None else a.worlds
    worlds = [f"family:{s}" for s in seeds] + list(a.kinds)
    t0 = time.perf_counter()
    results = []
    ctx = multiprocessing.get_context("spawn")  # torch and fork do not mix
    with ProcessPoolExecutor(max_workers=max(1, a.workers), mp_context=ctx) as pool:
        futures = {pool.submit(run_world, w, a.quick, a.seeds, a.all_candidates, a.oracle_line, a.wearer): w
                   for w in worlds}
        for fut in as_completed(futures):
            r = fut.result()
            results.append(r)
            print(json.dumps(r, default=float), flush=True)
    results.sort(key=lambda r: worlds.index(r["world"]))
    family = [r for r in results if r["world"].startswith("family:")]
    final = {"worlds": results, "distribution": {"family": distribution(family), "all": distribution(results)},
             "settings": {"quick": a.quick, "seeds": a.seeds, "workers": a.workers, "wearer": a.wearer,
                          "train": "TrainConfig() defaults" + (", max_epochs 20" if a.quick else ""),
                          "sim": "2 held-out trials x 30 s" if a.quick else "every held-out trial, whole"},
             "seconds": time.perf_counter() - t0}
    text = json.dumps(final, indent=1, default=float)
    if a.out:
        Path(a.out).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
