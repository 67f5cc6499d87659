"""The two claims in words (mpcshare.reports.claims): one sentence each, and the advice."""

import math

import pytest

from mpcshare.reports.claims import claim_sentence, claim_sentences, mixture_advice


def _claim(name: str, compared: str, effect: float, p: float, made: bool, min_effect: float) -> dict:
    return {"name": name, "compared": compared, "p_value": p, "effect_size": effect,
            "ci": {"low": effect - 0.05, "high": effect + 0.05, "level": 0.95}, "min_effect": min_effect,
            "made": made}


def _seg(helps: bool, temporal: bool, n_trials: int = 15, reachable: bool = True) -> dict:
    return {"n_trials": n_trials, "reachable": reachable, "min_trials": 10, "alpha": 1e-3, "reference": "gmm",
            "claims": {
                "modes_help": _claim("modes help", "random groups of equal sizes", 0.64, 3e-5, helps,
                                     math.log(1.5)),
                "temporal_model_adds": _claim("the temporal model adds information",
                                              "the time-free gmm reference grouping (and random groups)",
                                              0.031, 1.0, temporal, math.log(1.1))}}


def test_each_claim_has_its_own_sentence_with_verdict_effect_ci_and_p():
    helps, temporal = claim_sentences(_seg(helps=True, temporal=False))
    assert helps.startswith("Modes help: made.") and "random groups of equal sizes" in helps
    assert "47 % lower" in helps and "[0.590, 0.690]" in helps and "p = 3e-05 over 15 trials" in helps
    assert temporal.startswith("The temporal model adds information: not made.")
    assert "gmm reference" in temporal and "p = 1 over 15 trials" in temporal


def test_the_mixture_advice_appears_only_where_modes_help_without_the_temporal_model():
    assert "--modes-from mixture" in mixture_advice(_seg(helps=True, temporal=False))
    assert mixture_advice(_seg(helps=True, temporal=True)) is None
    assert mixture_advice(_seg(helps=False, temporal=False)) is None


def test_too_few_trials_says_no_claim_is_possible():
    s = claim_sentence(_seg(helps=False, temporal=False, n_trials=8, reachable=False), "modes_help")
    assert "no claim possible" in s and "10 trials needed" in s


def test_an_unknown_claim_names_the_valid_ones():
    with pytest.raises(KeyError, match="modes_help.*temporal_model_adds"):
        claim_sentence(_seg(True, False), "modes_add")
