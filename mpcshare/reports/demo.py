"""The demo's one report: ``report.md``, a self-contained ``report.html`` and ``report.json``.

It gathers every stage written by ``mpcshare demo`` into one document, with a summary
at the top that says what the robot did and why: the analysis (where the wearer's
intent is predictable), the trained gate and predictor, and the closed-loop
comparison of strategies. The stages' own files stay in their folders
(``analysis/``, ``model/``, ``sweep/``, ``sim/``); their Markdown is included here
with links rewritten to those folders.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

from learning.atomic import atomic_open, write_json
from mpcshare.reports.claims import claim_sentences, mixture_advice
from mpcshare.reports.comparison import comparison_findings
from mpcshare.reports.headline import headline_lines, trials_words
from mpcshare.reports.html import write_html_report
from mpcshare.reports.mode_sources import mode_source_sentence
from mpcshare.reports.training import skill_lines
from sim.task import EATING, Task

__all__ = ["demo_headline", "demo_summary", "write_demo_report"]


def _pct(x: float | None) -> str:
    return "–" if x is None or not math.isfinite(x) else f"{100 * x:.0f} %"


def _num(x: Any, digits: int = 3) -> str:
    if x is None:
        return "–"
    x = float(x)
    return "inf" if math.isinf(x) else f"{x:.{digits}g}"


def _section(md: str, folder: str, drop_title: bool = True) -> str:
    """A stage's Markdown with its image links pointing into ``folder`` and headings pushed one level down."""
    md = re.sub(r"!\[([^\]]*)\]\((?![a-z]+:)([^)]+)\)", lambda m: f"![{m.group(1)}]({folder}/{m.group(2)})", md)
    lines = md.splitlines()
    if drop_title and lines and lines[0].startswith("# "):
        lines = lines[1:]
    return "\n".join("#" + ln if ln.startswith("#") else ln for ln in lines).strip() + "\n"


def demo_summary(analysis: dict[str, Any], training: dict[str, Any], comparison: dict[str, Any] | None,
                 mode_sources: dict[str, Any] | None = None, task: Task = EATING) -> list[str]:
    """The bullet points at the top of the report, in words (``mode_sources``: the HMM against the
    mixture for the controller, :func:`mpcshare.reports.mode_sources.mode_source_comparison`; ``task``: whose
    criterion the findings state)."""
    out: list[str] = []
    q = analysis["quotients"]
    seg = analysis["segmentation_test"]
    out.append(f"Without task modes the knife is hard to predict from the fork: median Lipschitz quotient "
               f"{_num(q['p50'])} (p90 {_num(q['p90'])}). Within the {analysis['modes']['n_modes']} HMM task modes "
               f"the median falls to {_num(seg['hmm_median_q'])} (random groups of equal size: "
               f"{_num(seg['random_median_q'])}; a time-free {seg['reference']} grouping: "
               f"{_num(seg['reference_median_q'])}).")
    out += claim_sentences(seg)
    advice = mixture_advice(seg)
    if advice:
        out.append(advice)
    if mode_sources:
        out.append(mode_source_sentence(mode_sources))
    t = training["training"]
    g = training["gate"]["overall"]
    out.append(f"The robot was trained to act where the within-mode quotient is below K = {_num(t['K'])} "
               f"(percentile {t['percentile']:g}); on held-out trials its gate hands "
               f"{_pct(training['voluntary_share'])} of the time to the wearer, with accuracy "
               f"{_pct(g['accuracy'])} against the quotient labels.")
    fc = training.get("forecast")
    if fc and fc.get("forecast") and None not in (fc["forecast"][-1], fc["hold"][-1]):
        m = 1e3 if str(fc.get("units", "")).startswith("m ") else 1.0
        unit = " mm" if m == 1e3 else ""
        out.append(f"The predictor forecasts the knife {fc['horizons_s'][-1]:g} s ahead: on held-out reactive steps "
                   f"its error grows from {_num(fc['forecast'][0] * m)} to {_num(fc['forecast'][-1] * m)}{unit}, "
                   f"against {_num(fc['hold'][-1] * m)}{unit} for holding its present estimate and "
                   f"{_num(fc['constant_velocity'][-1] * m)}{unit} for extrapolating it.")
    ff = training.get("fast_forecast") or {}
    if ff.get("skill"):
        sk = ff["skill"]
        out.append(f"At the control rate (100 Hz, on the fork's Kalman state) the forecast's skill against holding "
                   f"its present estimate is {_num(sk['vs_hold'][1], 2)} at {ff['horizons_s'][1]:g} s and "
                   f"{_num(sk['vs_hold'][-1], 2)} at {ff['horizons_s'][-1]:g} s (against constant velocity "
                   f"{_num(sk['vs_constant_velocity'][1], 2)} and {_num(sk['vs_constant_velocity'][-1], 2)}).")
    if comparison:
        s = comparison["strategies"]
        if "gate" in s:
            gs = s["gate"]
            out.append(f"In the closed loop (MuJoCo, {len(comparison['trials'])} held-out trial(s)) the gate let the "
                       f"robot act {_pct(gs['reactive_share'])} of the time with {gs['handovers']} hand-over(s); the "
                       f"knife tip followed the wearer's intent at {_num(gs['tracking_rmse_m'] * 1e3)} mm RMS.")
        out += comparison_findings(s, task)
    return out


def demo_headline(comparison: dict[str, Any] | None, out: Path, rule_choice: dict[str, Any] | None = None,
                  task: Task = EATING) -> list[str]:
    """The report's first lines: the four answers (:mod:`mpcshare.reports.headline`; ``rule_choice``: the
    bundle's closed-loop choice of its hand-over rule, for the task line), then the effort–error plot."""
    lines = ["## What the robot did", ""]
    answers = headline_lines(comparison["strategies"], rule_choice=rule_choice,
                             trials=trials_words(comparison["trials"], comparison.get("duration_s")),
                             rule_check=comparison.get("rule_check"), task=task) \
        if comparison else []
    if not answers:
        return lines + ["The closed loop was not run, so there is nothing to say yet about the task, sharing, "
                        "effort or keep-out.", ""]
    lines += [f"- {a}" for a in answers] + [""]
    if (out / "sim" / "effort_error.png").exists():
        lines += ["![effort against error, with the line from the wearer alone to the robot alone]"
                  "(sim/effort_error.png)", ""]
    return lines


def _effort_unit(units: str) -> tuple[str, str]:
    """``"rad (shoulder angles from neutral)"`` → ``("rad", "shoulder angles from neutral")``."""
    unit, _, meaning = str(units).partition(" (")
    return unit, meaning.rstrip(")")


def write_demo_report(out: str | Path, *, data_summary_md: str, analysis: dict[str, Any], training: dict[str, Any],
                      comparison: dict[str, Any] | None, timings_s: dict[str, float],
                      data_summary: dict[str, Any] | None = None, sweep: dict[str, Any] | None = None,
                      mode_sources: dict[str, Any] | None = None, task: Task = EATING) -> list[str]:
    """Write ``report.md``, ``report.html`` and ``report.json`` into ``out`` (``task``: whose criterion the
    answers state); returns links not inlined in the HTML."""
    out = Path(out)
    parts = ["# mpcshare demo: from demonstrations to a shared controller", "",
             *demo_headline(comparison, out, training.get("rule_choice"), task),
             "## Statistics", "",
             *[f"- {s}" for s in demo_summary(analysis, training, comparison, mode_sources, task)], "",
             "Stages and their own files: `demos.npz` and `data_summary.*` (data), `analysis/` "
             "(predictability analysis), `model/` (the trained bundle), `sweep/` (the K trade-off), "
             "`sim/` (closed-loop runs, `comparison.json`).", "",
             "## 1. Demonstrations", "", _section(data_summary_md, "."),
             "## 2. Predictability analysis", "", _section((out / "analysis" / "report.md").read_text(), "analysis"),
             "## 3. Gates and reactive predictor", ""]
    t, p = training["training"], training["predictor"]
    g = training["gate"]["overall"]
    unit, meaning = _effort_unit(training["effort_units"])
    parts += ["| quantity | value |", "|---|---|",
              f"| K (percentile {t['percentile']:g}) | {_num(t['K'])} |",
              f"| reactive share, training / held-out | {_pct(t['reactive_share_train'])} / "
              f"{_pct(training['heldout_reactive_share'])} |",
              f"| predictor RMSE on R / all held-out (standardised) | {_num(p['rmse_reactive'])} / "
              f"{_num(p['rmse_all'])} |",
              *[f"| baseline {name}: RMSE on R / all | {_num(b['rmse_reactive'])} / {_num(b['rmse_all'])} |"
                for name, b in training.get("baselines", {}).items()],
              f"| gate accuracy / F1 / Brier (held-out) | {_num(g['accuracy'])} / {_num(g['f1'])} / "
              f"{_num(g['brier'])} |",
              f"| the wearer leads / the wearer's effort [{unit}] | {_pct(training['voluntary_share'])} / "
              f"{_num(training['voluntary_effort'])} |", "",
              f"Effort: {meaning}, averaged over the steps the wearer leads." if meaning else ""]
    consts = t["gates"]["constant_modes"]
    parts += [f"Mode {m}: the gate always says {'robot' if c['value'] else 'wearer'} ({c['reason']})."
              for m, c in consts.items()]
    parts += ["", "### The forecast at the control rate", "", *skill_lines(training.get("fast_forecast"))]
    if (out / "sweep" / "sweep.md").exists():
        parts += ["", "### The trade-off between accuracy and effort (K sweep)", "",
                  _section((out / "sweep" / "sweep.md").read_text(), "sweep")]
    if comparison is not None and (out / "sim" / "comparison.md").exists():
        parts += ["## 4. Closed loop in MuJoCo", "", _section((out / "sim" / "comparison.md").read_text(), "sim")]
    parts += ["## Time per stage", "", "| stage | time [s] |", "|---|---|",
              *[f"| {k} | {v:.0f} |" for k, v in timings_s.items()], ""]
    choice = training.get("rule_choice") or {}
    pruned = choice.get("pruned") or []
    if pruned:  # what was not simulated, and why
        parts += ["The hand-over rule's choice did not simulate: " + "; ".join(
            f"the wearer leading modes {r['wearer_modes']} (the per-mode costs: {r['why']})" for r in pruned) + ".", ""]
    if choice and not choice.get("mixes"):  # the demo leaves its comparators out (commands/demo.py)
        shares = choice.get("robot_alphas") or []
        second = (f" and without its second stage (the robot's share only {shares[0]:g} while it leads)"
                  if len(shares) == 1 else "")
        parts += [f"The demo's rule choice ran without the constant mixtures beside its candidates{second}, to fit "
                  "three minutes: `mpcshare train` runs them on its choice trials, and the closed loop above runs the "
                  "mixtures on the evaluation trials.", ""]
    md = "\n".join(parts) + "\n"
    with atomic_open(out / "report.md", "w") as f:
        f.write(md)
    obj = {"format_version": 1, "data": data_summary, "analysis": analysis, "training": training,
           "sweep": sweep, "comparison": comparison, "mode_sources": mode_sources, "timings_s": timings_s}
    write_json(obj, out / "report.json", default=_jsonable)
    return write_html_report(out / "report.md", out / "report.html")


def _jsonable(x: Any) -> Any:
    if hasattr(x, "to_dict"):
        return x.to_dict()
    if hasattr(x, "tolist"):
        return x.tolist()
    raise TypeError(f"not JSON-able: {type(x).__name__}")
