"""The closed-loop choice of the hand-over rule (:mod:`mpcshare.calibration.rule_choice`) in words:
the criterion (:func:`criterion_words`), why the rule won from the choice's reason record (:func:`why_words`),
the choice's progress lines, and a Markdown section of ``training.md`` (the choice, why, the sets not simulated,
the per-mode costs and every candidate's figures), or why it was skipped."""

from __future__ import annotations

from typing import Any, Mapping

from sim.task import EATING, Task

__all__ = ["CRITERION", "candidate_line", "criterion_why", "criterion_words", "pruned_line", "pruned_why", "ran_line",
           "rule_markdown", "span_words", "skipped_markdown", "why_words"]


def _sawed(stroke_mode: str | None, level: str | bool = "episode") -> str:
    """Who passes the task's criterion, in words: eating's "that saw in every cutting episode where the wearer
    alone saws" (a task with a stroke mode: sawing in that mode; without one: the criterion met); ``level``
    ``"trial"`` (the criterion's ``task_filter`` where no candidate passes every episode): over each trial's
    episodes as a whole."""
    if stroke_mode is None:
        return ("that meet the task's criterion in every trial's episodes as a whole where the wearer alone meets "
                "it (none does in every episode)" if level == "trial" else
                "that meet the task's criterion in every episode where the wearer alone meets it")
    return (f"that saw in every trial's {stroke_mode} episodes as a whole where the wearer alone saws (none saws in "
            f"every {stroke_mode} episode)" if level == "trial" else
            f"that saw in every {stroke_mode} episode where the wearer alone saws")


def criterion_words(task: Task = EATING) -> str:
    """The choice's criterion (:mod:`mpcshare.calibration.choice_criterion`) in ``task``'s words (eating's:
    :data:`CRITERION`)."""
    passed = "that saw" if task.stroke_mode is not None else "that meet it"
    which = ("that meet the task's criterion in every episode (trial) where the wearer alone meets it"
             if task.stroke_mode is None else f"{_sawed(task.stroke_mode)} (where none does, in every trial's "
             f"{task.stroke_mode} episodes as a whole)")
    return (f"among the candidates with effort <= max_effort x voluntary, those {which}, the lowest line "
            "ratio (the lowest tracking RMS where reactive itself costs >= max_effort x voluntary); if none is "
            f"within the cap, the same without the cap (the lowest line ratio of those {passed})")


#: the criterion in eating's words
CRITERION = criterion_words(EATING)


def criterion_why(reason: Mapping[str, Any]) -> str:
    """Why the criterion chose its row, from its reason record
    (:func:`mpcshare.calibration.choice_criterion.criterion`)."""
    cap = f"{reason['max_effort']:g}x voluntary"
    rms = f"{reason['tracking_rmse_m'] * 1e3:.1f} mm"
    sawed = " of those " + _sawed(reason["stroke_mode"], reason["task_filter"]) if reason["task_filter"] else ""
    if not reason["within_cap"]:
        if reason["by"] == "line_ratio":
            return f"no candidate has effort <= {cap}; the lowest line ratio ({reason['line_ratio']:.3f}){sawed}"
        return f"no candidate has effort <= {cap} and none a line ratio; the lowest tracking RMS ({rms}){sawed}"
    among = (f"among the {reason['n_within']} of {reason['n_candidates']} candidates with effort <= {cap}"
             f"{',' + sawed if sawed else ''}")
    if reason["by"] == "line_ratio":
        return f"lowest line ratio ({reason['line_ratio']:.3f}) {among}"
    cause = (f"reactive alone costs {reason['reactive_effort_vs_voluntary']:.2f}x the voluntary effort, so the line "
             "is ill-posed" if reason["ill_posed"] else "no line ratio is defined")
    return f"{cause}; the lowest tracking RMS ({rms}) {among}"


def why_words(reason: Mapping[str, Any]) -> str:
    """The choice's why (``choice["why"]``) from its reason record (:func:`mpcshare.calibration.rule_choice.
    choose_rule`'s ``reason``): the criterion's (:func:`criterion_why`), then, where one would win the criterion,
    the constant mixture the gate's rule cannot be, then, where leading the cutting modes costs more than the cap,
    that no rule leaving them to the wearer stays within it."""
    words = criterion_why(reason["criterion"])
    mix = reason.get("mixture")
    if mix:
        lr = "n/a" if mix["line_ratio"] is None else f"{mix['line_ratio']:.3f}"
        words += (f"; the constant mixture {mix['strategy']} would win the criterion (line ratio {lr} at "
                  f"{mix['effort_vs_voluntary']:.2f}x voluntary), but the gate's rule cannot be a constant mixture")
    over = reason.get("task_effort")
    if over:
        words += (f"; leading the cutting modes {over['cutting_modes']} costs the wearer "
                  f"{over['effort_vs_voluntary']:.2f}x the effort of doing the task alone (the robot leading the "
                  f"rest; from the per-mode costs), so no rule that leaves them to the wearer stays within "
                  f"{over['max_effort']:g}x here")
    return words


def candidate_line(row: Mapping[str, Any]) -> str:
    """The progress line of one simulated candidate (its wearer modes, timing, shares and figures)."""
    lr = "n/a" if row["line_ratio"] is None else f"{row['line_ratio']:.3f}"
    return (f"  gate with wearer modes {row['wearer_modes']} ({row['timing']} hand-over, robot share "
            f"{row['wearer_alpha']:g} while the wearer leads, {row['robot_alpha']:g} while it leads): "
            f"RMS {row['tracking_rmse_m'] * 1e3:.1f} mm, effort {row['effort_vs_voluntary']:.2f}x voluntary, "
            f"line ratio {lr}")


def pruned_why(effort_vs_voluntary: float, rmse_m: float) -> str:
    """Why a wearer-mode set was not simulated (:func:`mpcshare.calibration.mode_cost.prune_sets`), from the
    per-mode costs' prediction of its effort (share of the voluntary effort) and RMS [m]."""
    return (f"{effort_vs_voluntary:.2f}x the voluntary effort and {rmse_m * 1e3:.1f} mm before the hand-overs' cost, "
            "no better than the wearer alone on either")


def pruned_line(row: Mapping[str, Any]) -> str:
    """The progress line of a wearer-mode set not simulated (:func:`mpcshare.calibration.mode_cost.prune_sets`)."""
    return f"  gate with wearer modes {row['wearer_modes']}: not simulated (the per-mode costs: {row['why']})"


def ran_line(ran: int, planned: int) -> str:
    """The progress line that says ``ran`` of the ``planned`` episodes were simulated (the others repeat one)."""
    return (f"  {ran} of the {planned} episodes simulated: the others decide as one of them at every step "
            "(the same episode)")


def span_words(choice: dict[str, Any]) -> str:
    """How much of its trials the choice ran, in words: "whole trials", "first 60 s" or, per trial
    (``duration_by_trial``), "first 82 s of trial 3 and 60 s of trial 11"."""
    by_trial = choice.get("duration_by_trial")
    if by_trial and len({s for _, s in by_trial}) > 1:
        parts = ["whole" if s is None else f"{s:g} s" for _, s in by_trial]
        each = [f"{p} of trial {t}" for p, (t, _) in zip(parts, by_trial)]
        return "first " + (", ".join(each[:-1]) + " and " + each[-1] if len(each) > 1 else each[0])
    return "whole trials" if choice.get("duration_s") is None else f"first {choice['duration_s']:g} s"


def rule_markdown(choice: dict[str, Any]) -> str:
    """The choice as a Markdown section (for ``training.md``)."""
    dur = span_words(choice)
    dur = dur if dur == "whole trials" else f"the {dur}"
    lines = ["## Hand-over rule (closed-loop choice)", "",
             f"Chosen on held-out trials {choice['trials']} ({dur}, wearer {choice.get('wearer', 'default')}) in "
             f"{choice['seconds']:g} s: "
             f"the wearer leads modes {choice['wearer_modes']}, settings {choice['settings']}.", "",
             f"Why: {choice['why']}. Criterion: {choice['criterion']}.", "",
             *_predicted_markdown(choice),
             *_pruned_markdown(choice),
             *_costs_markdown(choice),
             "| run | wearer modes | hand-over | robot share while the wearer leads | robot share while it leads | "
             "RMS [mm] | effort vs voluntary | line ratio | stroke corr. |", "|---|---|---|---|---|---|---|---|---|"]
    for name in ("voluntary", "reactive"):
        m = choice[name]
        lines.append(f"| {name} | | | | | {m['tracking_rmse_m'] * 1e3:.1f} | "
                     f"{m['voluntary_effort'] / choice['voluntary']['voluntary_effort']:.2f} | 1 | {_f(m)} |")
    for m in choice.get("mixes") or []:  # comparators, not candidates
        lr = "n/a" if m["line_ratio"] is None else f"{m['line_ratio']:.3f}"
        lines.append(f"| {m['strategy']} | | | | | {m['tracking_rmse_m'] * 1e3:.1f} | {m['effort_vs_voluntary']:.2f} | "
                     f"{lr} | {_f(m)} |")
    for r in choice["candidates"]:
        lr = "n/a" if r["line_ratio"] is None else f"{r['line_ratio']:.3f}"
        lines.append(f"| gate | {r['wearer_modes']} | {r.get('timing', 'prompt')} | {r.get('wearer_alpha', 0.0):g} | "
                     f"{r.get('robot_alpha', 1.0):g} | "
                     f"{r['tracking_rmse_m'] * 1e3:.1f} | "
                     f"{r['effort_vs_voluntary']:.2f} | {lr} | {_f(r)} |")
    return "\n".join(lines) + "\n"


def skipped_markdown(skipped: str) -> str:
    """The section when the choice was skipped: ``skipped`` says why, e.g. "closed-loop choice was skipped: …"."""
    return f"## Hand-over rule\n\nThe {skipped}.\n"


def _predicted_markdown(choice: dict[str, Any]) -> list[str]:  # older choices have no prediction: no line
    p = choice.get("predicted")
    if not p:
        return []
    lr = "n/a" if p["line_ratio"] is None else f"{p['line_ratio']:.3f}"
    corr = "n/a" if p.get("saw_correlation") is None else f"{p['saw_correlation']:.2f}"
    return [f"Predicted on these trials (an evaluation sets it beside what it realises): line ratio {lr}, effort "
            f"{p['effort_vs_voluntary']:.2f}x voluntary, RMS {p['tracking_rmse_m'] * 1e3:.1f} mm, stroke corr. "
            f"{corr}, {'saws' if p.get('saws') else 'does not saw'} in every cutting episode where the wearer "
            f"alone saws.{_cv(choice.get('cross_validated'))}", ""]


def _cv(cv: dict[str, Any] | None) -> str:  # the leave-one-trial-out prediction; none with one trial
    if not cv or cv.get("line_ratio") is None:
        return ""
    return (f" Left one trial out (the rule chosen on the others, scored on it): line ratio {cv['line_ratio']:.3f}, "
            f"effort {cv['effort_vs_voluntary']:.2f}x voluntary.")


def _pruned_markdown(choice: dict[str, Any]) -> list[str]:  # the sets not simulated; none: no line
    rows = [f"{r['wearer_modes']} ({r['why']})" for r in choice.get("pruned") or []]
    return [f"Not simulated, from the per-mode costs: {'; '.join(rows)}.", ""] if rows else []


def _f(row: dict[str, Any]) -> str:
    return "n/a" if row.get("saw_correlation") is None else f"{row['saw_correlation']:.2f}"


def _costs_markdown(choice: dict[str, Any]) -> list[str]:
    """The per-mode costs table (:mod:`mpcshare.calibration.mode_cost`) and the order and cutting modes."""
    c = choice["mode_costs"]
    rows = ["What each mode costs (the controller's own mode estimate; price: squared error the wearer saves per "
            "rad of effort):", "",
            "| mode | share | wearer RMS [mm] | robot RMS [mm] | wearer effort [rad] | robot effort [rad] | "
            "price [mm²/rad] |", "|---|---|---|---|---|---|---|"]
    def f(key: str, j: int, digits: int) -> str:
        return "n/a" if c[key][j] is None else f"{c[key][j]:.{digits}f}"

    for j in range(len(c["share"])):
        rows.append(f"| {j} | {f('share', j, 2)} | {f('rms_wearer_mm', j, 1)} | {f('rms_robot_mm', j, 1)} | "
                    f"{f('effort_wearer_rad', j, 3)} | {f('effort_robot_rad', j, 3)} | "
                    f"{f('price_mm2_per_rad', j, 0)} |")
    task = choice.get("cutting_effort_vs_voluntary")
    task_line = "" if task is None else (f" Leading them, the robot leading the rest, costs the wearer {task:.2f}x the "
                                         "effort of doing the task alone (before any hand-over's cost).")
    return rows + ["", f"Modes by price: {choice['price_order']}; modes that carry the cutting: "
                   f"{choice['cutting_modes'] or 'none named'}.{task_line}", ""]
