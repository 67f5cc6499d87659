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
    from learning.modes import ModeSelection

__all__ = ["QuotientStats", "ModesSummary", "Claim", "SegmentationTest", "VoluntaryShare", "Candidate",
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
    of the fit [nats]; ``bic``: Bayesian information criterion [nats]; ``restart_logliks``:
    the training log-likelihood of every EM restart [nats] (the fit kept is the best
    without empty states; a wide spread means EM has poor local optima on these data);
    ``restart_ari``: adjusted Rand index of every restart's modes against the kept fit's
    (1 for all: the restarts agree on the partition, whatever the seed of their start).
    """

    n_modes: int
    agreement: float | None
    ari: float | None
    occupancy: list[float]
    converged: bool
    loglik: float
    bic: float
    restart_logliks: list[float] = field(default_factory=list)
    restart_ari: list[float] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"n_modes": self.n_modes, "agreement": self.agreement, "ari": self.ari,
                "occupancy": list(self.occupancy), "converged": self.converged, "loglik": self.loglik,
                "bic": self.bic, "restart_logliks": list(self.restart_logliks),
                "restart_ari": list(self.restart_ari)}


@dataclass(frozen=True)
class Claim:
    """One of the two claims of the segmentation test, with its own test and verdict.

    ``key``: ``"modes_help"`` (HMM modes against random groups of equal sizes: the paper's
    claim) or ``"temporal_model_adds"`` (HMM modes against the time-free reference grouping,
    and against random groups: what the Markov chain adds beyond one observation);
    ``name`` the claim in words; ``compared`` what the modes are compared against.
    ``p_value``: one-sided Wilcoxon signed-rank over trials of ln(reference / HMM per-trial
    median q) − ``min_effect``; ``effect_size`` the median over trials of that log ratio
    (> 0: modes lower q), ``ci_low``/``ci_high`` its percentile-bootstrap interval;
    ``made``: reachable, p < alpha and effect > ``min_effect``.
    """

    key: str
    name: str
    compared: str
    p_value: float
    effect_size: float
    ci_low: float
    ci_high: float
    ci_level: float
    min_effect: float
    made: bool

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "compared": self.compared, "p_value": self.p_value,
                "effect_size": self.effect_size,
                "ci": {"low": self.ci_low, "high": self.ci_high, "level": self.ci_level},
                "min_effect": self.min_effect, "made": self.made}


@dataclass(frozen=True)
class SegmentationTest:
    """The calibrated "modes add information" test (:mod:`learning.analysis.reference`).

    Units are trials (``unit`` = "trial", ``n_trials`` of them): per trial, the median q
    within HMM modes and within the time-free ``reference`` grouping of the same features
    (same number of groups); one-sided Wilcoxon signed-rank test over trials of
    ln(reference / HMM) − ``min_effect`` (``statistic``, ``reference_p_value``).
    ``effect_size`` is the median over trials of ln(reference / HMM) (> 0: modes lower q),
    ``ci_low``/``ci_high`` its ``ci_level`` percentile-bootstrap interval over trials.
    ``random_*``: the same test against random groups of equal sizes (``n_random`` draws,
    ``random_method``), the paper's reference. ``significant`` (the claim): ``reachable``
    (at least ``min_trials`` trials, else p < ``alpha`` is impossible: 2⁻ⁿ is the smallest p)
    and both tests with p < ``alpha`` and effect > ``min_effect``; ``p_value`` = the larger
    of the two p-values (intersection–union test). The medians ``*_median_q`` are over all
    windows. ``significant`` and ``p_value`` are the claim "the temporal model adds
    information"; ``claims`` holds both claims by key (:class:`Claim`): ``"modes_help"``
    (against random groups alone, smallest effect ``help_effect``) and
    ``"temporal_model_adds"``.
    """

    test: str
    unit: str
    n_trials: int
    statistic: float
    p_value: float
    reference_p_value: float
    reference: str
    hmm_median_q: float
    reference_median_q: float
    random_median_q: float
    effect_size: float
    ci_low: float
    ci_high: float
    ci_level: float
    min_effect: float
    random_p_value: float
    random_effect_size: float
    random_ci_low: float
    random_ci_high: float
    n_random: int
    random_method: str
    reachable: bool
    min_trials: int
    significant: bool
    alpha: float
    effect_size_name: str = "median over trials of ln(reference / HMM median q)"
    claims: dict[str, Claim] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"test": self.test, "unit": self.unit, "n_trials": self.n_trials,
                "statistic": self.statistic, "p_value": self.p_value,
                "reference_p_value": self.reference_p_value, "reference": self.reference,
                "hmm_median_q": self.hmm_median_q, "reference_median_q": self.reference_median_q,
                "random_median_q": self.random_median_q, "effect_size": self.effect_size,
                "effect_size_name": self.effect_size_name,
                "ci": {"low": self.ci_low, "high": self.ci_high, "level": self.ci_level},
                "min_effect": self.min_effect,
                "random": {"p_value": self.random_p_value, "effect_size": self.random_effect_size,
                           "ci": {"low": self.random_ci_low, "high": self.random_ci_high,
                                  "level": self.ci_level},
                           "n_random": self.n_random, "method": self.random_method},
                "n_random": self.n_random, "random_method": self.random_method,
                "reachable": self.reachable, "min_trials": self.min_trials,
                "significant": self.significant, "alpha": self.alpha,
                "claims": {k: c.to_dict() for k, c in self.claims.items()}}


@dataclass(frozen=True)
class VoluntaryShare:
    """The voluntary share (fraction of windows with q > K) at one K, mean over trials.

    ``p_value``: paired one-sided Wilcoxon signed-rank test over trials, share within
    HMM modes < share within the time-free reference grouping (``statistic``,
    ``effect_size`` the matched-pairs rank-biserial correlation); ``p_value_vs_random``,
    ``p_value_vs_without_modes``: the same test against random groups of equal sizes and
    against no modes; ``fold_reduction`` = without / with modes (``None`` when the share
    with modes is 0).
    """

    without_modes: float
    with_modes: float
    reference: float
    random: float
    fold_reduction: float | None
    statistic: float
    p_value: float
    effect_size: float
    test: str
    p_value_vs_random: float
    p_value_vs_without_modes: float
    n_trials: int

    def to_dict(self) -> dict[str, Any]:
        return {"without_modes": self.without_modes, "with_modes": self.with_modes,
                "reference": self.reference, "random": self.random,
                "fold_reduction": self.fold_reduction, "statistic": self.statistic,
                "p_value": self.p_value, "effect_size": self.effect_size, "test": self.test,
                "p_value_vs_random": self.p_value_vs_random,
                "p_value_vs_without_modes": self.p_value_vs_without_modes, "n_trials": self.n_trials}


@dataclass(frozen=True)
class Candidate:
    """One (window, number of modes) candidate of the search for missing information.

    ``gain_beyond_reference_log10``: median over trials of log10(per-trial median q within the
    time-free reference / within modes), the ranking key (``rank`` 1 = largest gain), with
    ``p_value`` its one-sided Wilcoxon test over trials (as the segmentation test);
    ``gain_beyond_random_log10``: the same against random groups (the paper's). The voluntary
    shares at the first K (``share_K``) are written under the key ``voluntary_share_K<K>``.
    """

    window_s: float
    n_modes: int
    median_q_without_modes: float
    median_q_modes: float
    median_q_reference: float
    median_q_random: float
    gain_beyond_reference_log10: float
    p_value: float
    gain_beyond_random_log10: float
    share_K: float
    share_without_modes: float
    share_with_modes: float
    share_reference: float
    share_random: float
    hmm_bic: float
    rank: int = 0

    def to_dict(self) -> dict[str, Any]:
        return {"window_s": self.window_s, "n_modes": self.n_modes,
                "median_q_without_modes": self.median_q_without_modes,
                "median_q_modes": self.median_q_modes, "median_q_reference": self.median_q_reference,
                "median_q_random": self.median_q_random,
                "gain_beyond_reference_log10": self.gain_beyond_reference_log10, "p_value": self.p_value,
                "gain_beyond_random_log10": self.gain_beyond_random_log10,
                f"voluntary_share_K{self.share_K:g}": {"without_modes": self.share_without_modes,
                                                       "with_modes": self.share_with_modes,
                                                       "reference": self.share_reference,
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
