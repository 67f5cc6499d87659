"""Learning from demonstrations: data, preprocessing, Lipschitz analysis, task modes, gates, predictor.

- :mod:`learning.data` — trials, NPZ / CSV-folder formats, validation, train/test splits.
- :mod:`learning.preprocessing` — downsampling, standardisation, causal windows; causal
  anti-aliased downsampling offline and streaming (:mod:`learning.preprocessing.resample`).
- :mod:`learning.lipschitz` — exact, fast point-wise Lipschitz quotients.
- :mod:`learning.modes` — HMM task modes offline (``TaskModes``) and online (``ModeFilter``).
- :mod:`learning.analysis` — the paper's analysis end to end (``analyze``): thresholds and
  voluntary shares (``predictability``), the calibrated segmentation test (``reference``), the
  search over windows and numbers of modes (``search``), the report's records (``report``).
- :mod:`learning.gates` — per-mode calibrated gates ``ModeGates`` and their scores.
- :mod:`learning.predictor` — the LSTM reactive predictor ``ReactivePredictor``, its NumPy
  ``PredictorStream``, the ridge baseline, RMSE per channel group, sequence sets.
- :mod:`learning.atomic`, :mod:`learning.torch_threads` — atomic writes and the project's JSON
  writer; torch's thread count scoped to a call.
- :mod:`learning.errors` — :class:`~learning.errors.LearningError`, the root of the errors
  ``learning`` raises.

Imports only numpy, scipy, scikit-learn, threadpoolctl, hmmlearn, numba, torch and tqdm.
"""
