"""The training data before K is chosen: split, causal downsampling, standardisation, HMM modes,
windows and within-mode quotients (steps 1–4 and 7 of :mod:`mpcshare.training.train`), shared by
every K of a sweep and by the held-out evaluation."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from learning.data import Demonstrations, split_by_trial
from learning.preprocessing.preprocess import Preprocessor, Standardizer, WindowedData, causal_windows, window_lags
from learning.preprocessing.resample import causal_downsample, decimation_factor
from mpcshare.errors import MpcshareError
from mpcshare.training.config import TrainConfig
from mpcshare.training.stages import Stages

if TYPE_CHECKING:  # annotations only
    from learning.modes import TaskModes

__all__ = ["TrainingError", "SplitData", "TrainingData", "check_training_data", "prepare_training_data",
           "reactive_labels"]


class TrainingError(MpcshareError, ValueError):
    """The data cannot be used for training with these settings (the message says why)."""


@dataclass
class SplitData:
    """One side of the split (training or held-out trials) at the model rate.

    Attributes:
        std: causally downsampled set, obs and act standardised (voluntary as recorded).
        windows: ``causal_windows(std, window_s, rms=True)``; row i is sample
            ``windows.source_index[i]`` of ``std.stacked()``.
        lengths: (n_trials,) samples per trial.
        modes: (n_samples,) Viterbi mode of every sample; posterior: (n_samples, n_modes)
            causal mode posteriors.
        q: (n_windows,) quotients within modes, computed within this side only.
    """

    std: Demonstrations
    windows: WindowedData
    lengths: np.ndarray
    modes: np.ndarray
    posterior: np.ndarray
    q: np.ndarray

    @property
    def window_modes(self) -> np.ndarray:
        return self.modes[self.windows.source_index]

    @property
    def trial_ids(self) -> list[int]:
        return self.std.trial_ids

    def sequences(self) -> list[np.ndarray]:
        """Per trial (T_i, d_o + n_modes): ``concat(o_t, p_t)``, the predictor's input."""
        post = np.split(self.posterior, np.cumsum(self.lengths)[:-1])
        return [np.concatenate([tr.obs, p], axis=1) for tr, p in zip(self.std.trials, post)]

    def targets(self) -> list[np.ndarray]:
        """Per trial (T_i, d_u): standardised action."""
        return [tr.act for tr in self.std.trials]

    def masks(self, window_mask: np.ndarray) -> list[np.ndarray]:
        """Per trial (T_i,) bool: ``window_mask`` (n_windows,) placed at its samples;
        samples without a window (the first L−1 of a trial) are False."""
        flat = np.zeros(int(self.lengths.sum()), dtype=bool)
        flat[self.windows.source_index] = np.asarray(window_mask, dtype=bool)
        return np.split(flat, np.cumsum(self.lengths)[:-1])

    def stacked_predictions(self, predictor: Any) -> np.ndarray:
        """(n_windows, d_u) standardised predictions of ``predictor`` at the windowed samples."""
        pred = np.concatenate([predictor.predict(s) for s in self.sequences()])
        return pred[self.windows.source_index]


@dataclass
class TrainingData:
    """Everything fitted before K is chosen (shared by every K of a sweep)."""

    config: TrainConfig
    rate_hz: float
    obs_names: list[str]
    act_names: list[str]
    vol_names: list[str]
    preprocessor: Preprocessor
    modes: TaskModes
    train: SplitData
    heldout: SplitData
    fit_trials: list[int]
    val_trials: list[int]
    novelty_threshold: float
    train_raw: Demonstrations | None = None
    heldout_raw: Demonstrations | None = None

    @property
    def train_trials(self) -> list[int]:
        return self.train.trial_ids

    @property
    def heldout_trials(self) -> list[int]:
        return self.heldout.trial_ids


def check_training_data(demos: Demonstrations, config: TrainConfig) -> int:
    """Refuse unusable data before any work; return the window length L [samples]."""
    if not isinstance(demos, Demonstrations) or len(demos) == 0:
        raise TrainingError("the data set has no trials")
    if demos.obs_dim == 0 or demos.act_dim == 0:
        raise TrainingError(f"the data set has {demos.obs_dim} obs and {demos.act_dim} act channels; "
                            "training needs at least one of each")
    if len(demos) < 3:
        raise TrainingError(f"the data set has {len(demos)} trial(s); training needs at least 3 "
                            "(training, validation for early stopping, held-out for evaluation)")
    try:
        f = decimation_factor(demos.rate_hz, config.model_hz)
    except ValueError as exc:
        raise TrainingError(f"cannot downsample causally to {config.model_hz:g} Hz: {exc}") from None
    if config.device == "cuda":
        import torch
        if not torch.cuda.is_available():
            raise TrainingError("device 'cuda' was asked for but torch sees no CUDA device; use cpu or auto")
    L = window_lags(config.window_s, config.model_hz)
    short = [(tr.trial_id, len(tr)) for tr in demos.trials if -(-len(tr) // f) < L + 1]
    if short:
        tid, n = short[0]
        raise TrainingError(
            f"{len(short)} trial(s) too short for a {config.window_s:g} s window at {config.model_hz:g} Hz "
            f"(need {L + 1} samples after downsampling, {(L + 1) * f} raw): trial {tid} has {n} samples; "
            f"ids {[s[0] for s in short[:10]]}{' …' if len(short) > 10 else ''}")
    return L


def _side(std: Demonstrations, modes: TaskModes, window_s: float, progress: bool) -> SplitData:
    from learning.lipschitz import pointwise_quotients

    obs, lengths = std.obs_sequences()
    labels = modes.predict(obs, lengths)
    posterior = modes.filter_proba(obs, lengths)
    w = causal_windows(std, window_s, rms=True)  # every trial is long enough (_check_data)
    q = pointwise_quotients(w.X, w.Y, groups=labels[w.source_index], progress=progress)
    return SplitData(std=std, windows=w, lengths=lengths, modes=labels, posterior=posterior, q=q)


def prepare_training_data(demos: Demonstrations, config: TrainConfig,
                          stages: Stages | None = None, progress: bool = False) -> TrainingData:
    """Steps 1–4 (without K) and 7 of the module docstring.

    Raises:
        TrainingError: fewer than 3 trials, no obs or act channels, a rate that is not
            an integer multiple of ``model_hz``, a trial shorter than the window.
    """
    from learning.modes import TaskModes

    check_training_data(demos, config)
    train_raw, held_raw = split_by_trial(demos, config.heldout_fraction, seed=config.seed)
    fit_raw, val_raw = split_by_trial(train_raw, config.val_fraction, seed=config.seed + 1)
    try:
        zp = config.zero_phase_targets
        low_train = causal_downsample(train_raw, config.model_hz, zero_phase_act=zp)
        low_held = causal_downsample(held_raw, config.model_hz, zero_phase_act=zp)
    except ValueError as exc:
        raise TrainingError(str(exc)) from None
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(low_train),
                       act=Standardizer("sensor", field="act").fit(low_train),
                       target_hz=float(config.model_hz), window_s=float(config.window_s))
    std_train, std_held = pre.standardize(low_train), pre.standardize(low_held)
    if stages:
        stages.done("preprocess")

    obs, lengths = std_train.obs_sequences()
    if len(obs) < 10 * config.n_modes:
        raise TrainingError(f"{len(obs)} training samples at {config.model_hz:g} Hz are too few for "
                            f"{config.n_modes} HMM modes (need at least {10 * config.n_modes})")
    hmm = TaskModes(n_modes=config.n_modes, n_restarts=config.hmm_restarts, seed=config.seed,
                    temporal=config.modes_from == "hmm")
    hmm.fit(obs, lengths)
    neg_log = -hmm.log_predictive(obs, lengths)
    novelty = float(np.percentile(neg_log, 99.9))
    if stages:
        stages.done("modes")

    train = _side(std_train, hmm, config.window_s, progress)
    held = _side(std_held, hmm, config.window_s, progress)
    if stages:
        stages.done("quotients")
    return TrainingData(config=config, rate_hz=float(demos.rate_hz), obs_names=list(demos.obs_names),
                        act_names=list(demos.act_names),
                        vol_names=list(demos.vol_names) if demos.has_voluntary else [],
                        preprocessor=pre, modes=hmm, train=train, heldout=held,
                        fit_trials=fit_raw.trial_ids, val_trials=val_raw.trial_ids,
                        novelty_threshold=novelty, train_raw=train_raw, heldout_raw=held_raw)


def reactive_labels(q: np.ndarray, K: float) -> np.ndarray:
    """Z_t = 1[q_t ≤ K] as an int array (the reactive subset R = {Z = 1})."""
    return (np.asarray(q, dtype=float) <= K).astype(int)


