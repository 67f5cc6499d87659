"""learning.modes.select_n_modes: the number of modes by held-out likelihood, and its errors."""

from __future__ import annotations

import pytest

from learning.modes import ModeSelection, select_n_modes
from tests.learning.hmm_samples import sample_hmm

# hmmlearn's reference computations here use tiny threaded BLAS calls (fixture: conftest.py)
pytestmark = pytest.mark.usefixtures("_one_blas_thread")


def test_select_n_modes_picks_the_true_number():
    X, _, L = sample_hmm(K=3, D=4, n_trials=6, T=250, sep=3.0, seed=11)
    sel = select_n_modes(X, L, candidates=[2, 3, 4, 5], cv=3, seed=0, n_restarts=2)
    assert isinstance(sel, ModeSelection)
    assert sel.n_modes == 3
    assert sel.n_modes_bic == 3
    assert len(sel.heldout_loglik) == len(sel.bic) == 4
    assert sel.heldout_loglik[1] > sel.heldout_loglik[0]
    assert sel.best_estimator.n_modes == 3
    d = sel.to_dict()
    assert d["n_folds"] == 3 and d["cv"] == "3-fold by trial" and "estimators" not in d


def test_select_n_modes_loto_and_errors():
    X, _, L = sample_hmm(K=2, D=3, n_trials=3, T=150, sep=4.0, seed=2)
    sel = select_n_modes(X, L, candidates=[1, 2], cv="loto", n_restarts=1, rule="max")
    assert sel.n_folds == 3 and sel.n_modes == 2 and sel.n_modes_max == 2
    with pytest.raises(ValueError, match="2 trials"):
        select_n_modes(X, None, candidates=[2])
    with pytest.raises(ValueError, match="cv"):
        select_n_modes(X, L, candidates=[2], cv="bogus")
