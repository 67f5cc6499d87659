"""The calibrated rule: checked field by field, as JSON and back, moved out of an old bundle's metrics."""

from __future__ import annotations

import json
import math

import pytest

from mpcshare.bundle.rule import (
    RULE_VERSION,
    CalibratedRule,
    rule_from_json,
    rule_from_metrics,
    rule_to_json,
    skipped_rule,
)


def test_json_round_trip_keeps_the_settings_and_the_record():
    rule = CalibratedRule("gate", {"wearer_modes": [0, 2], "lead_s": 1.5, "robot_alphas": (0.5, 1)},
                          {"why": "lowest line ratio", "candidates": [{"rms": 0.01}]})
    assert rule.settings == {"wearer_modes": (0, 2), "lead_s": 1.5, "robot_alphas": (0.5, 1)}
    text = json.dumps(rule_to_json(rule))
    assert rule_from_json(json.loads(text)) == rule and rule.version == RULE_VERSION
    assert rule_from_json(rule_to_json(None)) is None


@pytest.mark.parametrize("kwargs,match", [
    ({"strategy": "", "settings": {}}, "rule strategy must be"),
    ({"strategy": "gate", "settings": {"lead_s": math.inf}}, "'lead_s' must be a finite number"),
    ({"strategy": "gate", "settings": {"lead_s": True}}, "'lead_s' must be a finite number"),
    ({"strategy": "gate", "settings": [1]}, "rule settings must map"),
    ({"strategy": "gate", "settings": {}, "version": RULE_VERSION + 1}, f"rule version {RULE_VERSION + 1}"),
    ({"strategy": "gate", "settings": {}, "skipped": ""}, "rule skipped must be null or why"),
    ({"strategy": "gate", "settings": {"lead_s": 1.0}, "skipped": "no knife"}, "a skipped rule has no settings"),
])
def test_a_wrong_field_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        CalibratedRule(**kwargs)


def test_an_old_bundles_metrics_give_up_their_rule():
    metrics = {"gate": {}, "rule_settings": {"wearer_modes": [1]}, "rule_choice": {"why": "w"}}
    assert rule_from_metrics(metrics) == CalibratedRule("gate", {"wearer_modes": [1]}, {"why": "w"}, 1)
    assert metrics == {"gate": {}}
    assert rule_from_metrics({"gate": {}}) is None


def test_a_skipped_rule_says_why_and_round_trips_and_a_version_1_rule_reads_as_not_skipped():
    rule = skipped_rule("closed-loop choice was skipped: no knife")
    assert rule == CalibratedRule("gate", {}, {}, RULE_VERSION, "closed-loop choice was skipped: no knife")
    assert rule_from_json(json.loads(json.dumps(rule_to_json(rule)))) == rule
    old = {"rule": {"version": 1, "strategy": "gate", "settings": {"lead_s": 1.5}, "choice": {"why": "w"}}}
    assert rule_from_json(old) == CalibratedRule("gate", {"lead_s": 1.5}, {"why": "w"}, 1) and \
        rule_from_json(old).skipped is None


def test_an_old_bundles_metrics_give_up_why_the_choice_was_skipped():
    metrics = {"gate": {}, "rule_choice_skipped": "closed-loop choice was skipped: no knife"}
    assert rule_from_metrics(metrics) == skipped_rule("closed-loop choice was skipped: no knife")
    assert metrics == {"gate": {}}
