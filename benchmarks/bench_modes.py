"""Speed of learning.modes: ModeFilter step, offline filtering and TaskModes.fit. Prints JSON.

    python benchmarks/bench_modes.py [--quick]

- ``step``: one ``ModeFilter.step`` (K = 4; D_in = 9 raw, and D_in = 90 windowed with PCA to
  16), p50/p99 [µs] over many calls, with baselines measured in the same process:
  hmmlearn ``predict_proba`` on a 1-sample sequence (what calling hmmlearn per control
  step would cost) and ``scipy.special.logsumexp`` of size K (the cheapest numpy/scipy
  reduction a step needs). Target: p50 ≤ 50 µs.
- ``fit``: ``TaskModes`` defaults on 20k × 9 and 20k × 90 (n_pca = 16) sampled from a
  sticky 4-mode HMM (windowed rows built from it) — time, EM iterations, convergence.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time

import numpy as np
from scipy.special import logsumexp
from threadpoolctl import threadpool_limits

from learning.modes import TaskModes, mode_agreement


def sample(K: int, D: int, n_trials: int, T: int, seed: int = 0, sep: float = 1.0,
           stay: float = 0.97) -> tuple[np.ndarray, np.ndarray, list[int]]:
    rng = np.random.default_rng(seed)
    means = rng.standard_normal((K, D)) * sep
    chols = np.array([np.linalg.cholesky(Q @ Q.T + 0.5 * np.eye(D))
                      for Q in rng.standard_normal((K, D, D)) * 0.3])
    A = np.full((K, K), (1 - stay) / (K - 1))
    np.fill_diagonal(A, stay)
    Xs, Ss = [], []
    for _ in range(n_trials):
        u = rng.random(T)
        s = np.empty(T, dtype=int)
        s[0] = rng.integers(K)
        cum = np.cumsum(A, axis=1)
        for t in range(1, T):
            s[t] = min(int(np.searchsorted(cum[s[t - 1]], u[t])), K - 1)
        Xs.append(means[s] + np.einsum("tij,tj->ti", chols[s], rng.standard_normal((T, D))))
        Ss.append(s)
    return np.concatenate(Xs), np.concatenate(Ss), [T] * n_trials


def windows(X: np.ndarray, lengths: list[int], lags: int) -> tuple[np.ndarray, list[int], np.ndarray]:
    """Causal windows [o_t, o_{t-1}, …] within trials (rows without a full window dropped)."""
    out, lens, keep = [], [], []
    start = 0
    for T in lengths:
        seg = X[start:start + T]
        out.append(np.hstack([seg[lags - 1 - l:T - l] for l in range(lags)]))
        lens.append(T - lags + 1)
        keep.append(np.arange(start + lags - 1, start + T))
        start += T
    return np.vstack(out), lens, np.concatenate(keep)


def percentiles_us(times: np.ndarray) -> dict[str, float]:
    return {"p50_us": float(np.percentile(times, 50) * 1e6),
            "p99_us": float(np.percentile(times, 99) * 1e6),
            "mean_us": float(times.mean() * 1e6)}


def time_calls(fn, args_list, repeat: int) -> np.ndarray:
    out = np.empty(repeat)
    n = len(args_list)
    for i in range(repeat):
        a = args_list[i % n]
        t0 = time.perf_counter()
        fn(a)
        out[i] = time.perf_counter() - t0
    return out


def bench_step(m: TaskModes, X: np.ndarray, repeat: int, fixed_lags=(0, 5)) -> dict:
    res: dict = {"input_dim": int(X.shape[1]), "model_dim": int(m.n_components_),
                 "n_modes": int(m.n_modes)}
    rows = list(X[:2000])
    for lag in fixed_lags:
        f = m.make_filter(fixed_lag=lag)
        time_calls(f.step, rows, 2000)  # warm-up
        res[f"step_lag{lag}"] = percentiles_us(time_calls(f.step, rows, repeat))
    # baselines, same process
    Z1 = [m.transform(r[None, :]) for r in rows[:200]]
    with threadpool_limits(limits=1):
        res["baseline_hmmlearn_predict_proba_1_sample"] = percentiles_us(
            time_calls(m.model_.predict_proba, Z1, max(repeat // 20, 200)))
    v = [np.random.default_rng(0).standard_normal(m.n_modes) for _ in range(100)]
    res["baseline_scipy_logsumexp_K"] = percentiles_us(time_calls(logsumexp, v, repeat))
    s = res["step_lag0"]["p50_us"]
    res["ratio_hmmlearn_over_step_p50"] = \
        res["baseline_hmmlearn_predict_proba_1_sample"]["p50_us"] / s
    res["ratio_step_over_logsumexp_p50"] = s / res["baseline_scipy_logsumexp_K"]["p50_us"]
    res["step_target_p50_us"] = 50.0
    res["step_meets_target"] = bool(s <= 50.0)
    return res


def bench_fit(X, S, lengths, **params) -> tuple[dict, TaskModes]:
    t0 = time.perf_counter()
    m = TaskModes(**params).fit(X, lengths)
    dt = time.perf_counter() - t0
    t1 = time.perf_counter()
    pred = m.predict(X, lengths)
    t_pred = time.perf_counter() - t1
    t2 = time.perf_counter()
    filt = m.filter_proba(X, lengths)
    t_filt = time.perf_counter() - t2
    return {"shape": list(X.shape), "params": {k: v for k, v in params.items()},
            "fit_s": dt, "n_iter": int(m.n_iter_), "converged": bool(m.converged_),
            "restarts": int(m.n_restarts), "predict_viterbi_s": t_pred,
            "filter_proba_s": t_filt,
            "agreement_viterbi": mode_agreement(pred, S)[0],
            "agreement_filtered": mode_agreement(filt.argmax(1), S)[0]}, m


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer samples and repetitions")
    args = ap.parse_args()
    repeat = 5000 if args.quick else 50_000
    n_trials, T = (8, 500) if args.quick else (40, 500)  # 20k samples
    out: dict = {"python": sys.version.split()[0], "machine": platform.machine(),
                 "n_samples": n_trials * T}

    X9, S9, L9 = sample(4, 9, n_trials, T, seed=0)
    fit9, m9 = bench_fit(X9, S9, L9, n_modes=4)
    out["fit_raw_9"] = fit9
    out["step_raw_9"] = bench_step(m9, X9, repeat)

    Xw, Lw, keep = windows(X9, L9, 10)  # 90-dim causal windows of the same signal
    fit90, m90 = bench_fit(Xw, S9[keep], Lw, n_modes=4, n_pca=16)
    out["fit_windowed_90_pca16"] = fit90
    out["step_windowed_90_pca16"] = bench_step(m90, Xw, repeat)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
