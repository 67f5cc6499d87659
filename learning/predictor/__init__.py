"""The reactive predictor π̂: (observation, mode posterior) → knife action.

- :mod:`learning.predictor.lstm` — the LSTM :class:`ReactivePredictor` (PyTorch, trained on R);
- :mod:`learning.predictor.stream` — its NumPy step-by-step twin :class:`PredictorStream`;
- :mod:`learning.predictor.baseline` — ridge regression on the window (``RidgeWindowBaseline``);
- :mod:`learning.predictor.metrics` — RMSE per physical channel group;
- :mod:`learning.predictor.sequences` — per-trial sequence sets: checks, chunks, padding;
- :mod:`learning.predictor.defaults` — the LSTM's default settings (read by ``TrainConfig``).

The names below are imported on first use (PEP 562), so that reading the defaults does
not import torch.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["PredictorStream", "ReactivePredictor", "RidgeWindowBaseline", "rmse_by_channel", "rmse_by_group"]

_HOME = {"PredictorStream": "stream", "ReactivePredictor": "lstm", "RidgeWindowBaseline": "baseline",
         "rmse_by_channel": "metrics", "rmse_by_group": "metrics"}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(importlib.import_module(f"learning.predictor.{_HOME[name]}"), name)
    raise AttributeError(f"module 'learning.predictor' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
