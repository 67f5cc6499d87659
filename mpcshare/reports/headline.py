"""The answers a person wants first, one line each with its figure and a word of verdict.

1. **The task** — did the run meet the task's criterion (its ``criterion``, :meth:`sim.task.Task.done`;
   eating's: did the knife saw while cutting)? Where the bundle's rule was chosen in the closed loop
   (``rule_choice``) and the choice's verdict differs from this one, the line says why (the choice's trials and
   span against the evaluation's).
2. **Sharing** — did the shared strategy track the wearer's intent better than the wearer alone
   (``voluntary``), the robot alone (``reactive``) and mixing the two? Mixing is judged against the constant
   mixtures run (``mix25``, ...): it beats mixing only when none tracks better at equal or lower effort (one
   that does is named); without them, the *line ratio* stands in (below 1 beats the straight line).
3. **Effort** — how much of the wearer's effort did it save (against ``voluntary``)?
4. **Keep-out** — did the knife stay out of the wearer's body zones?
5. **The choice** (with ``rule_check``, :func:`mpcshare.evaluation.choice_check.choice_check`) — the rule's
   predicted line ratio (left one choice trial out where there is one), effort and stroke correlation beside
   the realised ones; do the line ratios differ by more than
   :data:`~mpcshare.evaluation.choice_check.LINE_RATIO_TOLERANCE`?

Read from ``comparison.json``'s ``strategies`` (name → metrics); newer keys are used when present:
``line_ratio`` (else computed here, the same definition), the clearance figures (keys with ``clearance``, in
metres, and ``driven_in`` or ``intrusion``: steps driven into a zone; without them: not measured).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from mpcshare.control.strategies import by_role
from mpcshare.line_ratio import add_line_ratios
from mpcshare.reports.rule_choice import span_words
from sim.task import EATING, Task
from sim.task.metrics import MIN_EPISODE_S

__all__ = ["MIX_RUNS", "Headline", "better_mixes", "choice_note", "episode_words",
           "headline_lines", "headlines", "lag_words", "line_ratio", "shared_strategy", "trials_words"]

EFFORT_TARGET = 0.75  # the shared strategy's effort, at most this share of the wearer's alone (docs/design.md)
_TIE = 0.02  # relative difference in tracking RMS (and effort) read as a tie
#: the constant mixtures of the two parties (the registry's ``mix`` role): what "mixing" is measured by
MIX_RUNS: tuple[str, ...] = by_role("mix")


@dataclass(frozen=True)
class Headline:
    """One answer: ``topic`` (The task, Sharing, Effort, Keep-out), its ``verdict`` word(s) and the ``text``."""

    topic: str
    verdict: str
    text: str

    def markdown(self) -> str:
        return f"**{self.topic}: {self.verdict}.** {self.text[:1].upper()}{self.text[1:]}"

    def plain(self) -> str:
        """The line for a terminal: no Markdown."""
        return f"{self.topic}: {self.verdict}. {self.text[:1].upper()}{self.text[1:]}".replace("`", "")


def _finite(x: Any) -> bool:
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x)


def shared_strategy(strategies: dict[str, dict[str, Any]]) -> str | None:
    """The run the headline calls *sharing*: the first present of the registry's ``shared`` strategies
    (:func:`mpcshare.control.strategies.by_role`, registry order), read at call time."""
    return next((s for s in by_role("shared") if s in strategies), None)


def line_ratio(strategies: dict[str, dict[str, Any]], name: str) -> float | None:
    """``name``'s tracking RMS over the voluntary–reactive line's at ``name``'s effort.

    The metrics' own ``line_ratio`` when they have one, else :func:`mpcshare.line_ratio.add_line_ratios`
    from the ``voluntary`` and ``reactive`` runs (the definition, ends included); None when an end
    of the line is missing.
    """
    m = strategies.get(name, {})
    if _finite(m.get("line_ratio")):
        return float(m["line_ratio"])
    if "voluntary" not in strategies or "reactive" not in strategies or name not in strategies:
        return None
    ratios = add_line_ratios({k: dict(strategies[k]) for k in ("voluntary", "reactive", name)})
    return ratios[name]["line_ratio"]


def lag_words(lag_s: float) -> str:
    """A lag in words: ``"60 ms late"`` (positive: the knife follows the intent), ``"20 ms ahead"``, ``"on time"``."""
    ms = round(lag_s * 1e3)
    return "on time" if ms == 0 else f"{abs(ms)} ms {'late' if ms > 0 else 'ahead'}"


def _task(name: str, m: dict[str, Any], rule_choice: dict[str, Any] | None, trials: str, task: Task) -> Headline:
    amp, corr, lag = m.get("saw_amplitude_ratio"), m.get("saw_correlation"), m.get("lag_s")
    lag_text = f" The knife's timing against the wearer's intent: {lag_words(lag)}." if _finite(lag) else ""
    if task.stroke_mode is None:  # judged by its criterion alone
        done = bool(task.done(m))
        note = choice_note(rule_choice, done, trials, task)
        return Headline("The task", "yes, done" if done else "NO, not done",
                        f"under `{name}` the task's criterion is {'met' if done else 'NOT met'} ({task.criterion})."
                        f"{lag_text}" + (f" {note}" if note else ""))
    if not (_finite(amp) and _finite(corr)):
        return Headline("The task", "not shown",
                        f"no {task.stroke_mode} in these trials, so no sawing to judge.{lag_text}")
    cut = bool(task.done(m))
    note = choice_note(rule_choice, cut, trials, task)
    return Headline("The task", "yes, it sawed" if cut else "NO, it did not saw",
                    f"under `{name}` the stroke correlates {corr:.2f} with the intended one at {amp:.2f} of its "
                    f"amplitude (sawing needs {task.criterion}).{episode_words(m, task)}{lag_text}"
                    + (f" {note}" if note else ""))


def episode_words(m: dict[str, Any], task: Task = EATING) -> str:
    """The criterion per cutting episode in words (`` It sawed in 2 of 3 cutting episodes; the worst: …``),
    from ``m["saw_by_episode"]`` (:func:`sim.task.metrics.sawing_by_episode`); "" without episodes."""
    episodes = [e for e in m.get("saw_by_episode") or () if e.get("saw_correlation") is not None]
    if not episodes:
        return ""
    done = sum(bool(task.done(e)) for e in episodes)
    worst = min(episodes, key=lambda e: (bool(task.done(e)), e["saw_correlation"]))
    amp = worst.get("saw_amplitude_ratio")
    return (f" It sawed in {done} of {len(episodes)} {task.stroke_mode} episodes (each at least "
            f"{MIN_EPISODE_S:g} s); the worst correlates {worst['saw_correlation']:.2f}"
            + (f" at {amp:.2f} of the amplitude." if amp is not None else "."))


def chosen_row(rule_choice: dict[str, Any]) -> dict[str, Any] | None:
    """The candidate ``rule_choice`` (``bundle.rule.choice``) chose: the one with its settings."""
    return next((r for r in rule_choice.get("candidates", ()) if r.get("settings") == rule_choice.get("settings")),
                None)


def choice_note(rule_choice: dict[str, Any] | None, sawed: bool, trials: str, task: Task = EATING) -> str:
    """Why the hand-over rule's choice and this evaluation disagree on ``task``'s criterion (eating's: sawing;
    "" when they agree or the choice is not recorded): the choice's figures on its trials and span against
    ``trials`` (the evaluation's, in words)."""
    if not rule_choice:
        return ""
    row = chosen_row(rule_choice)
    if row is None or (task.stroke_mode is not None and row.get("saw_correlation") is None):
        return ""
    per_trial = row.get("saws_by_trial")  # without strokes: the choice's verdict per trial (its pooled row
    if task.stroke_mode is None and not per_trial:  # holds none of the task's figures)
        return ""
    chose_sawing = bool(task.done(row)) if task.stroke_mode is not None else all(bool(x) for x in per_trial)
    if chose_sawing == sawed:
        return ""
    span = span_words(rule_choice)
    if task.stroke_mode is None:
        there = f"on trial(s) {', '.join(str(t) for t in rule_choice.get('trials', []))} ({span})"
        return (f"Training chose this hand-over rule as one that meets the task's criterion {there}; this "
                f"evaluation runs {trials}, and there it did not: the same rule, other stretches of the task."
                if chose_sawing else f"Training chose this hand-over rule although it did not meet the task's "
                f"criterion {there}; this evaluation runs {trials}, where it did.")
    there = (f"on trial(s) {', '.join(str(t) for t in rule_choice.get('trials', []))} ({span}) its stroke "
             f"correlated {row['saw_correlation']:.2f} at {row['saw_amplitude_ratio']:.2f} of the amplitude")
    return (f"Training chose this hand-over rule as one that saws because {there}; this evaluation runs {trials}, "
            "and there it did not: the same rule, other stretches of the task." if chose_sawing else
            f"Training chose this hand-over rule although it did not saw {there}; this evaluation runs {trials}, "
            "where it did.")


def _compare(mine: float, other: float) -> str:
    rel = mine / other if other > 0 else math.inf
    return "tie" if abs(rel - 1) <= _TIE else ("beat" if rel < 1 else "lost")


def better_mixes(strategies: dict[str, dict[str, Any]], name: str) -> tuple[list[str], list[str]]:
    """The constant mixtures (:data:`MIX_RUNS`) run beside ``name`` with equal or lower effort (within the
    tie, :data:`_TIE`) that track better than it (beyond the tie), and those that tie with it."""
    mine = strategies[name]
    better, tied = [], []
    for mix in MIX_RUNS:
        m = strategies.get(mix)
        if not m or not (_finite(m.get("tracking_rmse_m")) and _finite(m.get("voluntary_effort"))
                         and _finite(mine.get("voluntary_effort"))):
            continue
        if m["voluntary_effort"] > mine["voluntary_effort"] * (1 + _TIE):
            continue
        outcome = _compare(m["tracking_rmse_m"], mine["tracking_rmse_m"])
        (better if outcome == "beat" else tied if outcome == "tie" else []).append(mix)
    return better, tied


def _mixing(name: str, s: dict[str, dict[str, Any]]) -> tuple[str | None, str, str]:
    """(outcome, the party's label, a sentence): against the constant mixtures run, else the line ratio."""
    if any(mix in s for mix in MIX_RUNS):
        better, tied = better_mixes(s, name)
        if better:
            mm = [f"`{k}` {s[k]['tracking_rmse_m'] * 1e3:.1f} mm at effort {s[k]['voluntary_effort']:.3f}"
                  for k in better]
            return "lost", "mixing them (" + ", ".join(f"`{k}`" for k in better) + ")", (
                f" A constant mix tracks better at equal or lower effort: {'; '.join(mm)}.")
        if tied:
            return "tie", "mixing them (" + ", ".join(f"`{k}`" for k in tied) + ")", ""
        return "beat", "mixing them", " No constant mix tracks better at equal or lower effort."
    ratio = line_ratio(s, name)
    if ratio is None:
        return None, "", ""
    outcome = "tie" if abs(ratio - 1) <= _TIE else ("beat" if ratio < 1 else "lost")
    return outcome, "mixing them (the line)", (f" Line ratio {ratio:.2f} (tracking RMS over the straight line "
                                               "between the two at the same effort; below 1 beats it).")


def _sharing(name: str, s: dict[str, dict[str, Any]]) -> Headline:
    mine = s[name]["tracking_rmse_m"]
    parties = [(label, key) for label, key in (("the wearer alone", "voluntary"), ("the robot alone", "reactive"))
               if key in s and _finite(s[key].get("tracking_rmse_m"))]
    outcome = {label: _compare(mine, s[key]["tracking_rmse_m"]) for label, key in parties}
    mixing, label, line = _mixing(name, s)
    if mixing is not None:
        outcome[label] = mixing
    figures = "; ".join(f"{label} {s[key]['tracking_rmse_m'] * 1e3:.1f} mm" for label, key in parties)
    lost = [k for k, v in outcome.items() if v == "lost"]
    beat = [k for k, v in outcome.items() if v == "beat"]
    if not outcome:
        verdict = "not measured"
    elif lost:
        verdict = "NO, it loses to " + " and ".join(lost)
    elif len(beat) == len(outcome):
        verdict = "yes, it beats " + ", ".join(beat)
    else:
        verdict = "partly: it ties with " + " and ".join(k for k, v in outcome.items() if v == "tie")
    return Headline("Sharing", verdict, f"`{name}` tracks the wearer's intent at {mine * 1e3:.1f} mm RMS"
                    + (f" ({figures})." if figures else ".") + line)


def _effort(name: str, s: dict[str, dict[str, Any]]) -> Headline | None:
    if "voluntary" not in s or not _finite(s["voluntary"].get("voluntary_effort")):
        return None
    alone, mine = s["voluntary"]["voluntary_effort"], s[name]["voluntary_effort"]
    if not (_finite(mine) and alone > 0):
        return Headline("Effort", "not measured", "the wearer's effort alone is zero in these runs.")
    r = mine / alone
    verdict = (f"{1 - r:.0%} saved" if r <= EFFORT_TARGET else
               (f"only {1 - r:.0%} saved" if r < 1 else "NONE saved"))
    return Headline("Effort", verdict, f"under `{name}` the wearer works {r:.0%} as hard as alone "
                    f"({mine:.3f} against {alone:.3f} rad, mean shoulder angle from rest; the target is at most "
                    f"{EFFORT_TARGET:.0%}).")


def _keepout(s: dict[str, dict[str, Any]]) -> Headline:
    clear = [v for m in s.values() for k, v in m.items() if "clearance" in k and k.endswith("_m") and _finite(v)]
    driven = [v for m in s.values() for k, v in m.items()
              if ("driven_in" in k or "intrusion" in k) and _finite(v)]
    if not clear and not driven:
        return Headline("Keep-out", "not measured", "these runs have no keep-out zones around the wearer's body, "
                        "so no clearance was recorded.")
    n = int(sum(driven))
    closest = f" The knife came no closer than {min(clear) * 1e3:.0f} mm to a body zone." if clear else ""
    if n == 0:
        return Headline("Keep-out", "yes, it kept out",
                        f"the knife was driven into a body zone in 0 control steps, under every strategy.{closest}")
    return Headline("Keep-out", "NO", f"the knife was driven into a body zone in {n} control step(s).{closest}")


def headlines(strategies: dict[str, dict[str, Any]], rule_choice: dict[str, Any] | None = None,
              trials: str = "its trials", rule_check: dict[str, Any] | None = None,
              task: Task = EATING) -> list[Headline]:
    """The answers (module docstring) for the runs present; [] when no shared strategy was run.

    ``rule_choice``: the bundle's closed-loop choice of its hand-over rule (``bundle.rule.choice``),
    ``trials``: the evaluation's trials and span in words (both for :func:`choice_note`); ``rule_check``: the
    comparison's ``rule_check`` (the fifth answer; None: not shown); ``task``: whose criterion the first answer
    judges."""
    name = shared_strategy(strategies)
    if name is None:
        return []
    out = [_task(name, strategies[name], rule_choice, trials, task), _sharing(name, strategies)]
    effort = _effort(name, strategies)
    if effort is not None:
        out.append(effort)
    out.append(_keepout(strategies))
    if rule_check:
        out.append(_choice(rule_check))
    return out


def headline_lines(strategies: dict[str, dict[str, Any]], markdown: bool = True,
                   rule_choice: dict[str, Any] | None = None, trials: str = "its trials",
                   rule_check: dict[str, Any] | None = None, task: Task = EATING) -> list[str]:
    """:func:`headlines` as Markdown (bold topic and verdict) or plain text lines."""
    return [h.markdown() if markdown else h.plain()
            for h in headlines(strategies, rule_choice, trials, rule_check, task)]


def _figures(m: dict[str, Any]) -> str:
    """"line ratio 0.66, effort 0.55x the wearer alone, stroke corr. 0.89" of a check's side (n/a where None)."""
    def f(key: str, fmt: str) -> str:
        return "n/a" if m.get(key) is None else fmt.format(m[key])
    return (f"line ratio {f('line_ratio', '{:.2f}')}, effort {f('effort_vs_voluntary', '{:.2f}x')} the wearer "
            f"alone, stroke corr. {f('saw_correlation', '{:.2f}')}")


def _choice(check: dict[str, Any]) -> Headline:
    """The choice's prediction beside the evaluation (:func:`mpcshare.evaluation.choice_check.choice_check`)."""
    from mpcshare.evaluation.choice_check import LINE_RATIO_TOLERANCE

    gap = check.get("line_ratio_gap")
    verdict = ("not comparable" if gap is None else
               f"NO, off by {gap:+.2f}" if check.get("differs") else f"yes, within {LINE_RATIO_TOLERANCE:g}")
    tail = ("" if gap is None else f"; the realised line ratio differs from the predicted one by {gap:+.2f}"
            + (f", more than {LINE_RATIO_TOLERANCE:g}" if check.get("differs") else ""))
    cv = check.get("cross_validated_line_ratio")
    said = (f"on its choice trials, {_figures(check['predicted'])}" if cv is None else
            f"line ratio {cv:.2f} left one choice trial out (on the trials it was chosen on: "
            f"{_figures(check['predicted'])}, the least of its candidates' there)")
    return Headline("The choice", verdict, f"the hand-over rule chosen in training predicted {said}; "
                    f"`{check['run']}` realised {_figures(check['realised'])} here{tail}.")


def trials_words(trials: list[int], duration_s: float | None) -> str:
    """``"trial(s) 2 (first 10 s)"``: an evaluation's trials and span, for :func:`choice_note`."""
    span = "whole trials" if duration_s is None else f"first {duration_s:g} s"
    return f"trial(s) {', '.join(str(t) for t in trials)} ({span})"
