"""What the predictability analysis returns: its report and the arrays behind it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from learning.analysis.config import AnalysisConfig
from learning.analysis.report import AnalysisReport
from learning.modes import TaskModes
from learning.preprocessing.preprocess import WindowedData

__all__ = ["AnalysisResult"]


@dataclass
class AnalysisResult:
    """What :func:`analyze` found: the report and the arrays behind it.

    Attributes:
        summary: the findings (``report`` is ``summary.to_dict()``, the report.json content).
        windows: the preprocessed data at ``config.window_s``.
        q: (N,) quotients without modes; q_modes: (N,) within HMM modes;
        q_reference: (N,) within the time-free reference grouping;
        q_random: (n_random, N) within random segmentations.
        modes: (N,) HMM mode of each window row (Viterbi).
        features: (N_samples, D) standardised per-sample observations (the HMM's input);
        sample_modes: (N_samples,) their HMM modes (``modes = sample_modes[windows.source_index]``).
        true_modes: (N,) ground-truth labels or None.
        mode_model: the fitted :class:`TaskModes`.
        shares: {K: (trial ids, shares without modes, shares with modes)}.
    """

    summary: AnalysisReport
    config: AnalysisConfig
    windows: WindowedData
    q: np.ndarray
    q_modes: np.ndarray
    q_reference: np.ndarray
    q_random: np.ndarray
    modes: np.ndarray
    features: np.ndarray
    sample_modes: np.ndarray
    true_modes: np.ndarray | None
    mode_model: TaskModes
    shares: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=dict)

    @property
    def report(self) -> dict[str, Any]:
        """The JSON-ready report (``summary.to_dict()``, a fresh dict on every access)."""
        return self.summary.to_dict()
