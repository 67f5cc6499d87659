"""A small bundle for the controller tests: real preprocessing and task modes fitted on
generated data, plus tiny learned parts written here (a per-mode gate table and a ridge
regression as the reactive predictor) with the interfaces of ``learning.gates.gate`` and
``learning.predictor`` (``proba_one``, ``make_stream().step``)."""

from __future__ import annotations

from functools import lru_cache
from types import SimpleNamespace

import numpy as np
from sklearn.linear_model import Ridge

from learning.modes import TaskModes
from learning.preprocessing.preprocess import Preprocessor, Standardizer
from learning.preprocessing.resample import causal_downsample
from sim.demonstrator import (
    ACT_NAMES,
    OBS_NAMES,
    VOL_NAMES,
    GeneratorConfig,
    generate_demonstrations,
)

#: The SuperLimb's mount given to the controllers of these tests (T_plate_torso): the plate's centre
#: 0.22 m in front of the torso origin and 0.12 m to its right, at its height, axes aligned, so that
#: the demonstrations' knife positions lie mid-range of the joints around ``0.5·(lower + upper)``.
#: (`mpcshare sim` and `mpcshare run` give the eating scene's: ``mpcshare.arms.rest_base_pose``.)
MOUNT = np.eye(4)
MOUNT[:3, 3] = (-0.22, 0.12, 0.0)
MOUNT.setflags(write=False)

class TableGate:
    """Gate with a fixed probability per mode (``proba_one(window, mode)``)."""

    def __init__(self, table) -> None:
        self.table = np.asarray(table, dtype=float)

    def proba_one(self, window: np.ndarray, mode: int) -> float:
        return float(self.table[mode])


class LinearStream:
    """Stateless stream u = W·x + b (the predictor's ``make_stream()`` object)."""

    def __init__(self, W: np.ndarray, b: np.ndarray) -> None:
        self.W, self.b = W, b

    def step(self, x: np.ndarray) -> np.ndarray:
        return self.W @ x + self.b

    def reset(self) -> None:
        pass


class LinearPredictor:
    def __init__(self, W: np.ndarray, b: np.ndarray) -> None:
        self.W, self.b = W, b

    def make_stream(self) -> LinearStream:
        return LinearStream(self.W, self.b)


@lru_cache(maxsize=4)
def demos_and_bundle(seed: int = 0):
    """(demos at 100 Hz, bundle-like namespace); trials of 30 s."""
    demos = generate_demonstrations(n_subjects=1, minutes=1.5, seed=seed,
                                    config=GeneratorConfig(trial_minutes=0.5))
    low = causal_downsample(demos, 10.0)
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(low),
                       act=Standardizer("sensor", field="act").fit(low), target_hz=10.0, window_s=1.0)
    std = pre.standardize(low)
    X = np.concatenate([tr.obs for tr in std.trials])
    A = np.concatenate([tr.act for tr in std.trials])
    lengths = [len(tr) for tr in std.trials]
    modes = TaskModes(n_modes=3, n_restarts=1, seed=seed).fit(X, lengths)
    P = modes.filter_proba(X, lengths)
    ridge = Ridge(alpha=1e-3).fit(np.hstack([X, P]), A)
    hard = P.argmax(1)
    truth = np.concatenate([tr.mode for tr in low.trials])
    table = [float(np.mean(truth[hard == k] != 0)) if np.any(hard == k) else 0.0 for k in range(3)]
    bundle = SimpleNamespace(
        format_version=1, obs_names=OBS_NAMES, act_names=ACT_NAMES, vol_names=VOL_NAMES,
        rate_hz=100.0, model_hz=10.0, window_s=1.0, preprocessor=pre, modes=modes,
        gates=TableGate(table), predictor=LinearPredictor(ridge.coef_, ridge.intercept_),
        K=5.0, percentile=90.0,
        novelty_threshold=float(np.percentile(-modes.log_predictive(X, lengths), 99.9)))
    return demos, bundle


def real_model_bundle(seed: int = 0):
    """A ``mpcshare.bundle.ModelBundle`` with the real learned parts (RBF gates, a small LSTM
    trained for one epoch) on the same data and modes as :func:`demos_and_bundle`."""
    from learning.gates.gate import ModeGates
    from learning.predictor import ReactivePredictor
    from learning.preprocessing.preprocess import causal_windows
    from mpcshare.bundle import ModelBundle

    demos, b = demos_and_bundle(seed)
    low = causal_downsample(demos, 10.0)
    std = b.preprocessor.standardize(low)
    lengths = [len(tr) for tr in std.trials]
    P = b.modes.filter_proba(np.concatenate([tr.obs for tr in std.trials]), lengths)
    win = causal_windows(std, 1.0, rms=True)
    hard = P.argmax(1)[win.source_index]
    labels = (np.concatenate([tr.mode for tr in low.trials])[win.source_index] != 0).astype(int)
    gates = ModeGates(max_samples_per_mode=150, seed=seed).fit(win.X, hard, labels, n_modes=3)
    seqs = [np.hstack([tr.obs, p]) for tr, p in zip(std.trials, np.split(P, np.cumsum(lengths)[:-1]))]
    predictor = ReactivePredictor(hidden_size=8, max_epochs=1, chunk_len=25, seed=seed).fit(
        seqs, [tr.act for tr in std.trials], progress=False)
    return demos, ModelBundle(
        obs_names=tuple(b.obs_names), act_names=tuple(b.act_names), vol_names=tuple(b.vol_names),
        rate_hz=100.0, model_hz=10.0, window_s=1.0, preprocessor=b.preprocessor, modes=b.modes, gates=gates,
        predictor=predictor, K=5.0, percentile=90.0, novelty_threshold=b.novelty_threshold,
        train_trials=list(demos.trial_ids), heldout_trials=[])
