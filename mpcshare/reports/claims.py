"""The analysis's two claims in words, one sentence each, and the advice that follows from them.

Works on the ``segmentation_test`` dict of ``report.json`` (``learning.analysis.report.SegmentationTest.to_dict``),
so that the analysis report, the command line's headline and the demo's summary say the same:

1. "modes help": HMM modes against random groups of equal sizes (the paper's test);
2. "the temporal model adds information": HMM modes against the time-free reference grouping.

An effect e (median over trials of ln(reference / HMM per-trial median q)) is also given as the
per-cent change of q, 100·(1 − e^−e).
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["CLAIM_KEYS", "claim_sentence", "claim_sentences", "mixture_advice"]

CLAIM_KEYS = ("modes_help", "temporal_model_adds")


def _p(p: float) -> str:
    return "p < 1e-300" if p <= 0 else f"p = {p:.2g}"


def _pct(effect: float) -> str:
    pct = 100.0 * (1.0 - math.exp(-effect))
    return f"{abs(pct):.0f} % {'lower' if pct >= 0 else 'higher'}"


def claim_sentence(seg: dict[str, Any], key: str) -> str:
    """One sentence: the claim, whether it is made, against what, with effect, CI and p over trials.

    Raises:
        KeyError: ``key`` is not one of :data:`CLAIM_KEYS` (the message names them).
    """
    if key not in CLAIM_KEYS:
        raise KeyError(f"claim must be one of {CLAIM_KEYS}, got {key!r}")
    c = seg["claims"][key]
    n = seg["n_trials"]
    if not seg["reachable"]:
        verdict = (f"no claim possible (with {n} trials the smallest p is {2.0 ** -n:.2g}; "
                   f"{seg['min_trials']} trials needed)")
    else:
        verdict = "made" if c["made"] else "not made"
    ci = c["ci"]
    return (f"{c['name'].capitalize()}: {verdict}. Against {c['compared']}, the median quotient of a trial "
            f"within the HMM modes is {_pct(c['effect_size'])} (ln ratio {c['effect_size']:.3f}, "
            f"{100 * ci['level']:.0f} % bootstrap CI [{ci['low']:.3f}, {ci['high']:.3f}]; {_p(c['p_value'])} over {n} "
            f"trials, claimed below {seg['alpha']:g} with an effect above {c['min_effect']:.3f}).")


def claim_sentences(seg: dict[str, Any]) -> list[str]:
    """Both claims' sentences, "modes help" first."""
    return [claim_sentence(seg, k) for k in CLAIM_KEYS]


def mixture_advice(seg: dict[str, Any]) -> str | None:
    """Where modes help but the temporal model adds nothing: the controller could use the
    time-free grouping (``mpcshare train --modes-from mixture``); else None."""
    c = seg["claims"]
    if not (c["modes_help"]["made"] and not c["temporal_model_adds"]["made"]):
        return None
    return ("Grouping the data into modes helps, but a time-free grouping of the same observations "
            f"({seg['reference']}) does as well as the HMM: the controller could use the time-free grouping "
            "(`mpcshare train --modes-from mixture`), whose online mode filter then uses each observation alone.")
