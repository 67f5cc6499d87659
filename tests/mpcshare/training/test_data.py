"""The data before K is chosen (mpcshare.training.data): K and the novelty threshold against
independent computations, held-out labels with the training K."""

import numpy as np
import pytest

from learning.preprocessing.resample import causal_downsample
from mpcshare.training import prepare_training_data
from tests.mpcshare.training.small import SMALL


def _brute_quotients(X, Y, groups):
    q = np.zeros(len(X))
    for g in np.unique(groups):
        idx = np.flatnonzero(groups == g)
        dx = np.linalg.norm(X[idx, None, :] - X[None, idx, :], axis=2)
        dy = np.linalg.norm(Y[idx, None, :] - Y[None, idx, :], axis=2)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(dx > 0, dy / dx, np.where(dy > 0, np.inf, 0.0))
        np.fill_diagonal(r, 0.0)
        q[idx] = r.max(axis=1)
    return q


def test_K_and_novelty_threshold_match_independent_computations(demos):
    data = prepare_training_data(demos, SMALL)
    w = data.train.windows
    q = _brute_quotients(w.X, w.Y, data.train.window_modes)
    np.testing.assert_allclose(data.train.q, q, rtol=1e-9)
    # every point's window holds L samples, causal: row 0 of a trial's windows is its sample L-1
    L = w.lags
    assert np.all(np.diff(w.source_index) >= 1) and w.X.shape[1] == L * len(demos.obs_names)
    # novelty: recomputed from the raw training trials with the fitted preprocessing
    low = causal_downsample(demos.select(data.train_trials), 10.0)
    obs = np.concatenate([data.preprocessor.obs.transform(tr.obs) for tr in low.trials])
    lengths = [len(tr) for tr in low.trials]
    ref = np.percentile(-data.modes.log_predictive(obs, lengths), 99.9)
    assert data.novelty_threshold == pytest.approx(ref, rel=1e-12)
    assert not set(data.fit_trials) & set(data.val_trials)
    assert sorted(data.fit_trials + data.val_trials) == sorted(data.train_trials)


def test_held_out_labels_use_the_training_K(demos):
    from mpcshare.training import fit_gates, reactive_labels
    from mpcshare.training.evaluation import evaluate

    data = prepare_training_data(demos, SMALL)
    K = float(np.percentile(data.train.q, 60))
    gates = fit_gates(data, reactive_labels(data.train.q, K))

    class Zero:  # a predictor that always predicts the standardised mean (0)
        def predict(self, windows):
            return np.zeros((len(windows), len(demos.act_names)))

    m = evaluate(data, gates, Zero(), K)
    R = data.heldout.q <= K
    assert m["heldout_reactive_share"] == pytest.approx(R.mean())
    Y = data.heldout.windows.Y
    assert m["predictor"]["rmse_reactive"] == pytest.approx(np.sqrt(np.mean(Y[R] ** 2)))
    assert m["predictor"]["rmse_all"] == pytest.approx(np.sqrt(np.mean(Y ** 2)))
