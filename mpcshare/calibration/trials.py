"""Which held-out trials the closed-loop rule choice runs on, and which are left to evaluate the chosen rule.

:func:`choice_trials`: half of the held-out trials (1 to 2) by default, dealt round the subjects (every subject's
first held-out trial, then every subject's second, …; the choice takes the last ``n`` of that order), so that the
choice and the evaluation draw on the same subjects where the split allows. :func:`unseen_trials`: the held-out
trials the choice did not run on; :func:`evaluation_trials`: those, then the choice's own. Pure: trial ids in,
trial ids out. :func:`choice_duration`: how long the choice simulates its trials, so that each shows the task's
stroke where it has one (from the trials' mode labels); :func:`choice_seconds`: the same per trial.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["STROKE_SEEN_S", "STROKE_STRETCH", "bundle_evaluation_trials", "choice_duration", "choice_seconds",
           "choice_trials", "evaluation_trials", "unseen_trials"]

#: seconds of the task's stroke every choice trial must show (or all it has): a few strokes at 0.8–3 Hz, enough
#: for the stroke-band correlation that says whether a candidate saws
STROKE_SEEN_S = 3.0
#: the choice runs at most this many times the seconds it was given, to show the stroke
STROKE_STRETCH = 2.0


def choice_trials(heldout: Sequence[int], n_trials: int | None = None,
                  subjects: Mapping[int, Any] | None = None) -> list[int]:
    """The held-out trials the choice runs on: ``n_trials`` of them (default: half, 1 to 2); the others are left
    for evaluating the chosen rule (:func:`evaluation_trials`). The held-out trials are dealt round the subjects
    (``subjects``: trial → subject; None or one subject: the trials' order), each subject's in order, and the
    choice takes the last ``n_trials`` of that order: so the choice and the evaluation draw on the same subjects
    where the held-out trials allow it, not the choice on one subject and the evaluation on another."""
    held = _dealt([int(t) for t in heldout], subjects)
    n = n_trials or min(2, max(1, len(held) // 2))
    return held[-n:]


def unseen_trials(heldout: Sequence[int], chosen_on: Sequence[int]) -> list[int]:
    """The held-out trials the choice did not run on (``chosen_on``), in the held-out order: the only trials on
    which a chosen rule's figure is not biased by its choice."""
    used = {int(t) for t in chosen_on}
    return [int(t) for t in heldout if int(t) not in used]


def evaluation_trials(heldout: Sequence[int], chosen_on: Sequence[int]) -> list[int]:
    """The held-out trials to evaluate a chosen rule on: :func:`unseen_trials`, then the choice's own (an
    evaluation that asks for more trials gets them last)."""
    used = {int(t) for t in chosen_on}
    return unseen_trials(heldout, chosen_on) + [int(t) for t in heldout if int(t) in used]


def bundle_evaluation_trials(bundle: Any) -> list[int]:
    """:func:`evaluation_trials` of ``bundle``'s held-out trials and its rule's choice trials (none without a rule
    or a choice)."""
    rule = getattr(bundle, "rule", None)
    chosen_on = [] if rule is None else list((rule.choice or {}).get("trials") or [])
    return evaluation_trials(bundle.heldout_trials, chosen_on)


def choice_duration(trials: Sequence[Any], duration_s: float | None, rate_hz: float, stroke_label: int | None,
                    stroke_seen_s: float = STROKE_SEEN_S, stretch: float = STROKE_STRETCH) -> float | None:
    """The seconds the choice simulates of each of its ``trials`` (:class:`learning.data.Trial`, sampled at
    ``rate_hz``): ``duration_s``, or longer where a trial's first ``duration_s`` show less than ``stroke_seen_s``
    of the stroke (mode label ``stroke_label``) than the trial has: then until every trial has shown that much (or
    all of its stroke), rounded up to a whole second, at most ``stretch`` × ``duration_s``. A choice trial whose
    window holds no stroke cannot tell a candidate that saws from one that does not (the sawing criterion skips
    it). None (whole trials), no stroke label or no labels: ``duration_s`` unchanged. ValueError for a rate or a
    duration that is not positive, or a stretch below 1."""
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"rate_hz must be a positive number, got {rate_hz!r}")
    if duration_s is None or stroke_label is None:
        return duration_s
    if not duration_s > 0:
        raise ValueError(f"duration_s must be > 0 or None, got {duration_s!r}")
    if not stretch >= 1.0:
        raise ValueError(f"stretch must be >= 1, got {stretch!r}")
    need = float(duration_s)
    for trial in trials:
        if trial.mode is None:
            continue
        stroke = np.cumsum(np.asarray(trial.mode) == int(stroke_label))
        if not stroke.size:
            continue
        want = min(stroke_seen_s * rate_hz, float(stroke[-1]))  # samples of stroke the window should hold
        window = min(int(round(duration_s * rate_hz)), stroke.size)
        if want > 0 and stroke[window - 1] < want:
            end = int(np.searchsorted(stroke, want)) + 1  # samples up to the one that completes it
            need = max(need, float(math.ceil(end / rate_hz)))
    return min(need, stretch * float(duration_s))


def choice_seconds(trials: Sequence[Any], duration_s: float | None, rate_hz: float, stroke_label: int | None,
                   stroke_seen_s: float = STROKE_SEEN_S, stretch: float = STROKE_STRETCH) -> dict[int, float | None]:
    """Each of ``trials``' own choice window [s], by trial id: :func:`choice_duration` of that trial alone, so
    that only a trial whose first ``duration_s`` lack the stroke runs longer. Errors: :func:`choice_duration`'s."""
    return {int(tr.trial_id): choice_duration([tr], duration_s, rate_hz, stroke_label, stroke_seen_s, stretch)
            for tr in trials}


def _dealt(held: list[int], subjects: Mapping[int, Any] | None) -> list[int]:
    """``held`` dealt round the subjects: every subject's first trial (subjects in order of first appearance),
    then every subject's second, and so on."""
    if not subjects:
        return held
    groups: dict[Any, list[int]] = {}
    for t in held:
        groups.setdefault(subjects.get(t), []).append(t)
    rounds = max(len(g) for g in groups.values())
    return [g[k] for k in range(rounds) for g in groups.values() if k < len(g)]
