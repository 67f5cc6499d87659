"""The findings of :func:`learning.analysis.analyze` as typed records; ``to_dict()`` gives ``report.json``.

Every record's ``to_dict()`` returns plain JSON types (no NaN or infinity: an
infinite quotient is ``None``, JSON ``null``). The schema, with every key, type,
unit and meaning, is documented in ``docs/design.md`` ("The analysis report").
Quotients q are dimensionless ratios of standardised distances; shares are
fractions in [0, 1].
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # only for the annotation: the object is built by the analysis
    from .modes import ModeSelection

__all__ = ["QuotientStats", "ModesSummary", "SegmentationTest", "VoluntaryShare", "Candidate",
           "AnalysisReport"]


@dataclass(frozen=True)
class QuotientStats:
    """Distribution of point-wise quotients: percentiles (``None`` = infinite) and the infinite count.

    ``K_by_percentile`` maps a percentile ("50" … "100") to the quotient at it, the
    candidate thresholds K; reported for the quotients without modes only.
    """

    p50: float | None
    p90: float | None
    p99: float | None
    max: float | None
    n_inf: int
    K_by_percentile: dict[str, float | None] | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"p50": self.p50, "p90": self.p90, "p99": self.p99, "max": self.max,
                               "n_inf": self.n_inf}
        if self.K_by_percentile is not None:
            out["K_by_percentile"] = dict(self.K_by_percentile)
        return out


@dataclass(frozen=True)
class ModesSummary:
    """The fitted HMM task modes.

    ``agreement``: share of windows whose mode matches the ground-truth label after
    Hungarian matching, ``ari``: adjusted Rand index (both ``None`` without labels);
    ``occupancy[k]``: share of windows in mode k; ``loglik``: total log-likelihood
    of the fit [nats]; ``bic``: Bayesian information criterion [nats].
    """

    n_modes: int
    agreement: float | None
    ari: float | None
    occupancy: list[float]
    converged: bool
    loglik: float
    bic: float

    def to_dict(self) -> dict[str, Any]:
        return {"n_modes": self.n_modes, "agreement": self.agreement, "ari": self.ari,
                "occupancy": list(self.occupancy), "converged": self.converged, "loglik": self.loglik,
                "bic": self.bic}


@dataclass(frozen=True)
class SegmentationTest:
    """One-sided Mann–Whitney U test: quotients within HMM modes smaller than within random
    segmentations of equal group sizes; ``significant`` when p < ``alpha`` and the HMM median
    is the smaller. ``effect_size`` is Cliff's delta in [−1, 1]."""

    test: str
    statistic: float
    p_value: float
    effect_size: float
    effect_size_name: str
    hmm_median_q: float
    random_median_q: float
    n_random: int
    random_method: str
    significant: bool
    alpha: float

    def to_dict(self) -> dict[str, Any]:
        return {"test": self.test, "statistic": self.statistic, "p_value": self.p_value,
                "effect_size": self.effect_size, "effect_size_name": self.effect_size_name,
                "hmm_median_q": self.hmm_median_q, "random_median_q": self.random_median_q,
                "n_random": self.n_random, "random_method": self.random_method,
                "significant": self.significant, "alpha": self.alpha}


@dataclass(frozen=True)
class VoluntaryShare:
    """The voluntary share (fraction of windows with q > K) at one K, mean over trials.

    ``p_value``: paired one-sided Wilcoxon signed-rank test over trials, share within
    HMM modes < share within random segmentations (``statistic``, ``effect_size`` the
    matched-pairs rank-biserial correlation); ``p_value_vs_without_modes``: the same
    test against no modes; ``fold_reduction`` = without / with modes (``None`` when
    the share with modes is 0).
    """

    without_modes: float
    with_modes: float
    random: float
    fold_reduction: float | None
    statistic: float
    p_value: float
    effect_size: float
    test: str
    p_value_vs_without_modes: float
    n_trials: int

    def to_dict(self) -> dict[str, Any]:
        return {"without_modes": self.without_modes, "with_modes": self.with_modes, "random": self.random,
                "fold_reduction": self.fold_reduction, "statistic": self.statistic,
                "p_value": self.p_value, "effect_size": self.effect_size, "test": self.test,
                "p_value_vs_without_modes": self.p_value_vs_without_modes, "n_trials": self.n_trials}


@dataclass(frozen=True)
class Candidate:
    """One (window, number of modes) candidate of the search for missing information.

    ``gain_beyond_random_log10`` = log10(median q within random segmentations / median q
    within modes), the ranking key (``rank`` 1 = largest gain). The voluntary shares
    at the first K (``share_K``) are written under the key ``voluntary_share_K<K>``.
    """

    window_s: float
    n_modes: int
    median_q_without_modes: float
    median_q_modes: float
    median_q_random: float
    gain_beyond_random_log10: float
    share_K: float
    share_without_modes: float
    share_with_modes: float
    share_random: float
    hmm_bic: float
    rank: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {"window_s": self.window_s, "n_modes": self.n_modes,
                "median_q_without_modes": self.median_q_without_modes,
                "median_q_modes": self.median_q_modes, "median_q_random": self.median_q_random,
                "gain_beyond_random_log10": self.gain_beyond_random_log10,
                f"voluntary_share_K{self.share_K:g}": {"without_modes": self.share_without_modes,
                                                       "with_modes": self.share_with_modes,
                                                       "random": self.share_random},
                "hmm_bic": self.hmm_bic, "rank": self.rank}


@dataclass
class AnalysisReport:
    """Everything ``report.json`` holds (see ``docs/design.md`` for the schema).

    Sizes after preprocessing: ``n_samples`` windows in ``n_trials`` trials,
    ``input_dim`` = lags × d_o, ``output_dim`` = d_u; ``rate_hz`` [Hz], ``window_s`` [s],
    ``lags`` samples per window, ``scope`` of the standardisation. ``voluntary_share``
    is keyed by K formatted with ``:g`` ("5", "10"); ``candidates`` are in rank order;
    ``config`` is the :class:`~learning.analysis.AnalysisConfig` as a dict; ``timings_s``
    the wall time of each step [s].
    """

    n_samples: int
    n_trials: int
    input_dim: int
    output_dim: int
    rate_hz: float
    window_s: float
    lags: int
    scope: str
    quotients: QuotientStats
    quotients_with_modes: QuotientStats
    modes: ModesSummary
    segmentation_test: SegmentationTest
    voluntary_share: dict[str, VoluntaryShare]
    candidates: list[Candidate] = field(default_factory=list)
    mode_selection: ModeSelection | None = None
    config: dict[str, Any] = field(default_factory=dict)
    timings_s: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The JSON-ready dict written as ``report.json`` (a fresh copy on every call)."""
        return {
            "n_samples": self.n_samples, "n_trials": self.n_trials, "input_dim": self.input_dim,
            "output_dim": self.output_dim, "rate_hz": self.rate_hz, "window_s": self.window_s,
            "lags": self.lags, "scope": self.scope,
            "quotients": self.quotients.to_dict(),
            "quotients_with_modes": self.quotients_with_modes.to_dict(),
            "modes": self.modes.to_dict(),
            "segmentation_test": self.segmentation_test.to_dict(),
            "voluntary_share": {k: v.to_dict() for k, v in self.voluntary_share.items()},
            "candidates": [c.to_dict() for c in self.candidates],
            "mode_selection": None if self.mode_selection is None else self.mode_selection.to_dict(),
            "config": {k: (list(v) if isinstance(v, (tuple, list)) else v) for k, v in self.config.items()},
            "timings_s": dict(self.timings_s),
        }
