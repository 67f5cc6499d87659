"""A rule learned from the switch-priced oracle, in the closed loop on family worlds (prints JSON).

Per world (``family:<seed>``, quick-sized: 12 trials × 40 s, a bundle trained with the defaults at most 20
LSTM epochs, cached as ``bench_coming_error.py`` caches it; ``gate``'s rule chosen in the closed loop as
``mpcshare train`` does, on the last held-out trials):

* fit trials: ``--fit`` further trials of the world that neither training nor the evaluation sees. On them
  the constant levels run, the switch-priced search (:mod:`research.learned_rule.teacher`) finds the
  teacher's schedule in ``--rounds`` replayed rounds, and the rule (:mod:`research.learned_rule.fit`) is
  fitted on the features logged along the teacher's replay (behaviour cloning); each of ``--dagger`` rounds
  then runs the rule on the fit trials, labels the steps it visited with the teacher's level at that time,
  and refits on everything gathered. The iterate with the best figure on the fit trials (its replay there)
  is the choice; that figure is its *predicted* line ratio.
* evaluation trials: the held-out trials the gate's choice does not use (the first 30 s of 2, as
  ``bench_family.py --quick``). On them: ``voluntary``, ``reactive``, ``mix25``/``mix50``/``mix75``,
  ``paper_gate``, ``gate``, every learned iterate, ``random_handover`` matched to the chosen iterate (mean of
  ``--draws`` draws) and the priced oracle (the same search on these trials, knowing their future, best replay).

Per world one JSON line: per run RMS [mm], effort, line ratio, effort × the wearer's, stroke correlation
(mean and least over trials), lag, least clearance, time in a body zone, limit violations, robot share; the
teacher's rounds; the chosen iterate; its share of the oracle's gain (1 − line) / (1 − the oracle's line).
Then one summary object. ``--markdown`` prints the per-world table instead of the summary.

Cost: about 70 closed-loop episodes of 30 s a world (≈ 5 min of one core). Usage:
``python benchmarks/bench_learned_rule.py [--worlds 0 1 2] [--workers 2] [--fit 4] [--rounds 2] [--dagger 2]
[--draws 5] [--seconds 30] [--out DIR] [--markdown]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # research/ is not installed

CACHE = Path("/tmp/coming-error")  # bundles and gate choices of bench_coming_error.py, read if present
CONSTANT = ("voluntary", "reactive", "mix25", "mix50", "mix75", "paper_gate", "gate")
DRAWS = 5


def _bundle_and_choice(world: str, root: Path, demos: Any, mode_names: Any) -> tuple[Any, dict[str, Any]]:
    """The world's bundle and gate choice: from the cache where there, else trained / chosen and saved in root."""
    from mpcshare.bundle import is_bundle, load_bundle
    from research.coming_error.record import world_bundle, world_dir

    cached = world_dir(world, CACHE)
    bundle = load_bundle(cached / "bundle") if is_bundle(cached / "bundle") else world_bundle(world, demos, True, root)
    for folder in (cached, world_dir(world, root)):
        if (folder / "choice.json").exists():
            choice = json.loads((folder / "choice.json").read_text())
            break
    else:
        from mpcshare.calibration.rule_choice import choose_for_bundle

        full = choose_for_bundle(bundle, demos, mode_names=mode_names, log=None, workers=1)
        choice = {k: full[k] for k in ("settings", "trials", "wearer_modes")}
        world_dir(world, root).mkdir(parents=True, exist_ok=True)
        (world_dir(world, root) / "choice.json").write_text(json.dumps(choice, default=float))
    from mpcshare.bundle.rule import CalibratedRule

    bundle.rule = CalibratedRule("gate", choice["settings"], choice)  # what the controller reads (not the metrics)
    return bundle, choice


def _learner_runs(w: Any, trials: list[int], rule: Any) -> tuple[list[tuple[Any, dict[str, Any]]], list[Any]]:
    """The rule on ``trials``: (episode, metrics) and the policy's log per trial."""
    from research.learned_rule.policy import ImitationPolicy, controller_with

    done, logs = [], []
    for tid in trials:
        log: list[Any] = []
        done.append(w.run(tid, "mix50", make_controller=controller_with("mix50", lambda _p, log=log: ImitationPolicy(
            rule, log=log)), name="learned"))
        logs.append(log)
    return done, logs


def run_world(world: str, n_fit: int, rounds: int, dagger: int, root: Path, seconds: float = 30.0,
              draws: int = DRAWS) -> dict[str, Any]:
    """The module docstring's figures for one world."""
    import torch
    from scipy import stats as st

    torch.set_num_threads(1)
    from mpcshare.calibration.trials import unseen_trials
    from mpcshare.evaluation.handover import random_schedules_from, schedule_record
    from research.coming_error.record import world_data
    from research.learned_rule.fit import fit_rule
    from research.learned_rule.policy import log_arrays
    from research.learned_rule.teacher import (
        LEVELS,
        World,
        objective,
        pooled,
        priced_teacher,
        step_figures,
        teacher_labels,
    )

    t0 = time.perf_counter()
    say = lambda s: print(f"{world}: {s}", file=sys.stderr, flush=True)  # noqa: E731
    demos, mode_names, extra = world_data(world, True, n_fit)
    bundle, choice = _bundle_and_choice(world, root, demos, mode_names)
    w = World(bundle, demos, {t.trial_id: t for t in list(demos.trials) + extra}, tuple(mode_names), seconds)
    fit_trials = [t.trial_id for t in extra]
    eval_trials = unseen_trials(bundle.heldout_trials, choice["trials"])[:2]
    K = bundle.n_modes

    # the teacher on the fit trials
    fit_runs = {s: [w.run(t, s) for t in fit_trials] for s in LEVELS}
    ctx = step_figures(w, fit_trials, fit_runs)
    teacher = priced_teacher(w, ctx, rounds, say)
    if teacher["best"] is None:
        return {"world": world, "error": "the priced search found no schedule on the fit trials"}
    best = teacher["best"]
    X, y = [best["replay"]["X"]], [best["replay"]["target"]]
    iterates, rule = [], fit_rule(X[0], y[0], K)
    for d in range(dagger + 1):
        done, logs = _learner_runs(w, fit_trials, rule)
        figs = pooled(done, ctx["vol"], ctx["rea"])
        labels = teacher_labels(ctx, best["alpha"], [np.asarray(ep.t) for ep, _ in done])
        xs = np.concatenate([log_arrays(lg, np.asarray(ep.t)[:k])[0] for lg, (ep, _), k in zip(logs, done, ctx["n"])])
        agree = float(np.mean(np.concatenate([log_arrays(lg, np.asarray(ep.t)[:k])[1] for lg, (ep, _), k in
                                              zip(logs, done, ctx["n"])]) == labels))
        iterates.append({"rule": rule, "fit_figures": figs, "agreement_with_teacher": agree})
        say(f"iterate {d} on fit trials: line {figs['line_ratio']}, effort {figs['effort_vs_voluntary']:.2f}, "
            f"saw {figs['stroke_correlation']}, agreement {agree:.2f}")
        if d < dagger:
            X.append(xs)
            y.append(labels)
            rule = fit_rule(np.concatenate(X), np.concatenate(y), K)
    chosen = min(range(len(iterates)), key=lambda i: objective(iterates[i]["fit_figures"]))

    # the evaluation trials
    runs = {s: [w.run(t, s) for t in eval_trials] for s in CONSTANT}
    vol = (pooled(runs["voluntary"])["effort"], pooled(runs["voluntary"])["rms_mm"] / 1e3)
    rea = (pooled(runs["reactive"])["effort"], pooled(runs["reactive"])["rms_mm"] / 1e3)
    out = {s: pooled(runs[s], vol, rea) for s in CONSTANT}
    for i, it in enumerate(iterates):
        done, _ = _learner_runs(w, eval_trials, it["rule"])
        out[f"learned_{i}"] = pooled(done, vol, rea)
        if i == chosen:
            runs["learned"] = done
    rand = [[w.run(t, "schedule", {"schedule": s}, name="random_handover")
             for s in random_schedules_from(schedule_record(ep), draws, [0, j])]
            for j, (t, (ep, _)) in enumerate(zip(eval_trials, runs["learned"]))]
    drawn = [pooled([rand[j][k] for j in range(len(eval_trials))], vol, rea) for k in range(draws)]
    out["random_handover"] = {k: float(np.mean([d[k] for d in drawn])) for k in ("rms_mm", "effort", "line_ratio",
                                                                                 "effort_vs_voluntary")}
    rand_rms = np.mean([d["per_trial_rms_m"] for d in drawn], axis=0)
    ctx_eval = step_figures(w, eval_trials, {s: runs[s] for s in LEVELS})
    oracle = priced_teacher(w, ctx_eval, rounds, say)
    if oracle["best"] is not None:
        out["priced_oracle"] = {k: v for k, v in oracle["best"]["replay"]["figures"].items()}
    learned, lo = out[f"learned_{chosen}"], out.get("priced_oracle", {}).get("line_ratio")
    diff = rand_rms - np.array(learned["per_trial_rms_m"])
    res = {"world": world, "fit_trials": fit_trials, "eval_trials": eval_trials, "gate_choice": choice["settings"],
           "teacher_rounds": teacher["rounds"], "oracle_rounds": oracle["rounds"],
           "iterates": [{"fit_line_ratio": it["fit_figures"]["line_ratio"],
                         "fit_effort_vs_voluntary": it["fit_figures"]["effort_vs_voluntary"],
                         "fit_stroke_correlation": it["fit_figures"]["stroke_correlation"],
                         "agreement_with_teacher": it["agreement_with_teacher"],
                         "rule": it["rule"].to_json()} for it in iterates],
           "chosen_iterate": chosen, "predicted_line_ratio": iterates[chosen]["fit_figures"]["line_ratio"],
           "runs": out, "learned_over_random": learned["rms_mm"] / out["random_handover"]["rms_mm"],
           "learned_below_random_p": float(st.wilcoxon(diff, alternative="greater").pvalue) if np.any(diff != 0)
           else None, "pairs": int(diff.size),
           "oracle_gain_captured": None if lo is None or learned["line_ratio"] is None or lo >= 1
           else (1 - learned["line_ratio"]) / (1 - lo), "seconds": time.perf_counter() - t0}
    (root / "results").mkdir(parents=True, exist_ok=True)
    (root / "results" / f"{world.replace(':', '_')}.json").write_text(json.dumps(res, default=float))
    return res


def _f(x: Any, fmt: str = ".2f") -> str:
    return "–" if x is None else format(x, fmt)


def markdown(results: list[dict[str, Any]]) -> str:
    """Per world: line ratio (effort × wearer) of each run, the learned rule's stroke correlation, its
    ratio to matched random, its predicted line ratio and its share of the oracle's gain."""
    names = ("gate", "paper_gate", "mix25", "mix50", "mix75", "learned", "random_handover", "priced_oracle")
    rows = ["| world | " + " | ".join(names) + " | learned: stroke corr. (least) | vs random | predicted | gain "
            "captured |", "|" + "---|" * (len(names) + 5)]
    for r in results:
        if "runs" not in r:
            continue
        runs = {**r["runs"], "learned": r["runs"][f"learned_{r['chosen_iterate']}"]}
        cells = [f"{_f(runs[n].get('line_ratio'))} ({_f(runs[n].get('effort_vs_voluntary'))})" if n in runs else "–"
                 for n in names]
        lr = runs["learned"]
        rows.append(f"| {r['world']} | " + " | ".join(cells) + f" | {_f(lr['stroke_correlation'])} "
                    f"({_f(lr['stroke_correlation_min'])}) | {_f(r['learned_over_random'])} | "
                    f"{_f(r['predicted_line_ratio'])} | {_f(r['oracle_gain_captured'])} |")
    return "\n".join(rows)


def summary(results: list[dict[str, Any]]) -> dict[str, Any]:
    """Counts over the worlds against the issue's targets."""
    ok = [r for r in results if "runs" in r]
    lr = [r["runs"][f"learned_{r['chosen_iterate']}"]["line_ratio"] for r in ok]
    gate = [r["runs"]["gate"]["line_ratio"] for r in ok]
    return {"worlds": len(ok), "learned_line_ratio": lr, "gate_line_ratio": gate,
            "learned_beats_gate": int(sum(a is not None and b is not None and a < b for a, b in zip(lr, gate))),
            "learned_at_most_0.9": int(sum(a is not None and a <= 0.9 for a in lr)),
            "gate_at_most_0.9": int(sum(b is not None and b <= 0.9 for b in gate)),
            "half_the_oracle_gain": int(sum((r["oracle_gain_captured"] or -1) >= 0.5 for r in ok)),
            "prediction_within_0.1": int(sum(r["predicted_line_ratio"] is not None and a is not None and
                                             abs(r["predicted_line_ratio"] - a) <= 0.1 for r, a in zip(ok, lr)))}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--worlds", type=int, nargs="+", default=[0, 1, 2], help="family seeds (default 0 1 2)")
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--fit", type=int, default=4, help="fit trials per world (default 4)")
    p.add_argument("--rounds", type=int, default=2, help="the priced search's replayed rounds (default 2)")
    p.add_argument("--dagger", type=int, default=2, help="DAgger rounds after behaviour cloning (default 2)")
    p.add_argument("--out", default="/tmp/learned-rule", help="cache of bundles, choices and per-world results")
    p.add_argument("--draws", type=int, default=DRAWS, help=f"matched random draws (default {DRAWS})")
    p.add_argument("--seconds", type=float, default=30.0, help="episode length [s] (default 30)")
    p.add_argument("--markdown", action="store_true")
    a = p.parse_args(argv)
    if a.fit < 1 or a.rounds < 1 or a.dagger < 0 or a.workers < 1 or not a.seconds > 0 or a.draws < 1:
        p.error("need --fit >= 1, --rounds >= 1, --dagger >= 0, --workers >= 1, --seconds > 0, --draws >= 1")
    worlds = [f"family:{s}" for s in a.worlds]
    results = []
    with ProcessPoolExecutor(max_workers=a.workers) as pool:
        futures = [pool.submit(run_world, wd, a.fit, a.rounds, a.dagger, Path(a.out), a.seconds, a.draws)
                   for wd in worlds]
        for f in as_completed(futures):
            results.append(f.result())
            print(json.dumps(results[-1], default=float), flush=True)
    results.sort(key=lambda r: worlds.index(r["world"]))
    print(markdown(results) if a.markdown else json.dumps({"summary": summary(results)}, default=float, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
