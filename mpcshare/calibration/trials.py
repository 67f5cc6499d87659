"""Which held-out trials the closed-loop rule choice runs on, and which are left to evaluate the chosen rule.

:func:`choice_trials`: half of the held-out trials (1 to 2) by default, dealt round the subjects (every subject's
first held-out trial, then every subject's second, …; the choice takes the last ``n`` of that order), so that the
choice and the evaluation draw on the same subjects where the split allows. :func:`unseen_trials`: the held-out
trials the choice did not run on; :func:`evaluation_trials`: those, then the choice's own. Pure: trial ids in,
trial ids out.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

__all__ = ["bundle_evaluation_trials", "choice_trials", "evaluation_trials", "unseen_trials"]


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
