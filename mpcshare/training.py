"""Training a model bundle from demonstrations: ``train_bundle(demos, config)``.

Works on any data set in the project format (channel names need not be physical).
Steps (all at the model rate ``model_hz``, default 10 Hz):

1. split whole trials into training and held-out (``heldout_fraction``, seeded); the
   training trials are split again by trial into fit / validation trials for the LSTM's
   early stopping (everything else is fitted on all training trials);
2. :func:`learning.resample.causal_downsample` (the controller reproduces it online,
   never the zero-phase ``downsample``); the :class:`~learning.preprocess.Preprocessor`
   (``Standardizer(scope="sensor")`` for obs and act) fitted on the training trials;
   causal windows ``causal_windows(std, window_s, rms=True)``;
3. HMM :class:`~learning.modes.TaskModes` on the standardised per-sample obs of the
   training trials; Viterbi labels for the quotients, causal posteriors
   (``filter_proba``) as the predictor's input;
4. within-mode point-wise quotients ``q_t`` (windows → standardised act);
   ``K = percentile(q, p)``; labels ``Z_t = 1[q_t ≤ K]``; the reactive subset R = {Z = 1};
5. gates ``ModeGates.fit(windows, modes, Z)``; ``ReactivePredictor.fit`` on each trial's
   sequence ``concat(o_t, p_t)`` with the loss masked to R (the first L−1 samples of a
   trial have no window and so no label: masked out);
6. held-out evaluation (:mod:`mpcshare.evaluation`);
7. ``novelty_threshold`` = the 99.9th percentile of ``−log p(o_t | o_<t)`` per step on
   the training trials (``TaskModes.log_predictive``).

Data preparation (1–4 without K, and 7) is :func:`prepare_training_data`; the sweep
(:mod:`mpcshare.sweep`) reuses it for every K. The settings are a
:class:`~mpcshare.train_config.TrainConfig`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from learning.data import Demonstrations, split_by_trial
from learning.preprocess import Preprocessor, Standardizer, WindowedData, causal_windows, window_lags
from learning.resample import causal_downsample, decimation_factor
from mpcshare.train_config import TrainConfig

__all__ = ["TrainingError", "SplitData", "TrainingData", "prepare_training_data",
           "reactive_labels", "fit_gates", "fit_predictor", "train_bundle", "Stages"]


class TrainingError(ValueError):
    """The data cannot be used for training with these settings (the message says why)."""


# ------------------------------------------------------------------ progress

class Stages:
    """Stage-level progress (tqdm) with the time of each stage [s]."""

    def __init__(self, names: list[str], enabled: bool, desc: str = "train") -> None:
        self.bar = None
        if enabled:
            from tqdm.auto import tqdm
            self.bar = tqdm(total=len(names), desc=desc, unit="stage")
            self.bar.set_postfix_str(names[0])
        self.names = names
        self.timings: dict[str, float] = {}
        self._t = time.perf_counter()

    def done(self, name: str) -> None:
        now = time.perf_counter()
        self.timings[name] = round(self.timings.get(name, 0.0) + now - self._t, 3)
        self._t = now
        if self.bar is not None:
            self.bar.update(1)
            i = self.names.index(name) + 1 if name in self.names else len(self.names)
            if i < len(self.names):
                self.bar.set_postfix_str(self.names[i])

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


# ------------------------------------------------------------------ data

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
    modes: Any  # learning.modes.TaskModes
    train: SplitData
    heldout: SplitData
    fit_trials: list[int]
    val_trials: list[int]
    novelty_threshold: float

    @property
    def train_trials(self) -> list[int]:
        return self.train.trial_ids

    @property
    def heldout_trials(self) -> list[int]:
        return self.heldout.trial_ids


def _check_data(demos: Demonstrations, config: TrainConfig) -> int:
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


def _stack(std: Demonstrations) -> tuple[np.ndarray, np.ndarray]:
    return np.concatenate([tr.obs for tr in std.trials]), np.array([len(tr) for tr in std.trials])


def _side(std: Demonstrations, modes: Any, window_s: float, progress: bool) -> SplitData:
    from learning.lipschitz import pointwise_quotients

    obs, lengths = _stack(std)
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

    _check_data(demos, config)
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

    obs, lengths = _stack(std_train)
    if len(obs) < 10 * config.n_modes:
        raise TrainingError(f"{len(obs)} training samples at {config.model_hz:g} Hz are too few for "
                            f"{config.n_modes} HMM modes (need at least {10 * config.n_modes})")
    hmm = TaskModes(n_modes=config.n_modes, n_restarts=config.hmm_restarts, seed=config.seed)
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
                        novelty_threshold=novelty)


# ------------------------------------------------------------------ fitting

def reactive_labels(q: np.ndarray, K: float) -> np.ndarray:
    """Z_t = 1[q_t ≤ K] as an int array (the reactive subset R = {Z = 1})."""
    return (np.asarray(q, dtype=float) <= K).astype(int)


def fit_gates(data: TrainingData, labels: np.ndarray) -> Any:
    """``ModeGates`` fitted on the training windows, their modes and ``labels`` (Z)."""
    from learning.gate import ModeGates

    c = data.config
    gates = ModeGates(kernel=c.gate_kernel, max_samples_per_mode=c.gate_max_samples, seed=c.seed)
    return gates.fit(data.train.windows.X, data.train.window_modes, labels, c.n_modes)


def fit_predictor(data: TrainingData, window_mask: np.ndarray, progress: bool = False) -> Any:
    """``ReactivePredictor`` trained on the fit trials with the loss masked to
    ``window_mask`` (n_windows,) of the training side; early stopping on the val trials."""
    from learning.predictor import ReactivePredictor

    c = data.config
    seqs, tgts, masks = data.train.sequences(), data.train.targets(), data.train.masks(window_mask)
    ids = data.train.trial_ids
    fit_pos = [i for i, t in enumerate(ids) if t in set(data.fit_trials)]
    val_pos = [i for i, t in enumerate(ids) if t in set(data.val_trials)]
    if not any(masks[i].any() for i in fit_pos):
        raise TrainingError("no reactive point in the fit trials at this K; raise the percentile")
    model = ReactivePredictor(hidden_size=c.hidden_size, batch_size=c.batch_size, max_epochs=c.max_epochs,
                              patience=c.patience, learning_rate=c.learning_rate, chunk_len=c.chunk_len,
                              burn_in=c.burn_in, num_threads=c.torch_threads, seed=c.seed, device=c.device)
    return model.fit([seqs[i] for i in fit_pos], [tgts[i] for i in fit_pos], [masks[i] for i in fit_pos],
                     val_sequences=[seqs[i] for i in val_pos], val_targets=[tgts[i] for i in val_pos],
                     val_masks=[masks[i] for i in val_pos], progress=progress)


def train_bundle(demos: Demonstrations, config: TrainConfig | None = None, progress: bool = True):
    """Train every model of the shared controller and evaluate it on held-out trials.

    Returns a :class:`mpcshare.bundle.ModelBundle` (``metrics`` holds the held-out
    evaluation of :func:`mpcshare.evaluation.evaluate`, the K, the timings).

    Raises:
        TrainingError: the data cannot be used (see :func:`prepare_training_data`), or no
            training point is reactive at this percentile.
    """
    from learning.predictability import threshold_from_percentile
    from mpcshare.bundle import ModelBundle
    from mpcshare.evaluation import evaluate, fit_ridge

    config = config or TrainConfig()
    _check_data(demos, config)
    names = ["preprocess", "modes", "quotients", "gates", "predictor", "baselines", "evaluation"]
    stages = Stages(names, progress)
    t0 = time.perf_counter()
    try:
        data = prepare_training_data(demos, config, stages, progress=progress)
        K = threshold_from_percentile(data.train.q, config.percentile)
        Z = reactive_labels(data.train.q, K)
        gates = fit_gates(data, Z)
        stages.done("gates")
        predictor = fit_predictor(data, Z.astype(bool), progress=progress)
        stages.done("predictor")
        baselines = {"ridge": fit_ridge(data)}
        if config.lstm_baseline:
            baselines["lstm_all"] = fit_predictor(data, np.ones(len(Z), dtype=bool), progress=progress)
        stages.done("baselines")
        metrics = evaluate(data, gates, predictor, K, baselines=baselines)
        stages.done("evaluation")
    finally:
        stages.close()
    metrics["training"] = {
        "K": None if math.isinf(K) else float(K), "percentile": float(config.percentile),
        "reactive_share_train": float(Z.mean()), "n_train_windows": int(len(Z)),
        "n_heldout_windows": int(len(data.heldout.q)),
        "train_trials": data.train_trials, "fit_trials": data.fit_trials, "val_trials": data.val_trials,
        "heldout_trials": data.heldout_trials, "novelty_threshold": data.novelty_threshold,
        "gates": gates.describe(), "timings_s": dict(stages.timings),
        "total_s": round(time.perf_counter() - t0, 3)}
    return ModelBundle(
        obs_names=tuple(data.obs_names), act_names=tuple(data.act_names), vol_names=tuple(data.vol_names),
        rate_hz=data.rate_hz, model_hz=config.model_hz, window_s=config.window_s,
        preprocessor=data.preprocessor, modes=data.modes, gates=gates, predictor=predictor, K=float(K),
        percentile=float(config.percentile), novelty_threshold=data.novelty_threshold,
        train_trials=data.train_trials, heldout_trials=data.heldout_trials, metrics=metrics,
        config=config.to_dict())
