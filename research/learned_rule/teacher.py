"""The teacher: switch-priced schedules (:mod:`research.switch_priced`) searched on the per-step figures of
the constant levels and replayed in the closed loop, round by round, each round's switch prices measured
from the earlier replays (as ``benchmarks/priced_schedules.py`` does, without its hindsight tables).

Levels: :data:`LEVELS` (the ones the ``schedule`` replay runs). Groups: 1 s segments of each trial. A
schedule meets the task when its replay costs at most :data:`EFFORT_CAP` × the wearer's effort alone and
saws (trial-mean stroke-band correlation ≥ :data:`MIN_CORRELATION`); :func:`objective` ranks replays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from research.learned_rule.policy import FeatureLog, controller_with, log_arrays

LEVELS = {"voluntary": 0.0, "reactive": 1.0, "mix50": 0.5, "mix75": 0.75}
MIN_CORRELATION = 0.6
EFFORT_CAP = 0.75
GROUP_S = 1.0


@dataclass
class World:
    """One world's bundle, demonstrations (``by_id``: every trial by id), mode names and episode length [s]."""

    bundle: Any
    demos: Any
    by_id: dict[int, Any]
    mode_names: tuple[str, ...]
    duration_s: float = 30.0

    def run(self, tid: int, strategy: str, options: dict[str, Any] | None = None,
            make_controller: Callable[..., Any] | None = None, name: str | None = None) -> tuple[Any, dict[str, Any]]:
        """One closed-loop episode on trial ``tid`` (β 0.5, sim seed 0, the default wearer)."""
        from mpcshare.evaluation.episode import simulate_episode
        from mpcshare.run_table import StrategyRun

        return simulate_episode(self.bundle, self.demos, self.by_id[tid], StrategyRun(name or strategy, strategy),
                                options or {}, beta=0.5, duration_s=self.duration_s, seed=0, wearer=None,
                                mode_names=self.mode_names, make_controller=make_controller)


def pooled(done: list[tuple[Any, dict[str, Any]]], vol: tuple[float, float] | None = None,
           rea: tuple[float, float] | None = None) -> dict[str, Any]:
    """Figures pooled over trials (:func:`mpcshare.evaluation.pooling.pool_metrics`): RMS [mm], effort [rad],
    line ratio and effort × the wearer's (given ``vol``, ``rea`` as (effort, RMS)), stroke correlation (mean and
    least over the trials that cut), lag [s] (mean), least clearance [mm], time inside a zone [s], limit
    violations, the robot's share (mean α), per-trial RMS [m]."""
    from mpcshare.evaluation.pooling import pool_metrics
    from mpcshare.line_ratio import line_ratio

    ms = [m for _, m in done]
    p = pool_metrics(ms, [np.asarray(ep.step_time, dtype=float) for ep, _ in done],
                     [float(ep.t[-1] - ep.t[0]) for ep, _ in done])
    saw = [m["saw_correlation"] for m in ms if m.get("saw_correlation") is not None]
    lag = [m["lag_s"] for m in ms if m.get("lag_s") is not None]
    clear = [m["keepout_min_clearance_m"] for m in ms if m.get("keepout_min_clearance_m") is not None]
    inside = [m.get("keepout_time_inside_s") or 0.0 for m in ms]
    out = {"rms_mm": 1e3 * float(p["tracking_rmse_m"]), "effort": float(p["voluntary_effort"]),
           "stroke_correlation": float(np.mean(saw)) if saw else None,
           "stroke_correlation_min": float(np.min(saw)) if saw else None,
           "lag_s": float(np.mean(lag)) if lag else None,
           "min_clearance_mm": 1e3 * float(np.min(clear)) if clear else None,
           "time_inside_zone_s": float(np.sum(inside)), "limit_violations": int(p["limit_violations"]),
           "robot_share": float(np.mean(np.concatenate([np.nan_to_num(np.asarray(ep.alpha, dtype=float))
                                                        for ep, _ in done]))),
           "per_trial_rms_m": [float(m["tracking_rmse_m"]) for m in ms]}
    if vol is not None and rea is not None:
        out["line_ratio"] = line_ratio(out["rms_mm"] / 1e3, out["effort"], vol, rea)
        out["effort_vs_voluntary"] = out["effort"] / vol[0]
    return out


def step_figures(world: World, trials: list[int], runs: dict[str, list[tuple[Any, dict[str, Any]]]]) -> dict[str, Any]:
    """What the priced search needs of the constant levels' runs on ``trials`` (``runs``: per level of
    :data:`LEVELS` its (episode, metrics) per trial): e² [m²] and effort [rad] per level and step (L, N), the
    stroke terms, the parties' (effort, RMS), the 1 s groups, and per trial its step count and times."""
    from mpcshare.evaluation.handover import tracking_error
    from research.sawing_bound import stroke_terms

    names = list(LEVELS)
    n = [min(len(runs[s][i][0].t) for s in names) for i in range(len(trials))]
    dt = float(np.median(np.diff(runs["voluntary"][0][0].t)))
    cut = list(world.mode_names).index("cutting") if "cutting" in world.mode_names else None
    if cut is None or any(world.by_id[t].mode is None for t in trials):
        raise ValueError("the teacher needs a world with a 'cutting' mode and labelled trials")
    cutting = np.concatenate([np.asarray(world.by_id[t].mode)[:k] == cut for t, k in zip(trials, n)])
    if not cutting.any():
        raise ValueError(f"trials {trials}: no cutting in their first {n} steps; the teacher needs some to saw")
    e2, ef, dot, pw, Y = [], [], [], [], []
    for s in names:
        eps = [ep for ep, _ in runs[s]]
        e2.append(np.concatenate([tracking_error(ep)[:k] ** 2 for ep, k in zip(eps, n)]))
        ef.append(np.concatenate([np.linalg.norm(np.asarray(ep.voluntary), axis=1)[:k] for ep, k in zip(eps, n)]))
        parts, start = [], 0
        for ep, k in zip(eps, n):
            parts.append(stroke_terms(np.asarray(ep.tip)[:k], np.asarray(ep.tip_intent)[:k], cutting[start:start + k],
                                      dt))
            start += k
        dot.append(np.concatenate([q[0] for q in parts]))
        pw.append(np.concatenate([q[1] for q in parts]))
        Y.append(float(sum(q[2] for q in parts)))
    e2a, efa = np.stack(e2), np.stack(ef)
    per = max(1, round(GROUP_S / dt))
    groups = np.concatenate([i * 10**7 + np.arange(k) // per for i, k in enumerate(n)])
    labels = np.unique(groups)
    return {"trials": list(trials), "n": n, "dt": dt, "e2": e2a, "ef": efa, "dot": np.stack(dot), "pw": np.stack(pw),
            "Y": Y[0], "groups": groups, "first": np.concatenate([[True], labels[1:] // 10**7 != labels[:-1] // 10**7]),
            "vol": (float(efa[0].mean()), float(np.sqrt(e2a[0].mean()))),
            "rea": (float(efa[1].mean()), float(np.sqrt(e2a[1].mean()))),
            "times": [np.asarray(runs["voluntary"][i][0].t, dtype=float)[:k] for i, k in enumerate(n)]}


def objective(figs: dict[str, Any]) -> float:
    """A replay's line ratio where it meets the task (module docstring); 10 plus how far it misses otherwise."""
    saw = figs.get("stroke_correlation") or 0.0
    miss = max(figs["effort_vs_voluntary"] / EFFORT_CAP - 1.0, 0.0) + max(MIN_CORRELATION - saw, 0.0)
    ratio = figs.get("line_ratio")
    return 10.0 + miss if miss > 0 or ratio is None else float(ratio)


def replay(world: World, ctx: dict[str, Any], alpha: np.ndarray) -> dict[str, Any]:
    """α per step (N,) replayed on ctx's trials (``LevelSchedule`` read half a hand-over ramp ahead), the
    features logged: {"figures": pooled, "e2", "ef" (N,), "X" (N, F) features, "target" (N,) α targets}."""
    from mpcshare.control.types import ControllerConfig
    from mpcshare.evaluation.handover import tracking_error
    from mpcshare.evaluation.schedule import LevelSchedule

    lead = ControllerConfig().handover_s / 2
    K = world.bundle.n_modes
    done, X, tg, start = [], [], [], 0
    for tid, k, times in zip(ctx["trials"], ctx["n"], ctx["times"]):
        log: list[tuple[float, np.ndarray, float]] = []
        sched = LevelSchedule(times, alpha[start:start + k], lead)
        start += k
        ep, m = world.run(tid, "schedule", {"schedule": sched},
                          controller_with("schedule", lambda p, log=log: FeatureLog(p, K, log)), name="replay")
        done.append((ep, m))
        x, a = log_arrays(log, np.asarray(ep.t)[:k])
        X.append(x)
        tg.append(a)
    e2 = np.concatenate([tracking_error(ep)[:k] ** 2 for (ep, _), k in zip(done, ctx["n"])])
    ef = np.concatenate([np.linalg.norm(np.asarray(ep.voluntary), axis=1)[:k] for (ep, _), k in zip(done, ctx["n"])])
    return {"figures": pooled(done, ctx["vol"], ctx["rea"]), "e2": e2, "ef": ef, "X": np.concatenate(X),
            "target": np.concatenate(tg), "episodes": done}


def priced_teacher(world: World, ctx: dict[str, Any], rounds: int = 2, log: Callable[[str], None] = print
                   ) -> dict[str, Any]:
    """The best replay (by :func:`objective`) of ``rounds`` switch-priced searches (module docstring): its
    α per step ``alpha`` (N,), its replay (:func:`replay`) and each round's figures. Where a replay saws
    too little the next round asks the search for that much more correlation; where it costs too much effort,
    for that much less."""
    from research.splice_bound import group_sums
    from research.switch_priced import SwitchPrices, estimate_prices, next_targets, priced_search

    alphas = np.array(list(LEVELS.values()))
    e2, ef, groups, first = ctx["e2"], ctx["ef"], ctx["groups"], ctx["first"]
    _, inv = np.unique(groups, return_inverse=True)
    cols = np.arange(inv.size)
    prices, samples, target, cap = SwitchPrices.zero(), [], MIN_CORRELATION, EFFORT_CAP
    best: dict[str, Any] | None = None
    out = []
    for r in range(rounds):
        found = priced_search(e2, ef, groups, first, ctx["dot"], ctx["pw"], ctx["Y"], target, prices, ctx["vol"],
                              ctx["rea"], max_effort=cap)
        if found is None:
            out.append({"round": r, "found": False})
            break
        level = found.assignment[inv]
        rep = replay(world, ctx, alphas[level])
        figs = rep["figures"]
        log(f"teacher round {r}: predicted {found.line_ratio:.3f}, replayed {figs['line_ratio']}, "
            f"effort {figs['effort_vs_voluntary']:.2f}, saw {figs['stroke_correlation']}")
        out.append({"round": r, "predicted_line_ratio": found.line_ratio, "switches": found.switches,
                    **{k: figs[k] for k in ("line_ratio", "effort_vs_voluntary", "stroke_correlation")},
                    "objective": objective(figs)})
        if best is None or objective(figs) < objective(best["replay"]["figures"]):
            best = {"alpha": alphas[level], "replay": rep, "round": r}
        x_e2 = group_sums((rep["e2"] - e2[level, cols])[None], groups)[1][0]
        x_ef = group_sums((rep["ef"] - ef[level, cols])[None], groups)[1][0]
        samples.append((found.assignment, first, x_e2, x_ef))
        prices = estimate_prices(samples)
        target, cap = next_targets(target, cap, figs["stroke_correlation"], figs["effort_vs_voluntary"],
                                   min_correlation=MIN_CORRELATION, effort_cap=EFFORT_CAP)
    return {"rounds": out, "best": best}


def teacher_labels(ctx: dict[str, Any], alpha: np.ndarray, times: list[np.ndarray]) -> np.ndarray:
    """The teacher's α target at each step of episodes on ctx's trials (``times`` per trial, the first
    ctx["n"] steps): its schedule ``alpha`` (N,) read half a hand-over ramp ahead, as its replay reads it."""
    from mpcshare.control.types import ControllerConfig
    from mpcshare.evaluation.schedule import LevelSchedule

    lead = ControllerConfig().handover_s / 2
    out, start = [], 0
    for k, t_sched, t_ep in zip(ctx["n"], ctx["times"], times):
        s = LevelSchedule(t_sched, alpha[start:start + k], lead)
        start += k
        out.append(np.array([s(float(t)) for t in np.asarray(t_ep)[:k]]))
    return np.concatenate(out)
