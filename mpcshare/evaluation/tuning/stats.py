"""Statistics of a sweep's rows: per-setting summaries, the gate against chance, Pareto, recommendation.

* **Summary** per setting (strategy, matched_to, percentile, β): for each of :data:`SUMMARY_KEYS` the mean over
  its episodes (trials × seeds) and a 95 % bootstrap CI of that mean (``scipy.stats.bootstrap``, percentile
  method, 2000 resamples, seed 0; None with fewer than 2 episodes).
* **Line ratio** per setting (:mod:`mpcshare.line_ratio`): its mean tracking RMS over the line from ``reactive``
  (at the setting's percentile; the highest one for settings without one) to ``voluntary`` at its mean effort.
* **Tests** per setting of a tunable strategy: paired over (trial, seed), d = e_random − e_setting of the
  tracking RMS [m] against the setting's matched ``random_handover``, e_random the *mean over the pair's
  draws*; one-sided Wilcoxon signed-rank test of H1: d > 0 (exact for small n), the effect mean(d) [m] with its
  bootstrap CI, and the relative effect mean(d) / mean(e_random). ``n_forced``: the setting's episodes with at
  most one hand-over, left out of the test: the matched schedule (same steps on, hand-overs and first state) is
  then the setting's own, replayed, so the pair says nothing of its timing. **Holm's correction** across the
  m settings tested: ``p_holm`` = max over the settings ranked at or before this one of
  min(1, (m − rank + 1)·p) (ranks by ascending p, from 1); ``beats_random`` uses ``p_holm``.
* **Pareto set**: among the realisable settings (the registry's user strategies: not the upper bound
  ``oracle_preview`` nor the placebo), those no other beats on both mean tracking RMS and mean voluntary effort.
* **Recommended** (:data:`CRITERION`).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from scipy import stats as st

from mpcshare.line_ratio import line_ratio
from mpcshare.run_table import REALISABLE, TUNABLE

__all__ = ["ALPHA_LEVEL", "CRITERION", "PARETO_STRATEGIES", "SUMMARY_KEYS", "gate_vs_random", "holm", "pareto",
           "recommend", "setting_name", "summarise"]

SUMMARY_KEYS: tuple[str, ...] = ("tracking_rmse_m", "tracking_p95_m", "voluntary_effort", "reactive_share",
                                 "handovers", "conflict_share", "lag_s", "saw_amplitude_ratio", "saw_correlation")
ALPHA_LEVEL = 0.05
#: The realisable strategies the Pareto set is drawn from.
PARETO_STRATEGIES: tuple[str, ...] = REALISABLE
CRITERION = (f"the swept setting with the lowest mean tracking RMS among those that beat their matched "
             f"random_handover (one-sided paired Wilcoxon, Holm-corrected across the settings, p < {ALPHA_LEVEL}); "
             f"if none does, the lowest mean tracking RMS of all swept settings, marked as not beating chance")


def setting_name(row: dict[str, Any]) -> str:
    """``gate p90 b0.5``, ``random_handover[gate] p90 b0.5``, ``reactive p90``, ``voluntary``."""
    name = row["strategy"] + (f"[{row['matched_to']}]" if row.get("matched_to") else "")
    if row.get("percentile") is not None:
        name += f" p{row['percentile']:g}"
    if row.get("beta") is not None:
        name += f" b{row['beta']:g}"
    return name


def _ci(values: np.ndarray) -> list[float] | None:
    """95 % bootstrap CI of the mean (None with fewer than 2 values or no spread)."""
    if values.size < 2 or np.ptp(values) == 0:
        return None if values.size < 2 else [float(values[0])] * 2
    res = st.bootstrap((values,), np.mean, confidence_level=0.95, n_resamples=2000, method="percentile",
                       random_state=np.random.default_rng(0))
    return [float(res.confidence_interval.low), float(res.confidence_interval.high)]


def _values(rows: Sequence[dict[str, Any]], key: str) -> np.ndarray:
    v = np.array([np.nan if r.get(key) is None else float(r[key]) for r in rows], dtype=float)
    return v[np.isfinite(v)]


def summarise(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Setting name → its fields, ``n`` episodes and, per key, ``{"mean", "ci95"}`` (module docstring)."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault(setting_name(r), []).append(r)
    out = {}
    for name, rs in groups.items():
        entry: dict[str, Any] = {k: rs[0].get(k) for k in ("strategy", "matched_to", "percentile", "beta")}
        entry["n"] = len(rs)
        for key in SUMMARY_KEYS:
            v = _values(rs, key)
            entry[key] = {"mean": float(v.mean()) if v.size else None, "ci95": _ci(v)}
        out[name] = entry
    _line_ratios(out)
    return out


def _line_ratios(summary: dict[str, dict[str, Any]]) -> None:
    """Set ``line_ratio`` of every setting in place (module docstring); None without the parties."""
    def point(s: dict[str, Any]) -> tuple[float, float] | None:
        e, r = s["voluntary_effort"]["mean"], s["tracking_rmse_m"]["mean"]
        return None if e is None or r is None else (e, r)

    vol = next((point(s) for s in summary.values() if s["strategy"] == "voluntary"), None)
    reac = {s["percentile"]: point(s) for s in summary.values() if s["strategy"] == "reactive"}
    for s in summary.values():
        r = reac.get(s["percentile"]) or (reac[max(reac)] if reac else None)
        s["line_ratio"] = (line_ratio(s["tracking_rmse_m"]["mean"], s["voluntary_effort"]["mean"], vol, r)
                           if vol is not None and r is not None else None)


def holm(p_values: Sequence[float | None]) -> list[float | None]:
    """Holm's step-down adjusted p-values (module docstring); None stays None and is not counted."""
    idx = sorted((i for i, p in enumerate(p_values) if p is not None), key=lambda i: p_values[i])  # type: ignore
    m, out, running = len(idx), [None] * len(p_values), 0.0
    for rank, i in enumerate(idx):
        running = max(running, min(1.0, (m - rank) * float(p_values[i])))  # type: ignore[arg-type]
        out[i] = running
    return out  # type: ignore[return-value]


def _pairs(rows: Sequence[dict[str, Any]], name: str,
           placebo: dict[tuple, list[float]]) -> tuple[np.ndarray, np.ndarray, int]:
    """(e_random: the mean over each pair's draws, e_setting, n_forced) of setting ``name``; the pairs whose
    setting handed over at most once are only counted (module docstring)."""
    pairs, forced = [], 0
    for r in (r for r in rows if r["strategy"] in TUNABLE and setting_name(r) == name):
        if (r.get("handovers") or 0) <= 1:
            forced += 1
            continue
        p = placebo.get((r["strategy"], r["percentile"], r["beta"], r["trial"], r["seed"]))
        if p and r.get("tracking_rmse_m") is not None:
            pairs.append((float(np.mean(p)), float(r["tracking_rmse_m"])))
    e_rand, e_set = (np.array(x) for x in zip(*pairs)) if pairs else (np.zeros(0), np.zeros(0))
    return e_rand, e_set, forced


def gate_vs_random(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per setting of a tunable strategy: ``{"vs_random_handover": {...}}`` (module docstring)."""
    placebo: dict[tuple, list[float]] = {}
    for r in rows:
        if r["strategy"] == "random_handover" and r.get("tracking_rmse_m") is not None:
            key = (r["matched_to"], r["percentile"], r["beta"], r["trial"], r["seed"])
            placebo.setdefault(key, []).append(float(r["tracking_rmse_m"]))
    draws = sorted({len(v) for v in placebo.values()})
    tests = {}
    for name in dict.fromkeys(setting_name(r) for r in rows if r["strategy"] in TUNABLE):
        e_rand, e_set, forced = _pairs(rows, name, placebo)
        d = e_rand - e_set
        p_value = statistic = None
        if d.size and np.any(d != 0):
            res = st.wilcoxon(d, alternative="greater", zero_method="wilcox")
            p_value, statistic = float(res.pvalue), float(res.statistic)
        elif d.size:
            p_value = 1.0
        effect = float(d.mean()) if d.size else None
        tests[name] = {"vs_random_handover": {
            "test": "Wilcoxon signed-rank, one-sided (setting's tracking RMS < the mean of its random_handover "
                    "draws), paired over trials x seeds, Holm-corrected across the settings",
            "n_pairs": int(d.size), "draws_per_pair": draws, "n_forced": forced, "statistic": statistic,
            "p_value": p_value, "effect_m": effect, "effect_ci95_m": _ci(d),
            "relative_effect": effect / float(e_rand.mean()) if d.size and e_rand.mean() > 0 else None}}
    names = list(tests)
    for name, p_h in zip(names, holm([tests[n]["vs_random_handover"]["p_value"] for n in names])):
        v = tests[name]["vs_random_handover"]
        v["p_holm"] = p_h
        v["m_settings"] = sum(tests[n]["vs_random_handover"]["p_value"] is not None for n in names)
        v["beats_random"] = bool(p_h is not None and p_h < ALPHA_LEVEL and (v["effect_m"] or 0) > 0)
    return tests


def pareto(summary: dict[str, dict[str, Any]]) -> list[str]:
    """The settings no other beats on both mean tracking RMS and mean effort (module docstring)."""
    pts = {n: (s["tracking_rmse_m"]["mean"], s["voluntary_effort"]["mean"]) for n, s in summary.items()
           if s["tracking_rmse_m"]["mean"] is not None and s["voluntary_effort"]["mean"] is not None
           and s["strategy"] in PARETO_STRATEGIES}

    def dominated(a: tuple[float, float]) -> bool:
        return any(b[0] <= a[0] and b[1] <= a[1] and b != a for b in pts.values())

    return sorted((n for n, a in pts.items() if not dominated(a)), key=lambda n: pts[n][0])


def recommend(summary: dict[str, dict[str, Any]], tests: dict[str, dict[str, Any]]) -> dict[str, Any] | None:
    """The recommended setting by :data:`CRITERION` (None without gate or blend settings)."""
    def rmse(n: str) -> float:
        m = summary[n]["tracking_rmse_m"]["mean"]
        return math.inf if m is None else m

    names = [n for n in tests if n in summary]
    if not names:
        return None
    winners = [n for n in names if tests[n]["vs_random_handover"]["beats_random"]]
    best = min(winners or names, key=rmse)
    s = summary[best]
    return {"setting": best, "strategy": s["strategy"], "percentile": s["percentile"], "beta": s["beta"],
            "tracking_rmse_m": s["tracking_rmse_m"]["mean"], "voluntary_effort": s["voluntary_effort"]["mean"],
            "beats_random": bool(winners), "criterion": CRITERION}
