"""Learning from demonstrations: data, preprocessing, Lipschitz analysis, task modes.

- :mod:`learning.data` — trials, NPZ / CSV-folder formats, validation, train/test splits.
- :mod:`learning.preprocessing.preprocess` — downsampling, standardisation, causal windows.
- :mod:`learning.preprocessing.resample` — causal anti-aliased downsampling, offline and streaming.
- :mod:`learning.lipschitz` — exact, fast point-wise Lipschitz quotients.
- :mod:`learning.analysis.predictability` — thresholds, voluntary shares, segmentation tests, model order.
- :mod:`learning.modes` — HMM task modes offline (``TaskModes``) and online (``ModeFilter``).
- :mod:`learning.analysis` — the paper's analysis end to end (``analyze``); its search
  over windows and numbers of modes in :mod:`learning.analysis.search`.
- :mod:`learning.gates.gate` — per-mode calibrated gates ``ModeGates``; their scores
  (accuracy, F1, Brier) in :mod:`learning.gates.metrics` (``gate_metrics``).
- :mod:`learning.predictor` — the LSTM reactive predictor ``ReactivePredictor`` with its
  NumPy ``PredictorStream`` (:mod:`learning.predictor.stream`);
  :mod:`learning.predictor.baseline` (ridge on the window),
  :mod:`learning.predictor.metrics` (RMSE per physical channel group),
  :mod:`learning.predictor.sequences` (per-trial sequence sets: checks, chunks, padding).

Imports only numpy, scipy, scikit-learn, threadpoolctl, hmmlearn, numba, torch and tqdm.
"""
