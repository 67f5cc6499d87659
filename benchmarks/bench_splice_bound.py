"""What any authority schedule could reach knowing the future, per world: the splice bound (issue 28).

For each world of ``bench_family.py`` (``family:<seed>`` and the data kinds ``default``, ``other_seed``,
``other_structure``): train a bundle as ``bench_family.py --quick`` does, run the constant authorities
``voluntary``, ``reactive``, ``mix25``, ``mix50`` and ``mix75`` (sim seed 0) on the same evaluation
trials (the held-out trials the rule's choice does not use, the first 30 s of 2), and splice their
per-step figures (:mod:`research.splice_bound`): the lowest line ratio, within 0.75x the
wearer's effort, of any schedule that gives each group of control steps one of those authorities,

* groups: segments of 0.1 s, 1 s and 3 s, or whole modes (the controller's own mode estimate);
* authorities: ``binary`` (the wearer or the robot alone: hand-overs) or ``levels`` (all five);
* ``sawing``: the groups mostly labelled ``cutting`` are the wearer's (the task: the knife saws only
  where the wearer leads it), or ``free``;
* ``saws by measure`` (1 s, 3 s and whole modes): the spliced knife's stroke-band correlation with the
  intent over the cutting steps of both trials is at least 0.6, issue 28's target
  (:mod:`research.sawing_bound`: a Lagrangian bound from below and the best schedule found
  that saws, from above). This pools both trials' cutting; the reports average each trial's correlation
  weighted by its cutting time, and ask an amplitude too.

A splice pays no switch (no reaction, no pick-up), so no such schedule does better in the closed
loop: a bound from below on the line ratio. With ``--replay`` the best 1 s and 3 s schedules that saw
by the measure, among the levels the ``schedule`` strategy replays (``voluntary``, ``reactive``,
``mix50``, ``mix75``), are run in the closed loop (:class:`mpcshare.evaluation.schedule.LevelSchedule`,
read half a hand-over ramp ahead): what such a schedule, knowing the future, reaches once its switches
cost what they cost. With ``--priced ROUNDS`` the 1 s schedules that saw are searched with a price on each
switch (:mod:`research.switch_priced`), the prices measured from the earlier rounds' replays,
and replayed round by round; ``--polish REPLAYS`` then searches around the best one in the closed loop, every
candidate replayed; and causal tables (a level per mode estimate, or true phase, and the time in it) are
fitted in hindsight on the same steps (:mod:`research.table_rule`): what a rule that sees only
those could reach at best (``priced_schedules.py``). ``--trial-set choice`` takes the rule choice's two
trials instead, another draw. Prints one JSON line per world and a summary object.

Usage: ``python benchmarks/bench_splice_bound.py [--worlds 0 1 ...] [--kinds default ...] [--workers 2]
[--replay] [--priced ROUNDS [--polish REPLAYS] [--no-bounds] [--dump DIR]] [--trial-set choice]``. About 2 min
of one core per world, 4 more with ``--replay``, about 10 s a replay with ``--priced`` and ``--polish``.
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from priced_schedules import ALPHAS, MIN_CORRELATION, REPLAYABLE, per_step, priced, replay_alpha  # noqa: E402
from worlds import world_data  # noqa: E402

LEVELS = ("voluntary", "reactive", "mix25", "mix50", "mix75")
SEGMENTS_S = (0.1, 1.0, 3.0)


def _stroke(episodes: list[Any], n: list[int], cutting: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray,
                                                                                       float, np.ndarray]:
    """(b·b* (N,), ‖b‖² (N,), Y, the intent (N, 3)) of one run over the first n[i] steps of each episode."""
    from research.sawing_bound import stroke_terms

    parts, start = [], 0
    for ep, k in zip(episodes, n):
        parts.append(stroke_terms(np.asarray(ep.tip)[:k], np.asarray(ep.tip_intent)[:k], cutting[start:start + k], dt))
        start += k
    intent = np.concatenate([np.asarray(ep.tip_intent)[:k] for ep, k in zip(episodes, n)])
    return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]),
            float(sum(p[2] for p in parts)), intent)


def _sawing_entry(e2: np.ndarray, ef: np.ndarray, groups: np.ndarray, strokes: list[tuple], vol: tuple[float, float],
                  rea: tuple[float, float], cutting: np.ndarray, since_cut_s: np.ndarray) -> dict[str, Any]:
    """The bound and the best schedule found whose knife saws by the measure (module docstring)."""
    from research.sawing_bound import best_line_ratios, sawing_front

    runs = e2.shape[0]
    dot, power = np.stack([s[0] for s in strokes[:runs]]), np.stack([s[1] for s in strokes[:runs]])
    front = sawing_front(e2, ef, groups, dot, power, strokes[0][2], MIN_CORRELATION)
    bound, found, i = best_line_ratios(front, vol, rea, 0.75)
    entry: dict[str, Any] = {"line_ratio": bound, "found_line_ratio": found}
    if i is not None:
        _, inv = np.unique(groups, return_inverse=True)
        per_step = front.found_assignment[inv, i]
        entry.update(effort_vs_voluntary=float(front.found_effort[i] / vol[0]),
                     correlation=float(front.found_correlation[i]),
                     cutting_share_by_level={LEVELS[j]: float(np.mean(per_step[cutting] == j)) for j in range(runs)},
                     wearer_share_by_time_in_cutting=_by_time_in_cutting(per_step == 0, cutting, since_cut_s))
    return entry


CUT_BINS_S = (0.0, 1.0, 2.0, 4.0, 8.0, np.inf)


def _since_start(cutting: np.ndarray, starts: np.ndarray, dt: float) -> np.ndarray:
    """Per step the time [s] since its run of cutting steps began (nan outside cutting); a run also begins at
    each of ``starts`` (the trials' first steps)."""
    out, k0 = np.full(cutting.size, np.nan), None
    begin = set(int(s) for s in starts)
    for k, c in enumerate(cutting):
        if c and (k0 is None or k in begin):
            k0 = k
        elif not c:
            k0 = None
        if c:
            out[k] = (k - k0) * dt
    return out


def _by_time_in_cutting(wearer: np.ndarray, cutting: np.ndarray, since_s: np.ndarray) -> dict[str, float | None]:
    """The share of cutting steps the wearer leads, by time since the cutting began (``CUT_BINS_S``)."""
    out: dict[str, float | None] = {}
    for lo, hi in zip(CUT_BINS_S[:-1], CUT_BINS_S[1:]):
        sel = cutting & (since_s >= lo) & (since_s < hi)
        out[f"{lo:g}-{hi:g} s"] = float(np.mean(wearer[sel])) if sel.any() else None
    return out


def _replay(ctx: dict[str, Any], groups: np.ndarray) -> dict[str, Any]:
    """The best schedule that saws among :data:`REPLAYABLE` levels, spliced and replayed in the closed loop."""
    from research.sawing_bound import best_line_ratios, sawing_front

    idx = [LEVELS.index(name) for name in REPLAYABLE]
    st = [ctx["strokes"][i] for i in idx]
    front = sawing_front(ctx["e2"][idx], ctx["ef"][idx], groups, np.stack([s[0] for s in st]),
                         np.stack([s[1] for s in st]), st[0][2], MIN_CORRELATION)
    bound, found, i = best_line_ratios(front, ctx["vol"], ctx["rea"], 0.75)
    out: dict[str, Any] = {"splice_bound": bound, "splice_found": found}
    if i is None:
        return out
    _, inv = np.unique(groups, return_inverse=True)
    out.update(replay_alpha(ctx, ALPHAS[front.found_assignment[inv, i]])[0])
    return out


def run_world(world: str, replay: bool = False, n_rounds: int = 0, bounds: bool = True,
              dump: str | None = None, trial_set: str = "evaluation", polish_budget: int = 0,
              polish_tables: int = 0) -> dict[str, Any]:
    """The bounds of one world (module docstring)."""
    import torch

    torch.set_num_threads(1)
    from mpcshare.calibration.rule_choice import pooled_run
    from mpcshare.calibration.trials import choice_trials
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig
    from research.splice_bound import best_line_ratio, splice_front

    t0 = time.perf_counter()
    demos, mode_names, _ = world_data(world, True)
    bundle = train_bundle(demos, TrainConfig(max_epochs=20), progress=False)
    chooses = choice_trials(bundle.heldout_trials)  # the evaluation trials of bench_family: the others
    trials = ([int(t) for t in chooses][:2] if trial_set == "choice"
              else [int(t) for t in bundle.heldout_trials if int(t) not in chooses][:2])
    eps = {s: pooled_run(bundle, demos, trials, s, None, 30.0, None, 0, mode_names)[1] for s in LEVELS}
    n = [min(len(eps[s][i].t) for s in LEVELS) for i in range(len(trials))]
    figs = [per_step(eps[s], n) for s in LEVELS]
    e2, ef = np.stack([f[0] for f in figs]), np.stack([f[1] for f in figs])
    vol = (float(ef[0].mean()), float(np.sqrt(e2[0].mean())))
    rea = (float(ef[1].mean()), float(np.sqrt(e2[1].mean())))
    by_id = {tr.trial_id: tr for tr in demos.trials}
    cut_label = list(mode_names).index("cutting") if "cutting" in mode_names else None
    labels = [by_id[int(t)].mode for t in trials]
    cutting = (np.concatenate([np.asarray(lab)[:k] == cut_label for lab, k in zip(labels, n)])
               if cut_label is not None and all(lab is not None for lab in labels) else None)
    dt = float(np.median(np.diff(eps["voluntary"][0].t)))
    step = np.concatenate([np.arange(k) for k in n])
    trial = np.concatenate([np.full(k, i) for i, k in enumerate(n)])
    mode = np.concatenate([np.asarray(ep.mode)[:k] for ep, k in zip(eps["reactive"], n)])
    strokes = [] if cutting is None else [_stroke(eps[s], n, cutting, dt) for s in LEVELS]
    if strokes and not all(np.allclose(st[3], strokes[0][3], atol=1e-9) for st in strokes):
        raise RuntimeError(f"{world}: the runs' intents differ; a splice needs one intent")
    since_cut = None if cutting is None else _since_start(cutting, np.cumsum([0] + n[:-1]), dt)
    groupings = {f"{T:g} s": trial * 10**7 + step // max(1, round(T / dt)) for T in SEGMENTS_S}
    groupings["modes"] = mode
    out: dict[str, Any] = {"world": world, "trials": trials, "bounds": {},
                           "voluntary": {"rms_mm": 1e3 * vol[1], "effort_rad": vol[0]},
                           "reactive": {"rms_mm": 1e3 * rea[1], "effort_rad": rea[0]}}
    for gname, groups in (groupings.items() if bounds else ()):
        names, inv = np.unique(groups, return_inverse=True)
        for lname, runs in (("binary", 2), ("levels", len(LEVELS))):
            for task in ("free", "sawing"):
                allowed = np.ones((runs, names.size), dtype=bool)
                if task == "sawing":
                    if cutting is None:
                        continue
                    share = np.bincount(inv, weights=cutting.astype(float)) / np.bincount(inv)
                    allowed[1:, share > 0.5] = False
                front = splice_front(e2[:runs], ef[:runs], groups, allowed=allowed)
                r, i = best_line_ratio(front, vol, rea, 0.75)
                entry: dict[str, Any] = {"line_ratio": r, "effort_vs_voluntary": None if i is None
                                         else float(front.effort[i] / vol[0])}
                if gname == "modes" and i is not None:
                    entry["authority_per_mode"] = {str(int(m)): LEVELS[j] for m, j in zip(names, front.assignment(i))}
                out["bounds"][f"{gname}, {lname}, {task}"] = entry
            if cutting is not None and gname != "0.1 s":
                out["bounds"][f"{gname}, {lname}, saws by measure"] = _sawing_entry(
                    e2[:runs], ef[:runs], groups, strokes, vol, rea, cutting, since_cut)
    if (replay or n_rounds) and cutting is not None:
        ctx = {"e2": e2, "ef": ef, "strokes": strokes, "vol": vol, "rea": rea, "trials": trials, "n": n, "eps": eps,
               "bundle": bundle, "demos": demos, "by_id": by_id, "mode_names": mode_names, "mode": mode,
               "levels": LEVELS, "cutting": cutting, "polish_tables": polish_tables, "dt": dt,
               "trial": trial,
               "labels": np.concatenate([np.asarray(lab)[:k] for lab, k in zip(labels, n)]),
               "dump": (Path(dump) / f"{world.replace(':', '_')}.npz") if dump else None}
        if replay:
            out["replayed"] = {name: _replay(ctx, groupings[name]) for name in ("1 s", "3 s")}
        if n_rounds:
            out["switch_priced"] = priced(ctx, groupings["1 s"], n_rounds, polish_budget)
    out["seconds"] = time.perf_counter() - t0
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--worlds", type=int, nargs="*", default=list(range(10)), help="family seeds (default 0..9)")
    p.add_argument("--kinds", nargs="*", default=["default", "other_seed", "other_structure"],
                   choices=["default", "other_seed", "other_structure"])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--replay", action="store_true",
                   help="replay the best 1 s and 3 s schedules that saw in the closed loop (4 more min a world)")
    p.add_argument("--priced", type=int, default=0, metavar="ROUNDS",
                   help="replay ROUNDS switch-priced 1 s schedules that saw, pricing the switches by the earlier "
                        "replays (about 2 min a round and world)")
    p.add_argument("--polish", type=int, default=0, metavar="REPLAYS",
                   help="with --priced: a local search in the closed loop around the best schedule, REPLAYS replays")
    p.add_argument("--polish-tables", type=int, default=0, metavar="REPLAYS",
                   help="with --priced: improve the mode estimate x time table in the closed loop, REPLAYS replays")
    p.add_argument("--dump", metavar="DIR", help="with --priced: save each world's per-step figures to DIR/<world>.npz")
    p.add_argument("--trial-set", choices=["evaluation", "choice"], default="evaluation",
                   help="which 2 held-out trials: those bench_family evaluates on, or the rule choice's (another draw)")
    p.add_argument("--no-bounds", action="store_true", help="skip the splice and sawing bounds (with --priced)")
    a = p.parse_args(argv)
    worlds = [f"family:{s}" for s in a.worlds] + list(a.kinds)
    t0 = time.perf_counter()
    results = []
    with ProcessPoolExecutor(max_workers=max(1, a.workers), mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(run_world, w, a.replay, a.priced, not a.no_bounds, a.dump, a.trial_set,
                               a.polish, a.polish_tables) for w in worlds]
        for fut in as_completed(futures):
            results.append(fut.result())
            print(json.dumps(results[-1], default=float), flush=True)
    results.sort(key=lambda r: worlds.index(r["world"]))
    keys = sorted({k for r in results for k in r["bounds"]})
    by_world = {r["world"]: {"best replay": r["switch_priced"]["best_replay_meeting_the_task"],
                             "polished": r["switch_priced"].get("polished", {}).get("replay_line_ratio"),
                             **{k: v.get("line_ratio", v.get("replay_line_ratio"))
                                for k, v in r["switch_priced"]["tables"].items()}}
                for r in results if "switch_priced" in r}
    summary = {}
    for k in keys:
        vals = [r["bounds"][k]["line_ratio"] for r in results if k in r["bounds"]]
        got = [v for v in vals if v is not None]
        summary[k] = {"worlds": len(vals), "none_within_cap": len(vals) - len(got),
                      "median": float(np.median(got)) if got else None, "max": max(got) if got else None,
                      "at_most_0.9": sum(v <= 0.9 for v in got), "at_most_0.8": sum(v <= 0.8 for v in got)}
        found = [r["bounds"][k].get("found_line_ratio") for r in results if k in r["bounds"]]
        if any(f is not None for f in found):
            summary[k]["found_at_most_0.9"] = sum(f is not None and f <= 0.9 for f in found)
    print(json.dumps({"summary": summary, "switch_priced": by_world, "worlds": [r["world"] for r in results],
                      "seconds": time.perf_counter() - t0}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
