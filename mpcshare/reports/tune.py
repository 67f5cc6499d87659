"""The files of ``mpcshare tune``: ``tune.json``, ``tune.md`` and ``pareto.png``.

``tune.json``: ``rows`` (one per episode: ``percentile``, ``beta``, ``strategy``,
``matched_to``, ``trial``, ``seed``, the metrics of ``comparison.json`` and the task metrics,
and for gate/blend rows their ``schedule``), ``summary`` (setting → means with 95 %
bootstrap CIs over trials × seeds, and ``line_ratio``: the mean RMS over the voluntary–reactive
line at the mean effort, :mod:`mpcshare.line_ratio`), ``tests`` (setting of a tunable strategy →
``vs_random_handover``: ``p_value``, ``p_holm`` (Holm-corrected across the settings),
``effect_m``, ``effect_ci95_m``, ``draws_per_pair``, …), ``multiple_testing`` (the correction,
its family size and level), ``draws`` (placebo draws per pair), ``pareto`` (setting names),
``recommended`` (the setting and its ``criterion``), ``trials``, ``seeds``, ``duration_s``,
``wearer``, ``bundles``, ``timing_keys`` (the row keys that depend on wall time).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from learning.atomic import atomic_open, write_json
from mpcshare.evaluation.tuning.stats import ALPHA_LEVEL, gate_vs_random, pareto, recommend, summarise
from mpcshare.reports.style import number

__all__ = ["baseline_sentence", "build_result", "chance_sentences", "recommendation_line", "tune_markdown",
           "write_tune"]


def build_result(rows: list[dict[str, Any]], **info: Any) -> dict[str, Any]:
    """``tune.json``'s object from the rows (module docstring); ``info``: the run's other fields."""
    from mpcshare.evaluation.tuning.episodes import TIMING_KEYS

    summary = summarise(rows)
    tests = gate_vs_random(rows)
    m = sum(t["vs_random_handover"]["p_value"] is not None for t in tests.values())
    correction = {"method": "Holm", "family": "the swept settings' tests against their matched random_handover",
                  "m": m, "alpha": ALPHA_LEVEL}
    return {"rows": rows, "summary": summary, "tests": tests, "multiple_testing": correction,
            "pareto": pareto(summary), "recommended": recommend(summary, tests),
            "timing_keys": list(TIMING_KEYS), **info}


def _mm(x: Any) -> str:
    return number(x, ".1f", 1e3)


def _num(x: Any, fmt: str = ".3f") -> str:
    return number(x, fmt)


def recommendation_line(result: dict[str, Any]) -> str | None:
    """The recommendation in one line, with its figures and what it loses to: said plainly when the
    wearer alone (``voluntary``) tracks better."""
    rec = result["recommended"]
    if not rec:
        return None
    line = (f"recommended: {rec['setting']} (tracking RMS {_mm(rec['tracking_rmse_m'])} mm, effort "
            f"{_num(rec['voluntary_effort'])} rad)")
    vol = result["summary"].get("voluntary")
    v_rms = vol["tracking_rmse_m"]["mean"] if vol else None
    if v_rms is not None and rec["tracking_rmse_m"] is not None and rec["tracking_rmse_m"] > v_rms:
        v_eff = vol["voluntary_effort"]["mean"]
        cheaper = v_eff is not None and rec["voluntary_effort"] is not None and v_eff <= rec["voluntary_effort"]
        return (line + f"; but it LOSES to the wearer alone, who tracks at {_mm(v_rms)} mm"
                + (f" with no more effort ({_num(v_eff)} rad)" if cheaper else
                   f" at more effort ({_num(v_eff)} rad)") + ": on these trials the robot does not help")
    return line + ("" if rec["beats_random"] else "; no setting beats chance: this is only the lowest error")


def chance_sentences(result: dict[str, Any]) -> list[str]:
    """One sentence per gate/blend setting on whether it beats its matched random_handover."""
    out = []
    for name, t in result["tests"].items():
        v = t["vs_random_handover"]
        ci = v["effect_ci95_m"]
        ci_txt = f" (95 % CI {_mm(ci[0])} to {_mm(ci[1])} mm)" if ci else ""
        holm = "" if v.get("p_holm") is None else f" (Holm-corrected across {v.get('m_settings')} settings: " \
            f"{v['p_holm']:.3g})"
        if not v["n_pairs"] and v.get("n_forced"):
            out.append(f"{name}: no test against random hand-overs: in each of its {v['n_forced']} episodes it handed "
                       "over at most once, so the matched random schedule was its own.")
        elif v["beats_random"]:
            out.append(f"{name} beats random hand-overs at the same share and count: {_mm(v['effect_m'])} mm lower "
                       f"tracking RMS{ci_txt}, p = {v['p_value']:.3g}{holm} over {v['n_pairs']} trial x seed pairs.")
        else:
            p = "no test (no pair differs)" if v["p_value"] is None else f"p = {v['p_value']:.3g}{holm}"
            if v["p_value"] is not None and v["n_pairs"] and v["p_value"] <= 0.5 ** v["n_pairs"] * (1 + 1e-9):
                p += f" (the smallest p that {v['n_pairs']} pairs allow: a claim needs more trials or --seeds)"
            forced = (f" In {v['n_forced']} more episodes it handed over at most once: the matched random "
                      "schedule was its own, so those pairs are left out of the test."
                      if v.get("n_forced") else "")
            eff = v["effect_m"]
            how = "–" if eff is None else f"{_mm(abs(eff))} mm {'worse' if eff > 0 else 'better'}"
            out.append(f"{name} does not beat chance: random hand-overs at the same share and count track "
                       f"{how} on average{ci_txt}, {p} over {v['n_pairs']} pairs "
                       f"(threshold {ALPHA_LEVEL}): this sweep cannot tell its hand-over times from chance."
                       + forced)
    return out


def baseline_sentence(result: dict[str, Any]) -> str | None:
    """The recommended setting against ``voluntary`` and the best ``reactive`` (mean tracking RMS, effort)."""
    rec, summary = result["recommended"], result["summary"]
    if not rec:
        return None
    vol = summary.get("voluntary")
    reac = [s for s in summary.values() if s["strategy"] == "reactive" and s["tracking_rmse_m"]["mean"] is not None]
    parts = []
    if vol and vol["tracking_rmse_m"]["mean"] is not None:
        v = vol["tracking_rmse_m"]["mean"]
        word = "lower" if rec["tracking_rmse_m"] < v else "higher"
        parts.append(f"{word} tracking RMS than the wearer alone ({_mm(rec['tracking_rmse_m'])} against {_mm(v)} mm; "
                     f"effort {_num(rec['voluntary_effort'])} against {_num(vol['voluntary_effort']['mean'])} rad)")
    if reac:
        best = min(reac, key=lambda s: s["tracking_rmse_m"]["mean"])
        word = "lower" if rec["tracking_rmse_m"] < best["tracking_rmse_m"]["mean"] else "higher"
        parts.append(f"{word} than the best robot alone ({_mm(best['tracking_rmse_m']['mean'])} mm at the "
                     f"{best['percentile']:g}th percentile)")
    return f"{rec['setting']} has " + " and ".join(parts) + "." if parts else None


def tune_markdown(result: dict[str, Any]) -> str:
    """``tune.md``: the table, the Pareto set, the tests in words and the recommendation."""
    mt = result.get("multiple_testing") or {}
    head = recommendation_line(result)
    lines = ["# Closed-loop sweep (`mpcshare tune`)", "", *([f"**{head[0].upper() + head[1:]}.**", ""] if head else []),
             f"Held-out trials {result.get('trials')}, seeds {result.get('seeds')}, "
             f"{result.get('duration_s') or 'whole'} s each, wearer {result.get('wearer')}. "
             "Means over trials x seeds with 95 % bootstrap CIs. Line ratio: the tracking RMS over the straight "
             "line from `reactive` (same percentile) to `voluntary` at the same effort (below 1: better than "
             "mixing the two parties). The placebo of each pair is the mean of "
             f"{result.get('draws', '–')} random_handover draws; p is one-sided, paired, and p (Holm) corrected "
             f"by {mt.get('method', 'Holm')}'s method across the {mt.get('m', '–')} settings tested.", "",
             "| setting | n | tracking RMS [mm] (CI) | line ratio | effort [rad] (CI) | robot share | hand-overs "
             "| vs random: effect [mm] | p | p (Holm) |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, s in result["summary"].items():
        r, e = s["tracking_rmse_m"], s["voluntary_effort"]
        rci = f" ({_mm(r['ci95'][0])}–{_mm(r['ci95'][1])})" if r["ci95"] else ""
        eci = f" ({_num(e['ci95'][0])}–{_num(e['ci95'][1])})" if e["ci95"] else ""
        t = result["tests"].get(name, {}).get("vs_random_handover")
        eff, p, ph = (_mm(t["effect_m"]), _num(t["p_value"], ".3g"), _num(t.get("p_holm"), ".3g")) if t \
            else ("", "", "")
        lines.append(f"| {name} | {s['n']} | {_mm(r['mean'])}{rci} | {_num(s.get('line_ratio'), '.2f')} "
                     f"| {_num(e['mean'])}{eci} | {_num(s['reactive_share']['mean'], '.2f')} "
                     f"| {_num(s['handovers']['mean'], '.1f')} | {eff} | {p} | {ph} |")
    lines += ["", "**Pareto set** (realisable settings and baselines that no other beats on both error and "
              "effort; the upper bound and the placebo left out): "
              + ", ".join(result["pareto"]) + ".", "", "## Does the gate hand over at the right moments?", ""]
    lines += [f"- {s}" for s in chance_sentences(result)] or ["- No swept setting in this sweep."]
    rec = result["recommended"]
    if rec:
        lines += ["", "## Recommendation", "",
                  f"**{rec['setting']}**: tracking RMS {_mm(rec['tracking_rmse_m'])} mm, line ratio "
                  f"{_num(result['summary'][rec['setting']].get('line_ratio'), '.2f')}, effort "
                  f"{_num(rec['voluntary_effort'])} rad"
                  + ("." if rec["beats_random"] else "; no setting beats chance, so this is only the lowest error.")
                  + f" Criterion: {rec['criterion']}.", "", baseline_sentence(result) or "", ""]
    lines += ["![effort against error](pareto.png)", ""]
    return "\n".join(lines)


def _plot(result: dict[str, Any], path: Path) -> None:
    from matplotlib.figure import Figure

    from mpcshare.reports.style import legend_outside, strategy_colour

    fig = Figure(figsize=(8.5, 5), layout="constrained")
    ax = fig.add_subplot()
    pts = {n: (s["tracking_rmse_m"]["mean"], s["voluntary_effort"]["mean"], s["strategy"])
           for n, s in result["summary"].items()
           if s["tracking_rmse_m"]["mean"] is not None and s["voluntary_effort"]["mean"] is not None}
    for name, (err, eff, strat) in pts.items():
        edged = {"edgecolor": "k", "linewidth": 1.5} if name in result["pareto"] else {}
        marker = "x" if strat == "random_handover" else "o"
        ax.scatter(1e3 * err, eff, color=strategy_colour(strat), marker=marker, zorder=3,
                   **(edged if marker == "o" else {}))
        if name in result["pareto"] or strat in ("voluntary", "oracle_preview"):  # the rest by colour and legend
            lr = result["summary"][name].get("line_ratio")
            label = name if lr is None or strat in ("voluntary", "reactive") else f"{name} ({lr:.2f})"
            ax.annotate(label, (1e3 * err, eff), fontsize=6, xytext=(3, 3), textcoords="offset points")
    vol = [v for v in pts.values() if v[2] == "voluntary"]
    for err, eff, _ in (v for v in pts.values() if v[2] == "reactive"):
        for ve, vf, _ in vol:
            ax.plot([1e3 * ve, 1e3 * err], [vf, eff], "--", color="0.6", lw=0.8, zorder=1)
    from matplotlib.lines import Line2D

    shown = sorted({v[2] for v in pts.values()})
    legend_outside(ax, handles=[Line2D([], [], ls="", marker="x" if k == "random_handover" else "o",
                                       color=strategy_colour(k)) for k in shown], labels=shown)
    ax.set_xlabel("tracking RMS [mm]")
    ax.set_ylabel("voluntary effort [rad]")
    ax.set_title("effort against error (dashed: the voluntary-reactive line; edged and named: Pareto set, with its "
                 "line ratio)", fontsize=9)
    fig.savefig(path, dpi=120)


def write_tune(result: dict[str, Any], out: str | Path) -> None:
    """Write ``tune.json``, ``tune.md`` and ``pareto.png`` into ``out``."""
    out = Path(out)
    write_json(result, out / "tune.json", indent=1)
    with atomic_open(out / "tune.md", "w") as f:
        f.write(tune_markdown(result))
    _plot(result, out / "pareto.png")
