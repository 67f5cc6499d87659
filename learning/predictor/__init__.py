"""The reactive predictor π̂: (observation, mode posterior) → knife action.

- :mod:`learning.predictor.lstm` — the LSTM :class:`ReactivePredictor` (PyTorch, trained on R);
- :mod:`learning.predictor.stream` — its NumPy step-by-step twin :class:`PredictorStream`;
- :mod:`learning.predictor.baseline` — ridge regression on the window (``RidgeWindowBaseline``);
- :mod:`learning.predictor.metrics` — RMSE per physical channel group;
- :mod:`learning.predictor.sequences` — per-trial sequence sets: checks, chunks, padding.
"""

from learning.predictor.baseline import RidgeWindowBaseline
from learning.predictor.lstm import ReactivePredictor
from learning.predictor.metrics import rmse_by_channel, rmse_by_group
from learning.predictor.stream import PredictorStream

__all__ = ["PredictorStream", "ReactivePredictor", "RidgeWindowBaseline", "rmse_by_channel", "rmse_by_group"]
