"""HMM task modes (the paper's "missing information"), offline and online.

A Gaussian hidden Markov model over preprocessed observations, fitted without labels
with hmmlearn's :class:`~hmmlearn.hmm.GaussianHMM`::

    s_0 ~ π,   s_t | s_{t-1}=i ~ A_i·,   z_t | s_t=j ~ N(μ_j, Σ_j),   z_t = PCA(standardise(o_t))

- :class:`TaskModes` — estimator: ``fit``, ``predict`` (Viterbi), ``predict_proba`` (smoothed),
  ``filter_proba`` (causal), ``log_predictive``, ``score``, ``bic``, ``make_filter``, ``filter_params``.
- :class:`ModeFilter` — online causal posterior, one observation per ``step``, from a ``TaskModes``
  or the frozen :class:`HMMFilterParams` of ``TaskModes.filter_params()``.
- :func:`select_n_modes` → :class:`ModeSelection` — number of modes by held-out log-likelihood
  over trials (BIC as a second opinion); evidence, not truth, when the data are not Gaussian.
- :func:`match_modes`, :func:`mode_agreement`, :func:`mode_ari`, :func:`relabel` — agreement with
  ground-truth labels (Hungarian matching, accuracy, ARI).
- :class:`RegularizedGaussianHMM` — ``GaussianHMM`` with a covariance floor after every M-step
  (hmmlearn capped below 0.4: it overrides private methods); :func:`check_sequences` — the input
  validation; :func:`forward_filter_log` — the causal forward pass of one sequence in log space.

Fit on per-sample inputs, not long windows (docs/results.md, "Modes: the two claims, calibration, discovery").
"""

from ._hmm import RegularizedGaussianHMM, check_sequences
from ._metrics import match_modes, mode_agreement, mode_ari, relabel
from ._online import HMMFilterParams, ModeFilter, forward_filter_log
from ._selection import ModeSelection, select_n_modes
from ._task_modes import DegenerateModesWarning, TaskModes

__all__ = [
    "DegenerateModesWarning",
    "HMMFilterParams",
    "ModeFilter",
    "ModeSelection",
    "RegularizedGaussianHMM",
    "TaskModes",
    "check_sequences",
    "forward_filter_log",
    "match_modes",
    "mode_agreement",
    "mode_ari",
    "relabel",
    "select_n_modes",
]
