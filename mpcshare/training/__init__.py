"""Training a model bundle from demonstrations, and the K trade-off.

- :mod:`mpcshare.training.config` — :class:`TrainConfig`, every setting with its default;
- :mod:`mpcshare.training.data` — the data before K is chosen (split, standardisation, modes,
  windows, quotients): :func:`prepare_training_data`;
- :mod:`mpcshare.training.train` — :func:`train_bundle`: gates, predictor, evaluation, bundle
  (:func:`train_bundles`: one per K on the same prepared data; :func:`train_gates`: the gates alone);
- :mod:`mpcshare.training.evaluation` — held-out metrics of a trained bundle;
- :mod:`mpcshare.training.sweep` — the K trade-off (accuracy against the wearer's effort);
- :mod:`mpcshare.training.stages` — progress over named stages.
"""

import importlib

from mpcshare.training.config import DEFAULT_PERCENTILES, TrainConfig

#: public name → submodule; loaded on first use, so that reading the settings stays light
_LAZY = {"SplitData": "data", "TrainingData": "data", "TrainingError": "data", "check_training_data": "data",
         "prepare_training_data": "data", "reactive_labels": "data", "Stages": "stages", "fit_gates": "train",
         "fit_predictor": "train", "train_bundle": "train", "train_bundles": "train", "train_gates": "train",
         "GateFit": "train"}

__all__ = ["DEFAULT_PERCENTILES", "TrainConfig", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(f"mpcshare.training.{_LAZY[name]}"), name)
    raise AttributeError(f"module 'mpcshare.training' has no attribute {name!r}")
