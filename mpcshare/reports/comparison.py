"""``comparison.json``, ``comparison.md`` and ``comparison.png`` of a strategy comparison.

The Markdown states, in words, whether the comparison came out as the paper leads one
to expect — the gate cuts the wearer's effort far below ``voluntary`` while keeping
tracking error and conflicts far below ``reactive`` — and says so plainly where it
does not.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from learning.atomic import atomic_open, write_json
from mpcshare.control.strategies import by_role
from mpcshare.evaluation import Comparison
from mpcshare.reports.headline import headline_lines, lag_words, trials_words
from mpcshare.reports.style import strategy_colour, strategy_ticks
from sim.task import EATING, Task

__all__ = ["comparison_findings", "comparison_markdown", "line_sentence", "plot_effort_error",
           "write_comparison"]

_COLUMNS = (("tracking_rmse_m", "tracking RMS [mm]", 1e3, "{:.1f}"),
            ("line_ratio", "line ratio", 1.0, "{:.2f}"),
            ("tracking_p95_m", "tracking p95 [mm]", 1e3, "{:.1f}"),
            ("voluntary_effort", "effort [rad]", 1.0, "{:.3f}"),
            ("reactive_share", "robot leads [%]", 100.0, "{:.0f}"),
            ("handovers", "hand-overs", 1.0, "{:.0f}"),
            ("conflict_share", "conflicts [%]", 100.0, "{:.1f}"),
            ("limit_violations", "limit violations", 1.0, "{:.0f}"),
            ("step_p50_ms", "step p50 [ms]", 1.0, "{:.2f}"),
            ("step_p99_ms", "step p99 [ms]", 1.0, "{:.2f}"),
            ("realtime_factor", "× real time", 1.0, "{:.1f}"))
#: the task's figures (sim.task.Task.metric_keys; eating's: on time, and sawing while cutting)
_TASK_COLUMNS = (("tracking_rmse_m", "tracking RMS [mm]", 1e3, "{:.1f}"),
                 ("line_ratio", "line ratio", 1.0, "{:.2f}"),
                 ("lag_s", "lag [ms]", 1e3, "{:.0f}"),
                 ("rms_at_lag_m", "RMS at that lag [mm]", 1e3, "{:.1f}"),
                 ("saw_amplitude_ratio", "sawing amplitude", 1.0, "{:.2f}"),
                 ("saw_correlation", "sawing correlation", 1.0, "{:.2f}"),
                 ("stroke_share", "strokes executed [%]", 100.0, "{:.0f}"),
                 ("pickup_rms_m", "RMS while the wearer picks up [mm]", 1e3, "{:.1f}"),
                 ("pickup_error_share", "pick-ups' share of the squared error [%]", 100.0, "{:.0f}"))
#: how close the knife came to the wearer (sim.keepout_metrics)
_KEEPOUT_COLUMNS = (("keepout_min_clearance_m", "min clearance [mm]", 1e3, "{:.1f}"),
                    ("keepout_time_inside_s", "time inside [s]", 1.0, "{:.2f}"),
                    ("keepout_max_depth_m", "deepest [mm]", 1e3, "{:.1f}"),
                    ("keepout_steps_driven_in", "steps driven in", 1.0, "{:.0f}"),
                    ("keepout_inside_zone_moving_s", "inside, the body part coming [s]", 1.0, "{:.2f}"),
                    ("keepout_near_speed_mps", "speed toward the person within 5 cm [m/s]", 1.0, "{:.3f}"))


def _ratio(a: float, b: float) -> float:
    return float(a / b) if b > 0 else float("inf")


def comparison_findings(strategies: dict[str, dict[str, float]], task: Task = EATING) -> list[str]:
    """Sentences comparing the gate with the baselines (only for the runs present)."""
    s = strategies
    out: list[str] = []
    if "gate" in s and "voluntary" in s:
        r = _ratio(s["gate"]["voluntary_effort"], s["voluntary"]["voluntary_effort"])
        verdict = "far below" if r <= 0.5 else ("below" if r < 1 else "NOT below")
        out.append(f"Effort: the gate needs {r:.0%} of the wearer's effort under `voluntary` ({verdict}).")
    if "gate" in s and "reactive" in s:
        g, r = s["gate"], s["reactive"]
        e = _ratio(g["tracking_rmse_m"], r["tracking_rmse_m"])
        verdict = "below" if e < 0.98 else ("about equal" if e <= 1.02 else "NOT below")
        out.append(f"Accuracy: the gate's tracking RMS is {e:.0%} of `reactive`'s ({verdict}); the wearer and "
                   f"the robot push the tip in opposite directions {g['conflict_share']:.1%} of the time under the "
                   f"gate against {r['conflict_share']:.1%} under `reactive` (where the wearer's push is ignored).")
    line = line_sentence(s)
    if line:
        out.append(line)
    if "gate" in s and "gate_mpc" in s:
        n, g = s["gate"], s["gate_mpc"]
        rel = _ratio(g["tracking_rmse_m"], n["tracking_rmse_m"])
        effect = ("helps" if rel < 0.98 else "hurts") if abs(rel - 1) > 0.02 else "makes no measurable difference"
        out.append(f"MPC: with the MPC (its preview the fused forecast) the gate tracks at "
                   f"{g['tracking_rmse_m'] * 1e3:.1f} mm RMS, without it at {n['tracking_rmse_m'] * 1e3:.1f} mm: the "
                   f"MPC {effect}; its cost is a step p99 of {g['step_p99_ms']:.2f} ms against "
                   f"{n['step_p99_ms']:.2f} ms.")
    if "oracle_preview" in s and "reactive" in s:
        o, r = s["oracle_preview"], s["reactive"]
        out.append(f"Upper bound: given the wearer's true intent as its preview (not realisable), the arm tracks "
                   f"at {o['tracking_rmse_m'] * 1e3:.1f} mm RMS; `reactive` is at "
                   f"{_ratio(r['tracking_rmse_m'], o['tracking_rmse_m']):.1f}× that: the rest is the predictor's.")
    if "gate" in s and "random_handover" in s:
        g, r = s["gate"]["tracking_rmse_m"], s["random_handover"]["tracking_rmse_m"]
        word = "better than" if g < 0.98 * r else ("no better than" if g <= 1.02 * r else "WORSE than")
        out.append(f"Timing: with the same share of robot control and the same hand-overs at random times "
                   f"(`random_handover`), the arm tracks at {r * 1e3:.1f} mm RMS against the gate's {g * 1e3:.1f} mm: "
                   f"the gate's hand-over times are {word} chance on these trials (`mpcshare tune` tests it).")
    if "oracle_handover" in s:
        out.append(f"Upper bound: the best closed-loop replay of the hand-over schedules that minimise the error "
                   f"(from `voluntary` and `reactive`, with the same dwell, at several costs per hand-over; the "
                   f"wearer or the robot alone included; uses the future) tracks at "
                   f"{s['oracle_handover']['tracking_rmse_m'] * 1e3:.1f} mm RMS with the robot leading "
                   f"{s['oracle_handover']['reactive_share']:.0%} of the time.")
    if "gate" in s and (task.stroke_mode is None or s["gate"].get("saw_amplitude_ratio") is not None):
        out.append(task_sentence("gate", s["gate"], task))
    bad = [k for k, m in s.items() if m["limit_violations"]]
    out.append("Limits: no violation at the physics rate in any run." if not bad else
               f"Limits: VIOLATED at the physics rate in {', '.join(bad)}.")
    return out


def line_sentence(strategies: dict[str, dict[str, Any]]) -> str | None:
    """The line ratio of the shared runs in words (:mod:`mpcshare.line_ratio`); None without the parties."""
    shared = {k: m["line_ratio"] for k, m in strategies.items()
              if k not in ("voluntary", "reactive") and m.get("line_ratio") is not None
              and not k.startswith("oracle")}
    if not shared:
        return None
    parts = ", ".join(f"`{k}` {v:.2f}" for k, v in shared.items())
    better = [k for k, v in shared.items() if v < 1.0]
    v, r = strategies["voluntary"]["tracking_rmse_m"], strategies["reactive"]["tracking_rmse_m"]
    alone = (f" The wearer alone tracks better than the robot alone ({v * 1e3:.1f} against {r * 1e3:.1f} mm)."
             if v < r else "")
    return (f"Line: tracking RMS over the straight line from `reactive` to `voluntary` at the same effort (below 1: "
            f"better than mixing the two parties): {parts}; "
            + (f"below the line: {', '.join(f'`{k}`' for k in better)}." if better else
               "NONE is below the straight line between the wearer and the robot.") + alone)


def task_sentence(name: str, m: dict[str, Any], task: Task = EATING) -> str:
    """Did the knife do ``task`` under ``name``: its lag, and whether it met the task's criterion (eating's:
    whether it sawed while cutting)."""
    amp, corr = m.get("saw_amplitude_ratio"), m.get("saw_correlation")
    lag = m.get("lag_s")
    lag_text = "" if lag is None else f"the knife's timing against the wearer's intent: {lag_words(lag)}; "
    if task.stroke_mode is None:
        return (f"Task under `{name}`: {lag_text}the task's criterion ({task.criterion}) is "
                f"{'met' if task.done(m) else 'NOT met'}.")
    if amp is None or corr is None:
        return f"Task under `{name}`: {lag_text}no {task.stroke_mode} in these trials."
    share = m.get("stroke_share")
    strokes = "" if share is None else f", {share:.0%} of the intended strokes executed"
    return (f"Task under `{name}`: {lag_text}while {task.stroke_mode}, the stroke's amplitude is {amp:.2f} of the "
            f"intended and its correlation with it {corr:.2f}{strokes}: the knife "
            f"{'SAWED' if task.done(m) else 'did NOT saw'} (sawing needs {task.criterion}).")


def _table(strategies: dict[str, dict[str, Any]], columns: tuple) -> list[str]:
    head = "| run | " + " | ".join(c[1] for c in columns) + " |"
    rule = "|---|" + "---|" * len(columns)
    rows = []
    for name, m in strategies.items():
        cells = [fmt.format(m[key] * scale) if m.get(key) is not None and np.isfinite(m[key]) else "–"
                 for key, _, scale, fmt in columns]
        rows.append(f"| {name} | " + " | ".join(cells) + " |")
    return [head, rule, *rows]


def _task_table(comp: Comparison, task: Task) -> list[str]:
    """The task's figures of :data:`_TASK_COLUMNS` that ``task`` has (its ``metric_keys``), with
    the words of its stroke band; [] without a lag."""
    if not any(m.get("lag_s") is not None for m in comp.strategies.values()):
        return []
    columns = tuple(c for c in _TASK_COLUMNS if c[0] in ("tracking_rmse_m", "line_ratio") or c[0] in task.metric_keys)
    if task.stroke_mode is None or task.stroke_band_hz is None:
        words = f"The task ({task.name}; done when {task.criterion}): its figures:"
    else:
        low, high = task.stroke_band_hz
        words = ("The task: the knife's lag behind the wearer's intent (the time shift that minimises the RMS) "
                 f"and, while {task.stroke_mode}, its motion in the stroke band ({low:g}–{high:g} Hz) against the "
                 "intended stroke:")
    return [words, "", *_table(comp.strategies, columns), ""]


def _who_leads_table(comp: Comparison) -> list[str]:
    """Per mode: the share of steps the wearer leads in the closed loop under each of the registry's ``shared``
    strategies that ran (:func:`mpcshare.control.strategies.by_role`, registry order, read at call time) beside
    the bundle's held-out voluntary share of that mode (what the gate said offline)."""
    runs = [r for r in by_role("shared") if (comp.strategies.get(r) or {}).get("wearer_share_by_mode")]
    if not runs:
        return []
    offline = comp.offline_wearer_share_by_mode or {}
    modes = sorted({k for r in runs for k in comp.strategies[r]["wearer_share_by_mode"]})
    head = "| mode | " + " | ".join(f"wearer leads, `{r}`" for r in runs) + " | offline voluntary share |"
    rows = [head, "|---|" + "---|" * (len(runs) + 1)]
    for mode in modes:
        cells = [comp.strategies[r]["wearer_share_by_mode"].get(mode) for r in runs] + [offline.get(mode)]
        rows.append(f"| {mode} | " + " | ".join("–" if c is None else f"{c:.0%}" for c in cells) + " |")
    return ["Who leads, per mode of the data: the closed loop's share of steps with α < 0.5, beside the share "
            "the gate hands to the wearer on the bundle's held-out trials:", "", *rows, ""]


def comparison_markdown(comp: Comparison, plot_name: str | None = "comparison.png",
                        trial_plot: str | None = None, effort_plot: str | None = None, task: Task = EATING) -> str:
    """The Markdown section: the four headline answers (``task``'s criterion the first), the effort–error plot,
    then the tables, findings and plots."""
    span = "whole trials" if comp.duration_s is None else f"the first {comp.duration_s:g} s of each"
    who = (comp.wearer or {}).get("preset") or ("custom settings" if comp.wearer else None)
    wearer = f" Simulated wearer: {who}." if who else ""
    lines = [*[f"- {h}" for h in headline_lines(comp.strategies, trials=trials_words(comp.trials, comp.duration_s),
                                                 rule_check=comp.rule_check, task=task)], ""]
    if effort_plot:
        lines += [f"![effort against error, with the line from the wearer alone to the robot alone]({effort_plot})",
                  ""]
    lines += ["### The figures", "", f"Held-out trials {comp.trials}, {span}; pooled over trials.{wearer}", "",
              *_table(comp.strategies, _COLUMNS), ""]
    lines += _task_table(comp, task)
    if any(m.get("keepout_min_clearance_m") is not None for m in comp.strategies.values()):
        what = f"scenario `{comp.scenario}`" if comp.scenario else "normal runs"
        guard = "on" if comp.keepout else "OFF"
        lines += [f"The person first ({what}, keep-out {guard}): the knife's blade (tip to heel) against the "
                  "wearer's hand, forearm, head and torso (the body parts, without the controller's margin):", "",
                  *_table(comp.strategies, _KEEPOUT_COLUMNS), ""]
    lines += _who_leads_table(comp)
    lines += [*[f"- {s}" for s in comparison_findings(comp.strategies, task)], ""]
    if plot_name:
        lines += [f"![strategies]({plot_name})", ""]
    if trial_plot:
        lines += ["A trial: the knife tip against the wearer's intent, α and β, the shoulder:", "",
                  f"![a trial]({trial_plot})", ""]
    if comp.video:
        lines += [f"The gate on trial {comp.trials[0]} (offscreen MuJoCo render):", "",
                  f"![the gate]({comp.video})", ""]
    return "\n".join(lines)


def _plot(comp: Comparison, path: Path) -> None:
    """Horizontal bars per strategy, one panel per figure: the names read on one axis, never overlapping."""
    names = list(comp.strategies)
    keys = (("tracking_rmse_m", "tracking RMS [mm]", 1e3), ("line_ratio", "line ratio (< 1: beats mixing)", 1.0),
            ("voluntary_effort", "effort: mean ‖θ‖ [rad]", 1.0), ("conflict_share", "conflicts [%]", 100.0),
            ("reactive_share", "robot leads [%]", 100.0))
    fig = Figure(figsize=(13, 1.2 + 0.32 * len(names)), constrained_layout=True)
    axes = fig.subplots(1, len(keys), sharey=True)
    for ax, (key, label, scale) in zip(axes, keys):
        vals = [np.nan if comp.strategies[n].get(key) is None else comp.strategies[n][key] * scale for n in names]
        ax.barh(range(len(names)), vals, color=[strategy_colour(n) for n in names])
        if key == "line_ratio":
            ax.axvline(1.0, color="0.4", ls="--", lw=0.8)
        ax.set_title(label, fontsize=9)
        ax.tick_params(axis="x", labelsize=8)
    strategy_ticks(axes[0], names)
    axes[0].invert_yaxis()  # the first strategy on top, as in the tables
    fig.savefig(path, dpi=110)


def plot_effort_error(strategies: dict[str, dict[str, Any]], path: str | Path) -> Path:
    """Each run at (effort, tracking RMS), with the straight line from the wearer alone to the robot alone:
    a run beats another when it lies lower and to the left of it. Sized to sit under the report's
    headline lines within one laptop screen (990 × 385 px at 110 dpi), the legend beside the axes."""
    fig = Figure(figsize=(9.0, 3.5), constrained_layout=True)
    ax = fig.subplots()
    pts = {n: (m["voluntary_effort"], m["tracking_rmse_m"] * 1e3) for n, m in strategies.items()
           if m.get("voluntary_effort") is not None and m.get("tracking_rmse_m") is not None
           and np.isfinite([m["voluntary_effort"], m["tracking_rmse_m"]]).all()}
    if "voluntary" in pts and "reactive" in pts:
        (x0, y0), (x1, y1) = pts["reactive"], pts["voluntary"]
        ax.plot([x0, x1], [y0, y1], "--", color="0.5", lw=1.2, zorder=1,
                label="robot alone → wearer alone")
    for n, (x, y) in pts.items():  # the upper bounds (oracle_*): small diamonds on top, a run beneath still shows
        bound = n.startswith("oracle")
        ax.scatter([x], [y], s=26 if bound else 46, marker="D" if bound else "o", color=strategy_colour(n),
                   edgecolor="k", linewidth=0.6, zorder=4 if bound else 3, label=n.replace("_", " "))
    ax.set_xlabel("the wearer's effort: mean ‖θ‖ [rad]")
    ax.set_ylabel("tracking RMS [mm]")
    ax.set_title("effort against error: lower left is better", fontsize=9)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False,
              ncols=2 if len(pts) > 9 else 1)
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path


def write_comparison(comp: Comparison, out: str | Path, cutting: np.ndarray | None = None,
                     task: Task = EATING) -> dict[str, Any]:
    """Write comparison.json, comparison.md and comparison.png into ``out``; returns the JSON object.

    ``cutting``: bool per sample of the first trial, where the demonstration is in ``task``'s stroke mode (the
    trial plot's close-up of the strokes is taken there); ``task``: whose criterion and figures the text states."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    obj = comp.to_dict()
    write_json(obj, out / "comparison.json")
    _plot(comp, out / "comparison.png")
    plot_effort_error(comp.strategies, out / "effort_error.png")
    trial_plot = None
    shown = "gate" if comp.run_files.get("gate") else next((k for k, v in comp.run_files.items() if v), None)
    if shown is not None:
        from mpcshare.reports.episode_plot import plot_episode
        from sim.episode import Episode

        episode = Episode.load(out / comp.run_files[shown][0])
        trial_plot = "trial.png"
        plot_episode(episode, out / trial_plot, title=f"{shown}, trial {comp.trials[0]}",
                     cutting=None if cutting is None else np.asarray(cutting)[:len(episode.t)],
                     band=task.stroke_band_hz)
    with atomic_open(out / "comparison.md", "w") as f:
        f.write("# Closed-loop comparison of strategies\n\n"
                + comparison_markdown(comp, trial_plot=trial_plot, effort_plot="effort_error.png", task=task))
    return obj
