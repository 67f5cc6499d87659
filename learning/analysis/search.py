"""The search for missing information of :func:`learning.analysis.analyze`: every
(window length, number of modes) candidate ranked by how far its HMM modes lower the
per-trial median quotients beyond the time-free reference grouping (and random groups)."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from learning.analysis.predictability import voluntary_share
from learning.analysis.reference import mode_evidence, random_labelings, reference_segmentation
from learning.analysis.report import Candidate
from learning.data import Demonstrations
from learning.lipschitz import default_jobs, pointwise_quotients, pointwise_quotients_multi
from learning.modes import TaskModes
from learning.preprocessing.preprocess import causal_windows

if TYPE_CHECKING:
    from learning.analysis.config import AnalysisConfig

__all__ = ["QuotientCall", "fit_modes", "mean_share", "run_calls", "search_candidates", "search_labelings",
           "within_group_quotients"]


def fit_modes(Z: np.ndarray, lengths: np.ndarray, n_modes: int, config: AnalysisConfig
              ) -> tuple[TaskModes, np.ndarray]:
    """HMM task modes of the per-sample features ``Z`` (trials ``lengths``) and their labels."""
    # Restarts in parallel processes (the result does not depend on it).
    model = TaskModes(n_modes=n_modes, n_restarts=config.hmm_restarts, seed=config.seed,
                      n_jobs=-1).fit(Z, lengths)
    return model, model.predict(Z, lengths)




def search_labelings(window_labels: dict[int, np.ndarray], config: AnalysisConfig) -> np.ndarray:
    """The random groupings the search compares the candidates of one window against:
    ``search_random`` draws per number of modes (``window_labels[n]``: the HMM labels of the
    windows), stacked in the order of ``search_modes`` ((len(search_modes)·R, N)). The draws
    use ``config.seed``, as the main analysis's test does, so at the main window and number
    of modes they are the first R of the test's draws."""
    return np.vstack([random_labelings(window_labels[n], config.search_random, config.random_method, config.seed)
                      for n in config.search_modes])


def _progress_bar(config: AnalysisConfig, todo: list[int], known: dict, known_ref: dict, passes: dict) -> Any:
    """One step per HMM fit, per shared pass and per call within a grouping (those known skipped)."""
    from learning.progress import progress_bar

    n_known = sum(((float(w), int(n)) in known) + ((float(w), int(n)) in known_ref)
                  for w in config.search_windows for n in config.search_modes)
    n_known += sum(float(w) in passes for w in config.search_windows)
    return progress_bar(total=len(todo) + len(config.search_windows) * (1 + 2 * len(config.search_modes)) - n_known,
                desc="search", unit="step", leave=False)


def _plan_calls(std: Demonstrations, config: AnalysisConfig, fitted: dict[int, tuple[TaskModes, np.ndarray]],
                refs: dict[int, np.ndarray], passes: dict[float, np.ndarray], known: dict, known_ref: dict
                ) -> tuple[dict[float, Any], dict[tuple, QuotientCall]]:
    """(windows, quotient calls) of the search: per window a shared pass (no grouping, then every
    candidate's random groupings) unless ``passes`` has it, and a call per grouping (reference,
    modes) not already known; every call goes to one pool, longest first (:func:`run_calls`)."""
    R = config.search_random
    windows, calls = {}, {}
    for window in config.search_windows:
        w = causal_windows(std, window, rms=True)
        windows[window] = w
        Q = passes.get(float(window))
        if Q is None:
            rand = search_labelings({n: fitted[n][1][w.source_index] for n in config.search_modes}, config)
            calls[(window, "pass", 0)] = QuotientCall(
                w.X, w.Y, np.vstack([np.zeros((1, len(w)), np.int64), rand]), multi=True)
        elif Q.shape != (1 + R * len(config.search_modes), len(w)):
            raise ValueError(f"known_pass[{window}] must be ({1 + R * len(config.search_modes)}, {len(w)}) "
                             f"(no grouping, then {R} random groupings per number of modes), got {Q.shape}")
        for n in config.search_modes:
            if (float(window), int(n)) not in known_ref:
                calls[(window, "reference", n)] = QuotientCall(w.X, w.Y, refs[n][w.source_index])
            if (float(window), int(n)) not in known:
                calls[(window, "modes", n)] = QuotientCall(w.X, w.Y, fitted[n][1][w.source_index])
    return windows, calls


def _candidate(window: float, n_modes: int, q0: np.ndarray, share0: float, ev: Any, trial: np.ndarray,
               K0: float, bic: float) -> Candidate:
    """One candidate's row from its evidence (gains in log10, shares at K0)."""
    return Candidate(
        window_s=float(window), n_modes=int(n_modes), median_q_without_modes=float(np.median(q0)),
        median_q_modes=float(np.median(ev.q_modes)),
        median_q_reference=float(np.median(ev.q_reference)),
        median_q_random=float(np.median(ev.q_random)),
        gain_beyond_reference_log10=ev.vs_reference.effect / math.log(10),
        p_value=ev.vs_reference.p_value,
        gain_beyond_random_log10=ev.vs_random.effect / math.log(10),
        share_K=float(K0), share_without_modes=share0, share_with_modes=mean_share(ev.q_modes, trial, K0),
        share_reference=mean_share(ev.q_reference, trial, K0),
        share_random=float(np.mean([mean_share(r, trial, K0) for r in ev.q_random])),
        hmm_bic=bic)


def search_candidates(std: Demonstrations, Z: np.ndarray, lengths: np.ndarray, config: AnalysisConfig,
                      fitted: dict[int, tuple[TaskModes, np.ndarray]], alpha: float,
                      progress: bool = False,
                      known_q_modes: dict[tuple[float, int], np.ndarray] | None = None,
                      known_pass: dict[float, np.ndarray] | None = None,
                      known_q_reference: dict[tuple[float, int], np.ndarray] | None = None,
                      reference_labels: dict[int, np.ndarray] | None = None) -> list[Candidate]:
    """Rank (window, n_modes) candidates by the median over trials of
    log10(median q within the reference / median q within modes) (per-trial inference).

    ``fitted`` holds the HMMs already fitted (by number of modes); the others are fitted
    and added. Per window, the quotients without modes and within every candidate's
    random groupings come from one :func:`pointwise_quotients_multi` pass; within modes
    and within the reference from one :func:`pointwise_quotients` call each; all calls of
    all windows share one schedule, two at a time, longest first (:func:`run_calls`).
    ``known_q_modes`` maps (window [s], n_modes) to quotients within those modes already
    computed on the same windows (the main analysis's), which are then not recomputed;
    ``known_q_reference`` the same for the reference grouping, and ``known_pass`` maps a
    window to the rows of its shared pass (no grouping, then :func:`search_labelings`),
    computed by the caller in its own pass over the same windows; ``reference_labels``
    maps a number of modes to its reference grouping of the samples, already fitted
    (``reference_segmentation`` of those modes with ``config.seed``)."""
    K0 = config.K[0]
    rows = []
    todo = [n for n in config.search_modes if n not in fitted]
    known = known_q_modes or {}
    known_ref = known_q_reference or {}
    passes = known_pass or {}
    bar = _progress_bar(config, todo, known, known_ref, passes) if progress else None
    for n_modes in todo:
        fitted[n_modes] = fit_modes(Z, lengths, n_modes, config)
        if bar is not None:
            bar.update(1)
    R = config.search_random
    # What does not depend on the window, once per number of modes: the time-free
    # reference grouping (a mixture fit) and the HMM's BIC.
    refs = dict(reference_labels or {})
    refs.update(_reference_fits([n for n in config.search_modes if n not in refs], Z, fitted, config))
    bics = {n: float(fitted[n][0].bic(Z, lengths)) for n in config.search_modes}
    windows, calls = _plan_calls(std, config, fitted, refs, passes, known, known_ref)
    done = run_calls(calls, done=None if bar is None else lambda: bar.update(1))
    for window in config.search_windows:
        w = windows[window]
        Q = passes.get(float(window))
        if Q is None:
            Q = done[(window, "pass", 0)]
        q0 = Q[0]
        share0 = mean_share(q0, w.trial, K0)
        for k, n_modes in enumerate(config.search_modes):
            model, labels = fitted[n_modes]
            q_modes = known.get((float(window), int(n_modes)), done.get((window, "modes", n_modes)))
            ev = mode_evidence(w.X, w.Y, w.trial, w.source_index, model.transform(Z), labels,
                               reference=config.reference, n_random=R,
                               random_method=config.random_method, alpha=alpha,
                               min_effect=config.min_effect, seed=config.seed,
                               q_random=Q[1 + k * R:1 + (k + 1) * R], reference_labels=refs[n_modes],
                               q_modes=q_modes,
                               q_reference=known_ref.get((float(window), int(n_modes)),
                                                         done.get((window, "reference", n_modes))))
            rows.append(_candidate(window, n_modes, q0, share0, ev, w.trial, K0, bics[n_modes]))
    if bar is not None:
        bar.close()
    rows.sort(key=lambda r: -r.gain_beyond_reference_log10)
    return [replace(r, rank=rank) for rank, r in enumerate(rows, 1)]


def _reference_fits(modes: list[int], Z: np.ndarray, fitted: dict[int, tuple[TaskModes, np.ndarray]],
                    config: AnalysisConfig) -> dict[int, np.ndarray]:
    """The time-free reference grouping (:func:`reference_segmentation`, ``config.seed``) of each number of modes
    in ``modes``, on the cores side by side (threads: the mixture fits' array work releases the GIL; each fit
    is seeded on its own, so the labels are those of one fit after another)."""
    def one(n: int) -> np.ndarray:
        return reference_segmentation(fitted[n][0].transform(Z), fitted[n][1], config.reference, config.seed)

    if len(modes) < 2 or default_jobs() < 2:
        return {n: one(n) for n in modes}
    with ThreadPoolExecutor(max_workers=min(len(modes), default_jobs())) as pool:
        return dict(zip(modes, pool.map(one, modes)))


@dataclass(frozen=True)
class QuotientCall:
    """One quotient call of the analysis: ``pointwise_quotients(X, Y, labels)`` (labels
    (N,)), or with ``multi`` one :func:`pointwise_quotients_multi` pass over the labelings
    (L, N)."""

    X: np.ndarray
    Y: np.ndarray
    labels: np.ndarray
    multi: bool = False

    def cost(self) -> float:
        """Relative cost for the schedule: the pairs screened (within groups; all pairs,
        about 1.35× as dear a pair, for a shared pass: measured, 107k windows)."""
        if self.multi:
            n = self.labels.shape[1]
            return 1.35 * n * (n - 1) / 2
        _, sizes = np.unique(self.labels, return_counts=True)
        return float(np.sum(sizes.astype(np.float64) * (sizes - 1) / 2))

    def run(self, n_jobs: int) -> np.ndarray:
        if self.multi:
            return pointwise_quotients_multi(self.X, self.Y, self.labels, n_jobs=n_jobs)
        return pointwise_quotients(self.X, self.Y, self.labels, n_jobs=n_jobs)


def run_calls(calls: dict, max_parallel: int = 2, done: Callable[[], None] | None = None) -> dict:
    """The results of every :class:`QuotientCall` of ``calls`` (same keys), up to
    ``max_parallel`` at a time with the cores shared among them, the most expensive first
    (longest-processing-time order: no core waits long at the end for the last call).
    Each call has serial parts (features, k-d leaves) during which its other threads wait;
    two calls side by side fill those gaps (measured on 2 cores, the 107k windows of
    3 × 60 min, the search's 5 groupings of one window with 2, 4 and 6 modes: median 0.88
    of the time one after the other over 3 paired runs, range 0.75–1.06 on this shared
    machine). Two at a time bounds the memory: each call holds its own copies of X and Y in
    pass order. The quotients do not depend on the schedule (exact). ``done()`` is called
    as each call finishes."""
    keys = sorted(calls, key=lambda k: -calls[k].cost())
    if not keys:
        return {}
    cores = default_jobs()
    workers = max(1, min(max_parallel, len(keys), cores))
    threads = max(1, cores // workers)

    def one(key) -> np.ndarray:
        q = calls[key].run(threads)
        if done is not None:
            done()
        return q

    with ThreadPoolExecutor(max_workers=workers) as pool:
        qs = list(pool.map(one, keys))
    return dict(zip(keys, qs))


def within_group_quotients(X: np.ndarray, Y: np.ndarray, groupings: dict, max_parallel: int = 2,
                           done: Callable[[], None] | None = None) -> dict:
    """``pointwise_quotients(X, Y, g)`` for every grouping ``g`` of ``groupings`` (same keys),
    scheduled by :func:`run_calls`."""
    return run_calls({k: QuotientCall(X, Y, np.asarray(g)) for k, g in groupings.items()},
                     max_parallel, done)


def mean_share(q: np.ndarray, trial: np.ndarray, K: float) -> float:
    """Voluntary share at K, mean over trials."""
    return float(np.mean(list(voluntary_share(q, trial, K).values())))
