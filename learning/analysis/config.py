"""The analysis's settings, written once: :class:`AnalysisConfig` (the command line reads its
defaults from here), the claim's significance level and smallest effect of interest."""

from __future__ import annotations

import math
from dataclasses import dataclass

from learning.analysis.reference import REFERENCES
from learning.errors import LearningError

__all__ = ["AnalysisConfig", "AnalysisError", "HELP_EFFECT", "MIN_EFFECT", "SIGNIFICANCE"]


class AnalysisError(LearningError, ValueError):
    """The data cannot be analysed with these settings (the message says which and why)."""

SIGNIFICANCE = 1e-3  # p-value below which the report claims that modes lower the quotients
MIN_EFFECT = math.log(1.1)  # smallest effect of interest: modes lower per-trial median q by > 10 %
# smallest effect of interest of the claim "modes help" (modes against random groups alone):
# larger, since any grouping coherent in observation space beats random groups a little
# (up to a median ln ratio of 0.42 on regime-free data: see learning.analysis.reference)
HELP_EFFECT = math.log(1.5)


@dataclass(frozen=True)
class AnalysisConfig:
    """Settings of :func:`analyze` (defaults: the paper's, see README).

    Attributes:
        target_hz: rate after anti-aliased downsampling [Hz].
        window_s: causal window of observations [s].
        scope: standardisation, "sensor" (unit RMS magnitude per 3-channel sensor,
            as the paper) or "channel" (z-score).
        n_modes: HMM task modes.
        K: thresholds for the voluntary share (the paper: 5 and 10).
        percentiles: percentiles of q reported as candidate K.
        n_random: random segmentations compared against the HMM (the paper's reference).
        random_method: "permutation" (random groups of equal sizes) or "contiguous".
        reference: the time-free grouping the claim is tested against, "gmm" (default:
            the HMM's emission model without the Markov chain), "kmeans-sized" or "kmeans"
            (:mod:`learning.analysis.reference`; the choice is the calibration study's).
        min_effect: smallest effect of interest δ: the claim needs per-trial median q
            lowered by more than the factor e^δ (default ln 1.1; see
            :mod:`learning.analysis.reference` for the calibration behind it).
        help_effect: smallest effect of interest of the claim "modes help" (modes against
            random groups of equal sizes alone; default ``HELP_EFFECT``).
        search_windows, search_modes: the candidate grid of the search (empty: no search).
        search_random: random segmentations per search candidate.
        hmm_restarts: EM restarts of each HMM fit.
        select_modes: also choose the number of modes by held-out log-likelihood over
            trials (3-fold by trial; BIC as a second opinion) among ``search_modes``
            (2…6 if empty); reported as ``mode_selection``, costs about a minute.
        seed: seed of everything random.
    """

    target_hz: float = 10.0
    window_s: float = 1.0
    scope: str = "sensor"
    n_modes: int = 4
    K: tuple[float, ...] = (5.0, 10.0)
    percentiles: tuple[float, ...] = (50.0, 60.0, 70.0, 80.0, 90.0, 95.0, 99.0, 100.0)
    n_random: int = 20
    random_method: str = "permutation"
    reference: str = "gmm"
    min_effect: float = MIN_EFFECT
    help_effect: float = HELP_EFFECT
    search_windows: tuple[float, ...] = (0.5, 1.0, 2.0)
    search_modes: tuple[int, ...] = (2, 3, 4, 5, 6)
    search_random: int = 3
    hmm_restarts: int = 5
    select_modes: bool = False
    seed: int = 0

    def __post_init__(self) -> None:
        if not self.target_hz > 0:
            raise ValueError(f"target_hz must be > 0, got {self.target_hz}")
        if not self.window_s >= 0:
            raise ValueError(f"window_s must be >= 0, got {self.window_s}")
        if self.scope not in ("sensor", "channel"):
            raise ValueError(f"scope must be 'sensor' or 'channel', got {self.scope!r}")
        if self.n_modes < 1:
            raise ValueError(f"n_modes must be >= 1, got {self.n_modes}")
        if not self.K or any(not k > 0 for k in self.K):
            raise ValueError(f"K must be a non-empty list of positive thresholds, got {self.K}")
        if self.n_random < 1:
            raise ValueError(f"n_random must be >= 1, got {self.n_random}")
        if self.reference not in REFERENCES:
            raise ValueError(f"reference must be one of {REFERENCES}, got {self.reference!r}")
        if not self.min_effect >= 0:
            raise ValueError(f"min_effect must be >= 0, got {self.min_effect}")
        if not self.help_effect >= 0:
            raise ValueError(f"help_effect must be >= 0, got {self.help_effect}")
        if any(m < 1 for m in self.search_modes):
            raise ValueError(f"search_modes must be >= 1, got {self.search_modes}")
