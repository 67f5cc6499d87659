"""The ``tune`` sweep's report: the chance sentences and the recommendation."""

from __future__ import annotations

from tests.mpcshare.evaluation.tune_rows import tune_row as _row


def test_chance_sentence_says_when_the_pairs_cannot_reach_significance():
    from mpcshare.reports.tune import chance_sentences

    def result(p, n):
        return {"tests": {"gate p90 b0": {"vs_random_handover": {
            "effect_ci95_m": [0.001, 0.003], "beats_random": False, "p_value": p, "n_pairs": n,
            "effect_m": 0.002, "n_forced": 0}}}}

    floor = chance_sentences(result(0.0625, 4))[0]
    assert "smallest p that 4 pairs allow" in floor and "2.0 mm worse" in floor
    assert "smallest p" not in chance_sentences(result(0.2, 4))[0]


def test_chance_sentence_says_why_a_setting_that_never_handed_over_twice_has_no_test():
    from mpcshare.reports.tune import chance_sentences

    forced = {"tests": {"gate p100 b0": {"vs_random_handover": {
        "effect_ci95_m": None, "beats_random": False, "p_value": None, "n_pairs": 0, "effect_m": None,
        "n_forced": 10}}}}
    (line,) = chance_sentences(forced)
    assert line.startswith("gate p100 b0: no test against random hand-overs") and "each of its 10 episodes" in line
    assert "0 pairs" not in line


def test_the_recommendation_says_when_it_loses_to_the_wearer_alone():
    from mpcshare.reports.tune import build_result, recommendation_line, tune_markdown

    rows = []
    for i in range(4):
        rows += [_row("voluntary", 0, i, 0.0132, effort=0.05), _row("reactive", 0, i, 0.020, effort=0.0),
                 _row("gate", 0, i, 0.0153, effort=0.045),
                 _row("random_handover", 0, i, 0.0153 + (1e-4 if i % 2 else -1e-4), "gate", effort=0.045)]
    for r in rows:
        if r["strategy"] == "voluntary":
            r["percentile"], r["beta"] = None, None
    result = build_result(rows)
    line = recommendation_line(result)
    assert line.startswith("recommended: gate p90 b0.5") and "LOSES to the wearer alone" in line
    assert "13.2 mm" in line and "15.3 mm" in line
    md = tune_markdown(result)
    assert md.index("LOSES to the wearer alone") < md.index("| setting |")  # said first, before the table
    assert "-0.0" not in md  # an effect that rounds to zero has no sign
