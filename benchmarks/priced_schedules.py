"""Switch-priced schedules replayed in the closed loop, and causal tables fitted in hindsight (issue 28).

The part of ``bench_splice_bound.py --priced`` that runs schedules: :func:`replay_alpha` replays an authority
level per step with :class:`mpcshare.evaluation.schedule.LevelSchedule`; :func:`priced` searches
switch-priced schedules (:mod:`research.switch_priced`) round by round, each round's switch
prices measured from the earlier replays; :func:`polish` then searches around the best one in the closed
loop itself, each candidate replayed; :func:`table_rules` fits causal tables in hindsight
(:mod:`research.table_rule`).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

MIN_CORRELATION = 0.6  # issue 28: "saws while cutting (stroke-band correlation >= 0.6)"
REPLAYABLE = {"voluntary": 0.0, "reactive": 1.0, "mix50": 0.5, "mix75": 0.75}  # the replay's α per level
EFFORT_CAP = 0.75  # issue 28: the wearer's effort at most 0.75x doing it alone
ALPHAS = np.array(list(REPLAYABLE.values()))  # α per replayable level, in REPLAYABLE's order


def per_step(episodes: list[Any], n: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """(squared tracking error [m²], effort [rad]) per step of the first n[i] steps of each episode."""
    from mpcshare.evaluation.handover import tracking_error

    e2 = np.concatenate([tracking_error(ep)[:k] ** 2 for ep, k in zip(episodes, n)])
    ef = np.concatenate([np.linalg.norm(np.asarray(ep.voluntary), axis=1)[:k] for ep, k in zip(episodes, n)])
    return e2, ef


def replay_alpha(ctx: dict[str, Any], alpha: np.ndarray) -> tuple[dict[str, Any], np.ndarray, np.ndarray]:
    """Replay α per step (N,) in the closed loop (:class:`LevelSchedule`, read half a hand-over ramp ahead):
    (the pooled figures, the replay's e² [m²] and θ [rad] per step (N,))."""
    from mpcshare.control.types import ControllerConfig
    from mpcshare.evaluation.pooling import pool_metrics
    from mpcshare.evaluation.runs import simulate_episode
    from mpcshare.evaluation.schedule import LevelSchedule
    from mpcshare.line_ratio import line_ratio
    from mpcshare.run_table import StrategyRun

    lead = ControllerConfig().handover_s / 2
    ms, steps, secs, eps, start = [], [], [], [], 0
    for tid, k, ep0 in zip(ctx["trials"], ctx["n"], ctx["eps"]["reactive"]):
        sched = LevelSchedule(np.asarray(ep0.t)[:k], alpha[start:start + k], lead)
        start += k
        ep, m = simulate_episode(ctx["bundle"], ctx["demos"], ctx["by_id"][tid], StrategyRun("replay", "schedule"),
                                 {"schedule": sched}, beta=0.5, duration_s=30.0, seed=0, wearer=None,
                                 mode_names=ctx["mode_names"])
        ms.append(m)
        eps.append(ep)
        steps.append(np.asarray(ep.step_time, dtype=float))
        secs.append(float(ep.t[-1] - ep.t[0]))
    p = pool_metrics(ms, steps, secs)
    saw = [m["saw_correlation"] for m in ms if m.get("saw_correlation") is not None]
    e2, ef = per_step(eps, ctx["n"])
    return ({"replay_line_ratio": line_ratio(p["tracking_rmse_m"], p["voluntary_effort"], ctx["vol"], ctx["rea"]),
             "replay_effort_vs_voluntary": p["voluntary_effort"] / ctx["vol"][0],
             "replay_saw_correlation": float(np.mean(saw)) if saw else None,
             "replay_limit_violations": int(p["limit_violations"])}, e2, ef)


def priced(ctx: dict[str, Any], groups: np.ndarray, rounds: int, polish_budget: int = 0) -> dict[str, Any]:
    """Switch-priced schedules (:mod:`research.switch_priced`), replayed round by round: round 0
    pays nothing for a switch (the splice); each later round prices the switches by the excess of every
    earlier replay over its splice and searches again. Where a replay saws below the target (the reports
    average the trials' correlations, the search pools them, and a switch moves the stroke), the next
    round asks the search for that much more correlation; where it costs more than the effort cap, for that
    much less effort. With ``polish_budget`` > 0, :func:`polish` then
    searches around the best schedule replayed."""
    from research.splice_bound import group_sums
    from research.switch_priced import SWITCH_CLASSES, SwitchPrices, estimate_prices, next_targets, priced_search

    idx = [list(ctx["levels"]).index(name) for name in REPLAYABLE]
    e2, ef = ctx["e2"][idx], ctx["ef"][idx]
    st = [ctx["strokes"][i] for i in idx]
    labels, inv = np.unique(groups, return_inverse=True)
    first = _trial_starts(labels)
    prices, samples, out, target, cap = SwitchPrices.zero(), [], [], MIN_CORRELATION, EFFORT_CAP
    for r in range(rounds):
        found = priced_search(e2, ef, groups, first, np.stack([s[0] for s in st]), np.stack([s[1] for s in st]),
                              st[0][2], target, prices, ctx["vol"], ctx["rea"], max_effort=cap)
        entry: dict[str, Any] = {"round": r, "search_correlation": target, "search_effort_cap": cap,
                                 "prices_m2_steps": dict(zip(SWITCH_CLASSES, prices.error.tolist())),
                                 "effort_prices_rad_steps": dict(zip(SWITCH_CLASSES, prices.effort.tolist()))}
        if found is None:
            out.append(entry)
            break
        per_step = found.assignment[inv]
        figs, rep_e2, rep_ef = replay_alpha(ctx, ALPHAS[per_step])
        cols = np.arange(per_step.size)
        x_e2 = group_sums((rep_e2 - e2[per_step, cols])[None], groups)[1][0]
        x_ef = group_sums((rep_ef - ef[per_step, cols])[None], groups)[1][0]
        samples.append((found.assignment, first, x_e2, x_ef))
        entry.update(predicted_line_ratio=found.line_ratio, predicted_effort_vs_voluntary=found.effort / ctx["vol"][0],
                     switches=found.switches, wearer_share=float(np.mean(per_step == 0)), **figs)
        out.append(entry)
        prices = estimate_prices(samples)
        target, cap = next_targets(target, cap, figs["replay_saw_correlation"], figs["replay_effort_vs_voluntary"],
                                   min_correlation=MIN_CORRELATION, effort_cap=EFFORT_CAP)
    done = [e for e in out if e.get("replay_line_ratio") is not None and e["replay_effort_vs_voluntary"] <= 0.75
            and (e["replay_saw_correlation"] or 0.0) >= MIN_CORRELATION]
    result = {"rounds": out, "tables": table_rules(ctx, e2, ef, st, prices, target)}
    if ctx.get("dump"):
        st_arr = np.stack([np.stack([s[0] for s in st]), np.stack([s[1] for s in st])])
        np.savez(ctx["dump"], labels=ctx["labels"], e2=e2, ef=ef, stroke=st_arr, intent_power=st[0][2],
                 groups=groups, first=first, mode=ctx["mode"], cutting=ctx["cutting"], vol=ctx["vol"],
                 rea=ctx["rea"], dt=ctx["dt"], prices_error=prices.error, prices_effort=prices.effort,
                 trial=ctx["trial"],
                 schedules=np.stack([s_[0] for s_ in samples]) if samples else np.zeros((0, labels.size)))
    result["best_replay_meeting_the_task"] = min((e["replay_line_ratio"] for e in done), default=None)
    replayed = [(objective(e), e["round"]) for e in out if e.get("replay_line_ratio") is not None]
    if polish_budget > 0 and replayed:
        result["polished"] = polish(ctx, groups, samples[min(replayed)[1]][0], polish_budget)
    return result


def objective(figs: dict[str, Any]) -> float:
    """A replay's line ratio where it meets the effort cap and saws; 10 plus how far it misses otherwise."""
    saw = figs.get("replay_saw_correlation") or 0.0
    miss = max(figs["replay_effort_vs_voluntary"] / EFFORT_CAP - 1.0, 0.0) + max(MIN_CORRELATION - saw, 0.0)
    ratio = figs.get("replay_line_ratio")
    return 10.0 + miss if miss > 0 or ratio is None else float(ratio)


def _moves(level: np.ndarray, first: np.ndarray, rng: np.random.Generator) -> list[np.ndarray]:
    """Schedules next to ``level`` (G,): each segment of at most 2 groups merged into its left neighbour,
    then each switch moved one group either way; in random order within each kind."""
    merges, shifts = [], []
    starts = [g for g in range(1, level.size) if level[g] != level[g - 1] and not first[g]]
    for i, g in enumerate(starts):
        end = starts[i + 1] if i + 1 < len(starts) else level.size
        end = min([end] + [h for h in range(g + 1, level.size) if first[h]])
        if end - g <= 2:
            m = level.copy()
            m[g:end] = level[g - 1]
            merges.append(m)
        for src, dst in ((g - 1, g), (g, g - 1)):
            m = level.copy()
            m[dst] = level[src]
            shifts.append(m)
    rng.shuffle(merges)
    rng.shuffle(shifts)
    return merges + shifts


def _trial_starts(labels: np.ndarray) -> np.ndarray:
    """(G,) whether each sorted 1 s group label (trial·10⁷ + segment, as ``bench_splice_bound`` makes them)
    begins a trial."""
    return np.concatenate([[True], labels[1:] // 10**7 != labels[:-1] // 10**7])


def _descend(ctx: dict[str, Any], start: np.ndarray, neighbours: Callable[[np.ndarray], list[np.ndarray]],
             alpha: Callable[[np.ndarray], np.ndarray], budget: int) -> tuple[np.ndarray, dict[str, Any], int, int]:
    """First-improvement local search in the closed loop: from ``start``, replay the candidates of
    ``neighbours`` (α per step by ``alpha``) in their order and take the first whose replay lowers
    :func:`objective`, until none does or ``budget`` replays are spent. (the point, its replay's figures,
    replays used, moves taken)."""
    point = np.asarray(start, dtype=int).copy()
    figs = replay_alpha(ctx, alpha(point))[0]
    best, used, taken = objective(figs), 1, 0
    while used < budget:
        for cand in neighbours(point):
            if used >= budget:
                break
            cand_figs = replay_alpha(ctx, alpha(cand))[0]
            used += 1
            if objective(cand_figs) < best - 1e-4:
                point, figs, best, taken = cand, cand_figs, objective(cand_figs), taken + 1
                break
        else:
            break
    return point, figs, used, taken


def polish(ctx: dict[str, Any], groups: np.ndarray, start: np.ndarray, budget: int) -> dict[str, Any]:
    """A local search in the closed loop around the level per group ``start`` over the moves of
    :func:`_moves` (:func:`_descend`). What it returns was replayed: a schedule that reaches it exists
    (knowing the future)."""
    labels, inv = np.unique(groups, return_inverse=True)
    first = _trial_starts(labels)
    rng = np.random.default_rng(0)
    level, figs, used, taken = _descend(ctx, start, lambda lv: _moves(lv, first, rng), lambda lv: ALPHAS[lv[inv]],
                                        budget)
    switches = int(np.sum((level[1:] != level[:-1]) & ~first[1:]))
    return {"replays": used, "moves_taken": taken, "switches": switches, **figs,
            "meets_the_task": objective(figs) < 10.0}


TIME_IN_MODE_S = (0.0, 0.5, 1.0, 2.0, 4.0)  # the bins of the time in a mode [s]
ANTICIPATION_S = 0.5  # issue 28's anticipating hand-over: the wearer leads from 0.5 s before the stroke mode


def table_rules(ctx: dict[str, Any], e2: np.ndarray, ef: np.ndarray, st: list[tuple], prices: Any,
                 target: float, replay_tables: bool = True) -> dict[str, Any]:
    """Causal tables fitted in hindsight on the same steps, with the last round's switch prices
    (:mod:`research.table_rule`): a level per mode estimate (whole modes) and per mode estimate ×
    time in it; the same with the true task phase in place of the estimate (what a perfect mode filter adds), and
    with the true phase :data:`ANTICIPATION_S` ahead (what a filter that foresaw each phase change could add).
    Each fitted table's schedule is then replayed in the closed loop (the priced splice only estimates what its
    switches cost)."""
    from research.table_rule import fit_table, score_schedule, time_in_cell

    dot, pw = np.stack([s[0] for s in st]), np.stack([s[1] for s in st])

    def score(level: np.ndarray) -> Any:
        return score_schedule(level, e2, ef, dot, pw, st[0][2], ctx["trial"], prices, ctx["vol"], ctx["rea"])

    labels, trial = np.asarray(ctx["labels"]), np.asarray(ctx["trial"])
    ends = {t: np.flatnonzero(trial == t).max() for t in np.unique(trial)}
    last = np.array([ends[t] for t in trial])  # per step the last step of its trial
    ahead = labels[np.minimum(np.arange(labels.size) + max(1, round(ANTICIPATION_S / ctx["dt"])), last)]
    out: dict[str, Any] = {}
    for name, cell in (("mode estimate", ctx["mode"]), ("true phase", labels),
                       (f"true phase {ANTICIPATION_S:g} s ahead", ahead)):
        cell = np.asarray(cell, dtype=int)
        bins = time_in_cell(cell, ctx["trial"], ctx["dt"], TIME_IN_MODE_S)
        fit = fit_table(cell, bins, score, e2.shape[0], effort_cap=EFFORT_CAP * ctx["vol"][0],
                        min_correlation=target)
        for key, table, sc in (("whole", fit.whole, fit.whole_score), ("x time in it", fit.table, fit.score)):
            meets = sc.effort <= EFFORT_CAP * ctx["vol"][0] and sc.correlation >= MIN_CORRELATION
            out[f"{name}, {key}"] = {"line_ratio": sc.line_ratio if meets else None,
                                     "unconstrained_line_ratio": sc.line_ratio,
                                     "effort_vs_voluntary": sc.effort / ctx["vol"][0], "correlation": sc.correlation,
                                     "switches": sc.switches, "table": table.tolist()}
            if replay_tables:  # the table's schedule on these steps, run: its figures with the switches' true cost
                figs = replay_alpha(ctx, ALPHAS[table[cell, bins]])[0]
                out[f"{name}, {key}"].update(figs, replay_meets_the_task=objective(figs) < 10.0)
        if name == "mode estimate" and ctx.get("polish_tables", 0) > 0:
            out["mode estimate, x time in it, polished"] = polish_table(ctx, cell, bins, fit.table,
                                                                        ctx["polish_tables"])
    return out


def polish_table(ctx: dict[str, Any], cell: np.ndarray, bins: np.ndarray, table: np.ndarray,
                 budget: int) -> dict[str, Any]:
    """A causal table improved in the closed loop: single-cell changes in random order (:func:`_descend`). Still
    fitted on the steps it is scored on: what the best such table could reach here, not what one would reach
    elsewhere."""
    rng = np.random.default_rng(0)
    cells = sorted({(int(a), int(b)) for a, b in zip(cell, bins)})

    def changes(t: np.ndarray) -> list[np.ndarray]:
        moves = [(a, b, lv) for a, b in cells for lv in range(ALPHAS.size) if lv != t[a, b]]
        rng.shuffle(moves)
        out = []
        for a, b, lv in moves:
            cand = t.copy()
            cand[a, b] = lv
            out.append(cand)
        return out

    table, figs, used, taken = _descend(ctx, table, changes, lambda t: ALPHAS[t[cell, bins]], budget)
    return {"replays": used, "moves_taken": taken, "table": table.tolist(), **figs,
            "meets_the_task": objective(figs) < 10.0}
