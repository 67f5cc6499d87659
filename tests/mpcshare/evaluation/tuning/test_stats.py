"""The sweep's statistics (mpcshare.evaluation.tuning.stats): the paired one-sided test, Holm, the placebo, Pareto."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats as st

from mpcshare.evaluation.tuning.stats import gate_vs_random, pareto, recommend, summarise
from tests.mpcshare.evaluation.tune_rows import tune_row as _row


def test_gate_against_random_is_a_paired_one_sided_test():
    rng = np.random.default_rng(1)
    base = rng.uniform(0.01, 0.03, 8)  # per (trial, seed): a hard trial is hard for both
    gate_err = base
    rand_err = base + np.array([2, 1, 3, 0.5, 2, 1.5, -0.2, 1]) * 1e-3
    rows = []
    for i, (g, r) in enumerate(zip(gate_err, rand_err)):
        rows += [_row("gate", i % 2, i // 2, g), _row("random_handover", i % 2, i // 2, r, "gate")]
    rows = [rows[i] for i in rng.permutation(len(rows))]  # the order of rows must not matter
    test = gate_vs_random(rows)["gate p90 b0.5"]["vs_random_handover"]
    expected = st.wilcoxon(rand_err - gate_err, alternative="greater")
    assert test["p_value"] == pytest.approx(expected.pvalue) and test["n_pairs"] == 8
    assert test["n_forced"] == 0
    assert test["p_value"] < 0.05 and test["beats_random"]
    assert test["effect_m"] == pytest.approx(np.mean(rand_err - gate_err))
    lo, hi = test["effect_ci95_m"]
    assert lo < test["effect_m"] < hi
    # unpaired, the spread between trials would hide the effect: the pairing is what is tested
    assert st.mannwhitneyu(rand_err, gate_err, alternative="greater").pvalue > 0.05
    worse = [dict(r, tracking_rmse_m=r["tracking_rmse_m"] + (3e-3 if r["strategy"] == "gate" else 0))
             for r in rows]
    t2 = gate_vs_random(worse)["gate p90 b0.5"]["vs_random_handover"]
    assert t2["p_value"] > 0.5 and not t2["beats_random"]
    rec = recommend(summarise(worse), gate_vs_random(worse))
    assert rec["setting"] == "gate p90 b0.5" and rec["beats_random"] is False and "criterion" in rec


def test_pairs_whose_setting_handed_over_at_most_once_are_left_out_of_the_test():
    """Their matched random schedule is the setting's own (same steps on, hand-overs and first state): a replay a
    hair apart, which must not make a claim however consistently it leans."""
    rng = np.random.default_rng(3)
    gate_err = rng.uniform(0.01, 0.03, 12)
    rows = []
    for i, g in enumerate(gate_err):  # 10 forced pairs a hair apart, all leaning the gate's way; 2 informative
        forced = i < 10
        rows += [_row("gate", i % 2, i // 2, g, handovers=i % 2 if forced else 4),
                 _row("random_handover", i % 2, i // 2, g + (1e-12 if forced else 2e-3), "gate")]
    t = gate_vs_random(rows)["gate p90 b0.5"]["vs_random_handover"]
    assert t["n_forced"] == 10 and t["n_pairs"] == 2
    assert t["p_value"] == pytest.approx(0.25) and not t["beats_random"]  # two pairs allow p = 1/4 at best
    with_them = st.wilcoxon(np.r_[np.full(10, 1e-12), np.full(2, 2e-3)], alternative="greater").pvalue
    assert with_them < 0.01  # what counting them would have claimed


def test_holm_and_the_placebo_as_the_mean_of_its_draws():
    from mpcshare.evaluation.tuning.stats import holm

    assert holm([0.01, 0.04, 0.03, None]) == pytest.approx([0.03, 0.06, 0.06, None], nan_ok=True)
    rng = np.random.default_rng(2)
    gate_err = rng.uniform(0.01, 0.03, 10)
    rows = []
    for i, g in enumerate(gate_err):  # two draws per pair: one 1 mm worse than the gate, one 3 mm
        rows += [_row("gate", i % 2, i // 2, g)]
        rows += [dict(_row("random_handover", i % 2, i // 2, g + d, "gate"), draw=j)
                 for j, d in enumerate((1e-3, 3e-3))]
    rows += [_row("blend", i % 2, i // 2, g + 1e-3) for i, g in enumerate(gate_err)]
    rows += [_row("random_handover", i % 2, i // 2, g, "blend") for i, g in enumerate(gate_err)]
    tests = gate_vs_random(rows)
    t = tests["gate p90 b0.5"]["vs_random_handover"]
    assert t["effect_m"] == pytest.approx(2e-3) and t["draws_per_pair"] == [1, 2]
    assert t["p_value"] == pytest.approx(0.5 ** 10) and t["p_holm"] == pytest.approx(2 * 0.5 ** 10)
    assert t["p_holm"] < 0.01 and t["beats_random"]
    assert not tests["blend p90 b0.5"]["vs_random_handover"]["beats_random"]


def test_pareto_keeps_the_settings_nothing_beats_on_both():
    rows = [_row("voluntary", 0, 0, 0.030, effort=0.5), _row("reactive", 0, 0, 0.010, effort=0.05),
            _row("gate", 0, 0, 0.020, effort=0.2), _row("blend", 0, 0, 0.012, effort=0.04)]
    rows[0]["percentile"] = rows[0]["beta"] = None
    assert pareto(summarise(rows)) == ["reactive p90 b0.5", "blend p90 b0.5"]
