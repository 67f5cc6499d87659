"""The default gate's settings chosen in the closed loop on held-out trials of the user's own data.

The rule (:mod:`mpcshare.control.strategies.gate`) hands the wearer the modes whose held-out
unpredictable share v_j reaches ``share_on``. Which modes those should be depends on how well the
robot and the wearer track each mode, which the data alone does not say (the wearer's error is
not recorded), so :func:`choose_rule` measures it: for each nested set of wearer modes (the modes
sorted by v_j, the top 1, 2, …, K − 1; thresholds between consecutive shares, :func:`candidates`) it
simulates the closed loop (:func:`mpcshare.experiments.simulate_episode`, the default wearer) on
the given held-out trials, beside ``voluntary`` and ``reactive``, and reads each candidate's
**line ratio** r = RMS / RMS_line(e), the line running from (effort, RMS) of ``reactive`` to that
of ``voluntary``, evaluated at the candidate's effort e (below 1: better than mixing the parties).

Criterion (:data:`CRITERION`): the lowest line ratio among the candidates whose effort is at most
``max_effort`` × the voluntary effort (the issue-28 target 0.75). When none is, or the line is
ill-posed (the robot alone costs the wearer at least ``max_effort`` × the effort of doing it
alone: they correct it that much, and every ratio then divides by a near-vertical line), the
lowest tracking RMS: where nothing saves effort, track best.
The choice, every candidate's figures and why are returned for the bundle's ``metrics`` and
``training.md``.
"""

from __future__ import annotations

import time
from typing import Any, Callable, Sequence

import numpy as np

from learning.data import Demonstrations
from mpcshare.control.setup import arbitration_inputs
from mpcshare.control.strategies.gate import voluntary_shares
from mpcshare.control.types import ControllerConfig
from mpcshare.experiments import StrategyRun, pool_metrics, simulate_episode
from mpcshare.line_ratio import line_ratio as _line_ratio
from sim.wearer import WearerConfig

__all__ = ["CRITERION", "candidates", "choose_for_bundle", "choose_rule", "line_ratio", "rule_markdown"]

CRITERION = ("lowest line ratio among the candidates with effort <= max_effort x voluntary; if none, or "
             "reactive itself costs >= max_effort x voluntary, the lowest tracking RMS")


def line_ratio(rms: float, effort: float, voluntary: dict[str, float], reactive: dict[str, float]) -> float | None:
    """RMS / RMS_line(effort) of :func:`mpcshare.line_ratio.line_ratio` (the one definition: the line
    held at its ends, never extrapolated), from the parties' pooled metrics; None where undefined."""
    return _line_ratio(rms, effort, (voluntary["voluntary_effort"], voluntary["tracking_rmse_m"]),
                       (reactive["voluntary_effort"], reactive["tracking_rmse_m"]))


def candidates(v: np.ndarray) -> list[dict[str, Any]]:
    """The nested wearer-mode sets: for the top i modes by v_j (i = 1..K−1, distinct shares),
    share_on halfway between the i-th and the (i+1)-th share, share_off halfway below it; last, the
    empty set (the robot leads every mode; share_on halfway between the largest share and 1), so
    that the choice can keep the robot leading where it tracks best."""
    order = np.argsort(-np.asarray(v, dtype=float), kind="stable")
    s = np.asarray(v, dtype=float)[order]
    out = []
    for i in range(1, len(s)):
        if s[i - 1] - s[i] <= 1e-9:
            continue
        on = 0.5 * (s[i - 1] + s[i])
        out.append({"wearer_modes": sorted(int(j) for j in order[:i]),
                    "settings": {"share_on": round(float(on), 6), "share_off": round(float(0.5 * (on + s[i])), 6)}})
    if len(s) and s[0] < 1.0 - 1e-6:
        on = 0.5 * (s[0] + 1.0)
        out.append({"wearer_modes": [],
                    "settings": {"share_on": round(float(on), 6), "share_off": round(float(0.5 * (on + s[0])), 6)}})
    return out


def _pooled(bundle: Any, demos: Demonstrations, trials: Sequence[int], strategy: str, options: dict | None,
            duration_s: float | None, wearer: WearerConfig | None, seed: int) -> dict[str, float]:
    by_id = {tr.trial_id: tr for tr in demos.trials}
    ms, steps, secs = [], [], []
    extra = {"config": ControllerConfig(strategy_options=dict(options))} if options else {}
    for tid in trials:
        ep, m = simulate_episode(bundle, demos, by_id[int(tid)], StrategyRun(strategy, strategy), extra, beta=0.5,
                                 duration_s=duration_s, seed=seed, wearer=wearer, mode_names=None)
        ms.append(m)
        steps.append(np.asarray(ep.step_time, dtype=float))
        secs.append(float(ep.t[-1] - ep.t[0]))
    p = pool_metrics(ms, steps, secs)
    return {k: p[k] for k in ("tracking_rmse_m", "voluntary_effort", "limit_violations")}


def choose_rule(bundle: Any, demos: Demonstrations, trials: Sequence[int], *, duration_s: float | None = 30.0,
                max_effort: float = 0.75, wearer: WearerConfig | None = None, seed: int = 0,
                log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """Choose the gate's settings in the closed loop (module docstring).

    Returns ``{"settings", "wearer_modes", "why", "criterion", "candidates", "voluntary", "reactive",
    "trials", "duration_s", "seconds"}``. Raises ValueError when the bundle has no per-mode figures
    or no trial is given.
    """
    if not len(trials):
        raise ValueError("choose_rule needs at least one held-out trial")
    v = voluntary_shares(arbitration_inputs(bundle)["mode_stats"])
    if v is None:
        raise ValueError("the bundle has no per-mode held-out figures (metrics['gate']['per_mode']) to choose from")
    t0 = time.perf_counter()
    run = lambda s, o=None: _pooled(bundle, demos, trials, s, o, duration_s, wearer, seed)  # noqa: E731
    vol, rea = run("voluntary"), run("reactive")
    rows = []
    for c in candidates(v):
        m = run("gate", c["settings"])
        rows.append({**c, **m, "line_ratio": line_ratio(m["tracking_rmse_m"], m["voluntary_effort"], vol, rea),
                     "effort_vs_voluntary": m["voluntary_effort"] / vol["voluntary_effort"]})
        if log is not None:
            r = rows[-1]
            lr = "n/a" if r["line_ratio"] is None else f"{r['line_ratio']:.3f}"
            log(f"  gate with wearer modes {r['wearer_modes']}: RMS {r['tracking_rmse_m'] * 1e3:.1f} mm, effort "
                f"{r['effort_vs_voluntary']:.2f}x voluntary, line ratio {lr}")
    if not rows:
        raise ValueError(f"every mode has the same held-out unpredictable share {v.tolist()}: nothing to choose")
    ok = [r for r in rows if r["effort_vs_voluntary"] <= max_effort and r["line_ratio"] is not None]
    posed = rea["voluntary_effort"] < max_effort * vol["voluntary_effort"]
    if ok and posed:
        best = min(ok, key=lambda r: r["line_ratio"])
        why = (f"lowest line ratio ({best['line_ratio']:.3f}) among the {len(ok)} of {len(rows)} candidates with "
               f"effort <= {max_effort:g}x voluntary")
    else:
        best = min(rows, key=lambda r: r["tracking_rmse_m"])
        cause = (f"reactive alone costs {rea['voluntary_effort'] / vol['voluntary_effort']:.2f}x the voluntary effort"
                 if not posed else f"no candidate has effort <= {max_effort:g}x voluntary")
        why = f"{cause}; the lowest tracking RMS ({best['tracking_rmse_m'] * 1e3:.1f} mm)"
    return {"settings": best["settings"], "wearer_modes": best["wearer_modes"], "why": why, "criterion": CRITERION,
            "max_effort": max_effort, "candidates": rows, "voluntary": vol, "reactive": rea,
            "trials": [int(t) for t in trials], "duration_s": duration_s, "voluntary_share_by_mode": v.tolist(),
            "seconds": round(time.perf_counter() - t0, 1)}


def choose_for_bundle(bundle: Any, demos: Demonstrations, *, n_trials: int | None = None,
                      duration_s: float | None = 30.0, wearer_name: str | None = None,
                      log: Callable[[str], None] | None = None) -> dict[str, Any]:
    """:func:`choose_rule` on the last ``n_trials`` held-out trials of ``bundle`` (default: half of them,
    1 to 2) with the wearer preset ``wearer_name`` (default the default preset), recorded in
    ``bundle.metrics`` (``rule_settings``, ``rule_choice``) so that the saved bundle's ``gate`` uses it;
    returns the choice. What ``mpcshare train``, ``mpcshare demo`` and the benchmarks call."""
    from sim.wearer_presets import DEFAULT_WEARER_PRESET, wearer_preset

    name = wearer_name or DEFAULT_WEARER_PRESET
    held = list(bundle.heldout_trials)
    n = n_trials or min(2, max(1, len(held) // 2))
    choice = choose_rule(bundle, demos, held[-n:], duration_s=duration_s, log=log, wearer=wearer_preset(name))
    choice["wearer"] = name
    bundle.metrics["rule_settings"] = choice["settings"]
    bundle.metrics["rule_choice"] = choice
    return choice


def rule_markdown(choice: dict[str, Any]) -> str:
    """The choice as a Markdown section (for ``training.md``)."""
    dur = "whole trials" if choice["duration_s"] is None else f"the first {choice['duration_s']:g} s"
    lines = ["## Hand-over rule (closed-loop choice)", "",
             f"Chosen on held-out trials {choice['trials']} ({dur}, wearer {choice.get('wearer', 'default')}) in "
             f"{choice['seconds']:g} s: "
             f"the wearer leads modes {choice['wearer_modes']}, settings {choice['settings']}.", "",
             f"Why: {choice['why']}. Criterion: {choice['criterion']}.", "",
             f"Held-out unpredictable share per mode: {[round(x, 3) for x in choice['voluntary_share_by_mode']]}.", "",
             "| run | wearer modes | RMS [mm] | effort vs voluntary | line ratio |", "|---|---|---|---|---|"]
    for name in ("voluntary", "reactive"):
        m = choice[name]
        lines.append(f"| {name} | | {m['tracking_rmse_m'] * 1e3:.1f} | "
                     f"{m['voluntary_effort'] / choice['voluntary']['voluntary_effort']:.2f} | 1 |")
    for r in choice["candidates"]:
        lr = "n/a" if r["line_ratio"] is None else f"{r['line_ratio']:.3f}"
        lines.append(f"| gate | {r['wearer_modes']} | {r['tracking_rmse_m'] * 1e3:.1f} | "
                     f"{r['effort_vs_voluntary']:.2f} | {lr} |")
    return "\n".join(lines) + "\n"
