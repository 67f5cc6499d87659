"""Training a model bundle from demonstrations: ``train_bundle(demos, config)``.

Any data set in the project format, at ``model_hz`` (10 Hz); settings :class:`~mpcshare.training.config.TrainConfig`:

1. whole trials split into training and held-out (``heldout_fraction``, seeded); the training trials again
   into fit / validation trials for the LSTM's early stopping (all else fits on every training trial);
2. :func:`learning.preprocessing.resample.causal_downsample` (as the controller online); the
   :class:`~learning.preprocessing.preprocess.Preprocessor` (per-sensor ``Standardizer``) fitted on the training
   trials; causal windows ``causal_windows(std, window_s, rms=True)``;
3. HMM :class:`~learning.modes.TaskModes` on the standardised obs: Viterbi labels for the quotients, causal
   posteriors (``filter_proba``) for the predictor;
4. within-mode quotients q_t; K = percentile(q, p); Z_t = 1[q_t ≤ K]; the reactive subset R = {Z = 1};
5. ``ModeGates.fit(windows, modes, Z)``; ``ReactivePredictor.fit`` on concat(o_t, p_t), loss masked to R;
6. held-out evaluation (:mod:`mpcshare.training.evaluation`); the control-rate forecast
   (:mod:`mpcshare.training.fast`) fitted on the fit trials, its preview skill on the validation trials, its
   skill table (per mode and horizon, against hold and constant velocity) on the held-out trials;
7. ``novelty_threshold`` = 99.9th percentile of −log p(o_t | o_<t) per training step (``TaskModes.log_predictive``).

Steps 1–4 without K and 7: :func:`prepare_training_data`, reused per K by the sweep
(:mod:`mpcshare.training.sweep`) and :func:`train_bundles` (``mpcshare tune``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from learning.analysis.predictability import threshold_from_percentile
from learning.data import Demonstrations
from mpcshare.training.config import TrainConfig
from mpcshare.training.data import (
    SplitData,
    TrainingData,
    TrainingError,
    check_training_data,
    prepare_training_data,
    reactive_labels,
)
from mpcshare.training.evaluation import evaluate, fit_ridge, heldout_gate
from mpcshare.training.stages import Stages

if TYPE_CHECKING:  # annotations only (imported where they are used: torch loads on first use)
    from learning.gates import ModeGates
    from learning.predictor import ReactivePredictor
    from mpcshare.bundle import ModelBundle

__all__ = ["GateFit", "TrainingError", "SplitData", "TrainingData", "prepare_training_data",
           "reactive_labels", "fit_gates", "fit_predictor", "train_bundle", "train_bundles", "train_gates", "Stages"]


def fit_gates(data: TrainingData, labels: np.ndarray) -> ModeGates:
    """``ModeGates`` fitted on the training windows, their modes and ``labels`` (Z)."""
    from learning.gates.gate import ModeGates

    c = data.config
    gates = ModeGates(kernel=c.gate_kernel, max_samples_per_mode=c.gate_max_samples, seed=c.seed)
    return gates.fit(data.train.windows.X, data.train.window_modes, labels, c.n_modes)


def fit_predictor(data: TrainingData, window_mask: np.ndarray, progress: bool = False) -> ReactivePredictor:
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
                              burn_in=c.burn_in, num_threads=c.torch_threads, seed=c.seed, device=c.device,
                              horizons=c.forecast_steps)
    return model.fit([seqs[i] for i in fit_pos], [tgts[i] for i in fit_pos], [masks[i] for i in fit_pos],
                     val_sequences=[seqs[i] for i in val_pos], val_targets=[tgts[i] for i in val_pos],
                     val_masks=[masks[i] for i in val_pos], progress=progress)


def train_bundle(demos: Demonstrations, config: TrainConfig | None = None, progress: bool = True) -> ModelBundle:
    """Train every model of the shared controller and evaluate it on held-out trials.

    Returns a :class:`mpcshare.bundle.ModelBundle` (``metrics`` holds the held-out
    evaluation of :func:`mpcshare.training.evaluation.evaluate`, the K, the timings).

    Raises:
        TrainingError: the data cannot be used (see :func:`prepare_training_data`), or no
            training point is reactive at this percentile.
    """
    config = config or TrainConfig()
    return next(iter(train_bundles(demos, config, [config.percentile], progress).values()))


def train_bundles(demos: Demonstrations, config: TrainConfig | None = None,
                  percentiles: Sequence[float] | None = None, progress: bool = True) -> dict[float, ModelBundle]:
    """One bundle per percentile (default: ``config.percentile``), percentile → bundle: the data
    preparation (split, preprocessing, HMM modes, quotients, novelty threshold) is done once and
    shared; gates, predictor and evaluation per K (as :func:`train_bundle`)."""
    config = config or TrainConfig()
    ps = [float(p) for p in (percentiles if percentiles is not None else [config.percentile])]
    check_training_data(demos, config)
    tags = [f" p{p:g}" if len(ps) > 1 else "" for p in ps]  # one percentile: the stages of train_bundle
    per_k = ("gates", "predictor", "fast", "baselines", "evaluation")
    names = ["preprocess", "modes", "quotients"] + [stage + tag for tag in tags for stage in per_k]
    stages = Stages(names, progress)
    t0 = time.perf_counter()
    try:
        data = prepare_training_data(demos, config, stages, progress=progress)
        out = {}
        for p, tag in zip(ps, tags):
            cfg = TrainConfig(**{**config.to_dict(), "percentile": p})
            out[p] = _bundle_at(data, cfg, stages, progress, t0, tag)
    finally:
        stages.close()
    return out


@dataclass(frozen=True)
class GateFit:
    """The mode model and gates of :func:`train_gates` at ``K``, and the gates' held-out figures: the share of
    held-out windows handed to the wearer and the accuracy against the quotient labels (as
    :func:`mpcshare.training.evaluation.evaluate` gives them: ``voluntary_share``, ``gate.overall.accuracy``)."""

    modes: Any
    gates: ModeGates
    K: float
    voluntary_share: float
    gate_accuracy: float


def train_gates(demos: Demonstrations, config: TrainConfig | None = None) -> GateFit:
    """Steps 1–5 of the module docstring without the predictor: the data preparation, the gates at
    ``config.percentile`` and their held-out figures, exactly as :func:`train_bundle` computes them (the same
    split, modes, K and gates). What compares two mode sources needs no predictor. Raises :class:`TrainingError`
    as :func:`train_bundle`."""
    config = config or TrainConfig()
    data = prepare_training_data(demos, config)
    K = threshold_from_percentile(data.train.q, config.percentile)
    gates = fit_gates(data, reactive_labels(data.train.q, K))
    _, h, gate = heldout_gate(data, gates, K)
    return GateFit(data.modes, gates, float(K), float(np.mean(1 - h)), float(gate["overall"]["accuracy"]))


def _fit_fast(data: TrainingData, predictor, config: TrainConfig):
    """(fast forecaster or None, its metrics) (:func:`mpcshare.training.fast.fit_fast`)."""
    if not config.fast_forecast:
        return None, {"skipped": "fast_forecast is off in the training settings"}
    if not config.forecast_steps:
        return None, {"skipped": "the predictor has no forecast (forecast_s = 0)"}
    from mpcshare.training.fast import fit_fast

    return fit_fast(data, predictor)


def _bundle_at(data: TrainingData, config: TrainConfig, stages: Stages, progress: bool, t0: float,
               tag: str) -> ModelBundle:
    """Gates, predictor, baselines and evaluation at ``config.percentile`` on prepared ``data``
    (``tag``: the suffix of the stage names)."""
    from mpcshare.bundle import ModelBundle

    K = threshold_from_percentile(data.train.q, config.percentile)
    Z = reactive_labels(data.train.q, K)
    gates = fit_gates(data, Z)
    stages.done("gates" + tag)
    predictor = fit_predictor(data, Z.astype(bool), progress=progress)
    stages.done("predictor" + tag)
    fast, fast_metrics = _fit_fast(data, predictor, config)
    stages.done("fast" + tag)
    baselines = {"ridge": fit_ridge(data)}
    if config.lstm_baseline:
        baselines["lstm_all"] = fit_predictor(data, np.ones(len(Z), dtype=bool), progress=progress)
    stages.done("baselines" + tag)
    metrics = evaluate(data, gates, predictor, K, baselines=baselines)
    metrics["fast_forecast"] = fast_metrics
    stages.done("evaluation" + tag)
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
        percentile=float(config.percentile), novelty_threshold=data.novelty_threshold, fast=fast,
        train_trials=data.train_trials, heldout_trials=data.heldout_trials, metrics=metrics,
        config=config.to_dict())
