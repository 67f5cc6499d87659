"""The predictability analysis of Song & Asada, end to end, on any data set.

1. preprocessing: downsample, standardise (fitted on the data), causal windows normalised by √L
   (:func:`learning.preprocessing.preprocess.causal_windows` with ``rms=True``);
2. HMM task modes on the per-sample observations; quotients q_i = max_j ‖Δu‖/‖Δo‖ without modes
   (K at percentiles 50…100) and within the random groupings in one pass over the pairs
   (:func:`learning.lipschitz.pointwise_quotients_multi`);
3. quotients within modes and within the time-free reference grouping; the two claims "modes
   help" and "the temporal model adds information", each a one-sided Wilcoxon signed-rank test
   over trials (:mod:`learning.analysis.reference`);
4. the voluntary share (fraction of windows with q > K) per trial at each K, without modes, within
   modes, the reference and random groups; paired one-sided Wilcoxon test, modes vs reference;
5. a search for missing information (:mod:`learning.analysis.search`): (window length, number of
   modes) candidates ranked by how far their modes lower the per-trial median q beyond the reference.

:func:`analyze` returns an :class:`AnalysisResult`: the findings as an
:class:`~learning.analysis.report.AnalysisReport` (schema: docs/design.md) and the arrays the plots
need (drawn by :mod:`mpcshare.reports.analysis`). Data it cannot analyse with the settings (rate
below ``target_hz``, trials too short for the window) raise :class:`AnalysisError`.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict
from typing import Any

import numpy as np

from learning.analysis.config import MIN_EFFECT, SIGNIFICANCE, AnalysisConfig, AnalysisError
from learning.analysis.predictability import paired_wilcoxon, threshold_from_percentile, voluntary_share
from learning.analysis.reference import (
    min_trials_for,
    mode_evidence,
    random_labelings,
    reference_segmentation,
)
from learning.analysis.report import (
    AnalysisReport,
    Claim,
    ModesSummary,
    QuotientStats,
    SegmentationTest,
    VoluntaryShare,
)
from learning.analysis.result import AnalysisResult
from learning.analysis.search import fit_modes, search_candidates, search_labelings, within_group_quotients
from learning.data import Demonstrations
from learning.lipschitz import pointwise_quotients_multi
from learning.modes import TaskModes, mode_agreement, mode_ari, select_n_modes
from learning.preprocessing.preprocess import (
    Preprocessor,
    Standardizer,
    WindowedData,
    causal_windows,
    downsample,
    window_lags,
)

__all__ = ["AnalysisConfig", "AnalysisResult", "AnalysisError", "analyze", "MIN_EFFECT", "SIGNIFICANCE"]


def _finite_stats(q: np.ndarray, K_by_percentile: dict[str, float | None] | None = None) -> QuotientStats:
    """p50, p90, p99 and max of quotients; an infinite value is reported as None (JSON null)."""
    return QuotientStats(p50=_json_float(np.percentile(q, 50)), p90=_json_float(np.percentile(q, 90)),
                         p99=_json_float(np.percentile(q, 99)), max=_json_float(np.max(q)),
                         n_inf=int(np.isinf(q).sum()), K_by_percentile=K_by_percentile)


def _json_float(x: float) -> float | None:
    return None if not math.isfinite(x) else float(x)


class _Steps:
    """A step-level progress bar (tqdm) with timings for the report."""

    def __init__(self, total: int, enabled: bool, start: float | None = None) -> None:
        self.bar = None
        if enabled:
            from learning.progress import progress_bar
            self.bar = progress_bar(total=total, desc="analysis", unit="step")
        self.timings: dict[str, float] = {}
        self._t = time.perf_counter() if start is None else start

    def done(self, name: str) -> None:
        now = time.perf_counter()
        self.timings[name] = round(now - self._t, 3)
        self._t = now
        if self.bar is not None:
            self.bar.set_postfix_str(f"{name} done")
            self.bar.update(1)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _shares(q: np.ndarray, trial: np.ndarray, K: float, ids: np.ndarray) -> np.ndarray:
    """Voluntary share at K of each trial in ``ids`` (that order)."""
    by_trial = voluntary_share(q, trial, K)
    return np.array([by_trial[i] for i in ids])


def _check_windows(std: Demonstrations, config: AnalysisConfig) -> None:
    """Every window (analysis and search) must fit in the longest trial: checked
    before any long work starts, not when the search reaches that window."""
    longest = max(len(tr) for tr in std.trials)
    for name, window in [("window", config.window_s)] + [("search window", w) for w in config.search_windows]:
        L = window_lags(window, std.rate_hz)
        if L > longest:
            raise AnalysisError(
                f"{name} {window:g} s ({L} samples at {std.rate_hz:g} Hz) is longer than the longest "
                f"trial ({longest} samples = {longest / std.rate_hz:g} s); use a shorter window")


def _preprocess(demos: Demonstrations, config: AnalysisConfig) -> tuple[Demonstrations, WindowedData]:
    """Downsampled and standardised data, and its causal windows (normalised by √L)."""
    try:
        low = downsample(demos, config.target_hz) if demos.rate_hz != config.target_hz else demos
    except ValueError as exc:  # a trial too short to keep 2 samples
        raise AnalysisError(str(exc)) from exc
    pre = Preprocessor(obs=Standardizer(config.scope, field="obs").fit(low),
                       act=Standardizer(config.scope, field="act").fit(low),
                       target_hz=config.target_hz, window_s=config.window_s)
    std = pre.standardize(low)
    _check_windows(std, config)
    return std, causal_windows(std, config.window_s, rms=True)


def _voluntary_shares(trial: np.ndarray, q: np.ndarray, q_modes: np.ndarray, q_ref: np.ndarray,
                      q_random: np.ndarray, config: AnalysisConfig
                      ) -> tuple[dict[str, VoluntaryShare], dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """The voluntary share (fraction of windows with q > K) per trial at each K, and its paired test.

    Quotients within any grouping can only fall (fewer partners), so the paired test that
    means something is HMM modes against the time-free reference ("p_value"); against random
    groups and no modes are reported too.
    """
    share_report: dict[str, VoluntaryShare] = {}
    shares: dict[float, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    for K in config.K:
        by_trial = voluntary_share(q_modes, trial, K)
        ids = np.array(list(by_trial))
        with_m = np.array([by_trial[i] for i in ids])
        without = _shares(q, trial, K, ids)
        ref_share = _shares(q_ref, trial, K, ids)
        rand = np.mean([_shares(r, trial, K, ids) for r in q_random], axis=0)
        stat, p, eff = paired_wilcoxon(with_m, ref_share, alternative="less")
        shares[K] = (ids, without, with_m)
        mean_without, mean_with = float(np.mean(without)), float(np.mean(with_m))
        share_report[f"{K:g}"] = VoluntaryShare(
            without_modes=mean_without, with_modes=mean_with, reference=float(np.mean(ref_share)),
            random=float(np.mean(rand)),
            fold_reduction=_json_float(mean_without / mean_with) if mean_with > 0 else None,
            statistic=stat, p_value=p, effect_size=eff,
            test=f"wilcoxon signed-rank over trials, one-sided: share within HMM modes < share within "
                 f"the {config.reference} reference",
            p_value_vs_random=paired_wilcoxon(with_m, rand, alternative="less")[1],
            p_value_vs_without_modes=paired_wilcoxon(with_m, without, alternative="less")[1],
            n_trials=int(len(ids)))
    return share_report, shares


def _claims(ev: Any, config: AnalysisConfig) -> dict[str, Claim]:
    """The two claims of :func:`~learning.analysis.reference.mode_evidence`, by key."""
    h, t = ev.modes_help, ev.vs_reference
    return {
        "modes_help": Claim(
            key="modes_help", name="modes help", compared="random groups of equal sizes",
            p_value=float(h.p_value), effect_size=float(h.effect), ci_low=float(h.ci_low),
            ci_high=float(h.ci_high), ci_level=float(h.ci_level), min_effect=float(config.help_effect),
            made=bool(h.claimed)),
        "temporal_model_adds": Claim(
            key="temporal_model_adds", name="the temporal model adds information",
            compared=f"the time-free {config.reference} reference grouping (and random groups)",
            p_value=float(ev.p_value), effect_size=float(t.effect), ci_low=float(t.ci_low),
            ci_high=float(t.ci_high), ci_level=float(t.ci_level), min_effect=float(config.min_effect),
            made=bool(ev.claimed))}


def _segmentation_test(ev: Any, config: AnalysisConfig) -> SegmentationTest:
    """The report's record of :func:`~learning.analysis.reference.mode_evidence`'s tests."""
    t_ref, t_rand = ev.vs_reference, ev.vs_random
    q_modes, q_ref, q_random = ev.q_modes, ev.q_reference, ev.q_random
    return SegmentationTest(
        test=f"wilcoxon signed-rank over trials, one-sided: ln(reference / HMM per-trial median q) "
             f"> {config.min_effect:.4g}, for the time-free reference and for random groups (both)",
        unit="trial", n_trials=int(t_ref.n_trials), statistic=float(t_ref.statistic),
        p_value=float(ev.p_value), reference_p_value=float(t_ref.p_value), reference=config.reference,
        hmm_median_q=float(np.median(q_modes)), reference_median_q=float(np.median(q_ref)),
        random_median_q=float(np.median(q_random)),
        effect_size=float(t_ref.effect), ci_low=float(t_ref.ci_low), ci_high=float(t_ref.ci_high),
        ci_level=float(t_ref.ci_level), min_effect=float(config.min_effect),
        random_p_value=float(t_rand.p_value), random_effect_size=float(t_rand.effect),
        random_ci_low=float(t_rand.ci_low), random_ci_high=float(t_rand.ci_high),
        n_random=int(config.n_random), random_method=config.random_method,
        reachable=bool(t_ref.reachable), min_trials=min_trials_for(SIGNIFICANCE),
        significant=bool(ev.claimed), alpha=SIGNIFICANCE, claims=_claims(ev, config))


def _search_rows(search_rand: np.ndarray, rand: np.ndarray, config: AnalysisConfig
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Where the search's random groupings at the main window go in the main pass, whose
    rows are: no grouping, the test's draws ``rand``, then the returned new rows. At the
    main number of modes the search's R draws are the first R of the test's (same labels,
    same seed; checked) and are reused; the others are new. Returns (new rows, the indices
    of the main pass's rows that make the search's pass: no grouping, then R per number of
    modes)."""
    R = config.search_random
    new, index = [], [0]
    nxt = 1 + len(rand)
    for k, n in enumerate(config.search_modes):
        block = search_rand[k * R:(k + 1) * R]
        if n == config.n_modes and R <= len(rand) and np.array_equal(block, rand[:R]):
            index.extend(range(1, 1 + R))
        else:
            new.append(block)
            index.extend(range(nxt, nxt + R))
            nxt += R
    rows = np.vstack(new) if new else np.zeros((0, search_rand.shape[1]), np.int64)
    return rows, np.asarray(index)


def _check_settings(demos: Demonstrations, config: AnalysisConfig) -> None:
    """AnalysisError where the data cannot be analysed with ``config`` (rate, trials for select_modes)."""
    if demos.rate_hz < config.target_hz:
        raise AnalysisError(f"data rate {demos.rate_hz:g} Hz is below the analysis rate "
                            f"{config.target_hz:g} Hz; lower --rate")
    if config.select_modes and len(demos.trials) < 2:
        raise AnalysisError(f"choosing the number of modes (select_modes) holds out whole trials and needs "
                            f"at least 2 trials, the data have {len(demos.trials)}")


def _modes_summary(model: TaskModes, modes: np.ndarray, true: np.ndarray | None, Z: np.ndarray,
                   lengths: np.ndarray, config: AnalysisConfig) -> ModesSummary:
    """The fitted HMM's figures: occupancy, fit, restarts, and its agreement with the labels (if any)."""
    agreement = ari = None
    if true is not None:
        agreement = float(mode_agreement(modes, true)[0])
        ari = float(mode_ari(modes, true))
    return ModesSummary(
        n_modes=int(config.n_modes), agreement=agreement, ari=ari,
        occupancy=[float(np.mean(modes == k)) for k in range(config.n_modes)],
        converged=bool(model.converged_), loglik=float(model.loglik_), bic=float(model.bic(Z, lengths)),
        restart_logliks=[float(v) for v in model.restart_logliks_],
        restart_ari=[float(v) for v in model.restart_ari_])


def _select_modes(Z: np.ndarray, lengths: np.ndarray, config: AnalysisConfig, progress: bool, steps: Any) -> Any:
    """The number of modes chosen by held-out likelihood over whole trials (``select_n_modes``)."""
    sel = select_n_modes(Z, lengths, candidates=config.search_modes or range(2, 7), cv=3,
                         seed=config.seed, n_restarts=min(config.hmm_restarts, 2), progress=progress)
    steps.done("mode selection")
    return sel


def _fit_all_modes(Z: np.ndarray, lengths: np.ndarray, config: AnalysisConfig, shared: bool
                   ) -> dict[int, tuple[TaskModes, np.ndarray]]:
    """The HMM of ``config.n_modes`` and, where the search shares the main pass (``shared``), those
    of its other numbers of modes: number of modes → (model, per-sample labels)."""
    fitted = {config.n_modes: fit_modes(Z, lengths, config.n_modes, config)}
    for n in config.search_modes if shared else ():
        if n not in fitted:
            fitted[n] = fit_modes(Z, lengths, n, config)
    return fitted


def _shared_pass(w: WindowedData, rand: np.ndarray, fitted: dict[int, tuple[TaskModes, np.ndarray]],
                 config: AnalysisConfig, shared: bool, progress: bool) -> tuple[np.ndarray, dict[float, np.ndarray]]:
    """(Q, known_pass): the quotients without modes (row 0), within the test's random groupings
    ``rand`` and, where ``shared``, within the search's random groupings at this window, in one
    pass over the pairs (:func:`pointwise_quotients_multi`, each row equal to its own call); the
    search's rows keyed by the window, so that the search does not pass over these windows again."""
    extra = np.zeros((0, len(w)), np.int64)
    if shared:
        search_rand = search_labelings({n: fitted[n][1][w.source_index] for n in config.search_modes}, config)
        extra, search_rows = _search_rows(search_rand, rand, config)
    Q = pointwise_quotients_multi(w.X, w.Y, np.vstack([np.zeros((1, len(w)), np.int64), rand, extra]),
                                  progress=progress)
    return Q, ({float(config.window_s): Q[search_rows]} if shared else {})


def _mode_tests(w: WindowedData, Z: np.ndarray, model: TaskModes, labels: np.ndarray, modes: np.ndarray,
                q_random: np.ndarray, config: AnalysisConfig) -> tuple[Any, np.ndarray]:
    """(evidence, reference labels): the quotients within the modes and within the time-free reference
    (two calls side by side) and the two tests against random groups and the reference."""
    features = model.transform(Z)
    ref_labels = reference_segmentation(features, labels, config.reference, config.seed)
    within = within_group_quotients(w.X, w.Y, {"modes": modes, "reference": ref_labels[w.source_index]})
    ev = mode_evidence(w.X, w.Y, w.trial, w.source_index, features, labels,
                       reference=config.reference, n_random=config.n_random,
                       random_method=config.random_method, alpha=SIGNIFICANCE, min_effect=config.min_effect,
                       help_effect=config.help_effect, seed=config.seed, q_random=q_random,
                       q_modes=within["modes"], reference_labels=ref_labels, q_reference=within["reference"])
    return ev, ref_labels


def analyze(demos: Demonstrations, config: AnalysisConfig | None = None, *,
            progress: bool = False) -> AnalysisResult:
    """Run the whole predictability analysis (see module docstring).

    Args:
        demos: the demonstrations (any rate ≥ ``config.target_hz``).
        config: settings; defaults are the paper's.
        progress: show progress bars (steps, and the quotient engine's).

    Raises:
        AnalysisError: the data cannot be analysed with these settings (rate
            below ``target_hz``, a trial too short to downsample, no trial as
            long as the window or a search window, ``select_modes`` with one trial).
    """
    config = config or AnalysisConfig()
    _check_settings(demos, config)
    n_search = len(config.search_windows) * len(config.search_modes)
    t_start = time.perf_counter()

    # 1. preprocessing (and every check on the data, before the progress bar starts)
    std, w = _preprocess(demos, config)
    steps = _Steps(5 + bool(n_search) + config.select_modes, progress, start=t_start)
    steps.done("preprocess")

    # 2. HMM modes
    Z, lengths = std.obs_sequences()
    # the search's other numbers of modes too, where its random groupings join step 3's pass
    shared = bool(n_search) and float(config.window_s) in {float(v) for v in config.search_windows}
    fitted = _fit_all_modes(Z, lengths, config, shared)
    model, labels = fitted[config.n_modes]
    modes = labels[w.source_index]
    true = w.mode if w.mode is not None and np.any(w.mode >= 0) else None
    steps.done("modes")

    # 3. quotients without modes and within random groupings (the test's and the search's), one pass
    rand = random_labelings(modes, config.n_random, config.random_method, config.seed)
    Q, known_pass = _shared_pass(w, rand, fitted, config, shared, progress)
    q = Q[0]
    K_by_percentile = {f"{p:g}": _json_float(threshold_from_percentile(q, p)) for p in config.percentiles}
    steps.done("quotients")

    # 4. quotients within modes and within the time-free reference; the two tests
    ev, ref_labels = _mode_tests(w, Z, model, labels, modes, Q[1:1 + len(rand)], config)
    q_modes, q_ref, q_random = ev.q_modes, ev.q_reference, ev.q_random
    steps.done("segmentation test")

    # 5. voluntary share per trial: without modes, within modes, the reference, random groups
    share_report, shares = _voluntary_shares(w.trial, q, q_modes, q_ref, q_random, config)
    steps.done("voluntary share")

    # 6. search for missing information, and the number of modes chosen on held-out trials
    main = (float(config.window_s), int(config.n_modes))
    candidates = (search_candidates(std, Z, lengths, config, fitted, SIGNIFICANCE, progress,
                                    known_q_modes={main: q_modes}, known_q_reference={main: q_ref},
                                    known_pass=known_pass, reference_labels={config.n_modes: ref_labels})
                  if n_search else [])
    if n_search:
        steps.done("search")
    selection = _select_modes(Z, lengths, config, progress, steps) if config.select_modes else None
    steps.close()

    summary = AnalysisReport(
        n_samples=int(len(w)), n_trials=int(len(np.unique(w.trial))),
        input_dim=int(w.X.shape[1]), output_dim=int(w.Y.shape[1]),
        rate_hz=float(config.target_hz), window_s=float(config.window_s), lags=int(w.lags), scope=config.scope,
        quotients=_finite_stats(q, K_by_percentile),
        quotients_with_modes=_finite_stats(q_modes),
        modes=_modes_summary(model, modes, true, Z, lengths, config),
        segmentation_test=_segmentation_test(ev, config),
        voluntary_share=share_report,
        candidates=candidates,
        mode_selection=selection,
        config={k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(config).items()},
        timings_s=steps.timings,
    )
    return AnalysisResult(summary=summary, config=config, windows=w, q=q, q_modes=q_modes,
                          q_reference=q_ref, q_random=q_random, modes=modes, features=Z,
                          sample_modes=labels, true_modes=true, mode_model=model,
                          shares=shares)
