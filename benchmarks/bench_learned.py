"""Speed and accuracy of the learned parts (learning.gates.gate, learning.predictor). Prints JSON.

    python benchmarks/bench_learned.py [--quick] [--subjects 3] [--minutes 10] [--seed 0] [--single-regime]

Data: the generator's demonstrations (default 3 subjects × 10 min), causal 10 Hz
(``causal_downsample``), standardised per sensor on the training trials, RMS windows of
1 s; task modes from ``TaskModes`` (4 modes, fitted on the training trials' samples),
causal posterior by ``filter_proba``, gate mode = its argmax. Labels Z = 1 where the
within-mode quotient (``pointwise_quotients`` grouped by mode, all trials) ≤ K, K the
given percentile of the training rows' quotients. Every fourth trial is held out.

- ``gates``: per percentile (90, 50), fit time and held-out accuracy / F1 / Brier of
  ``ModeGates`` with ``max_samples_per_mode`` 1000, 2000 (default), 5000 and all rows, and
  of ``kernel="nystroem"`` on all rows; ``cost_of_default`` = default − all rows.
- ``proba_one``: p50/p99 [µs] of ``ModeGates.proba_one`` (default gates, 50th percentile)
  against ``ModeGates.predict_proba`` on one row and against the fitted scikit-learn
  ``CalibratedClassifierCV.predict_proba`` of one mode on one row (baselines, same
  process), their ratios; max |difference| over held-out rows.
- ``predictor``: ``ReactivePredictor`` defaults trained on R (reactive steps at the 90th
  percentile) and on all steps, and ``RidgeWindowBaseline`` on R: fit time, epochs,
  held-out RMSE on R and on all steps (standardised and per physical group).
- ``stream``: p50/p99 [µs] of ``PredictorStream.step`` against a torch step of the same
  network (``lstm`` on a (1, 1, d) tensor with carried state + ``head``, no_grad) and the
  ratio; max |stream − predict| over a held-out trial.
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from learning.gates.gate import ModeGates
from learning.gates.metrics import gate_metrics
from learning.lipschitz import pointwise_quotients
from learning.modes import TaskModes
from learning.predictor import ReactivePredictor, RidgeWindowBaseline, rmse_by_group
from learning.preprocessing.preprocess import Preprocessor, Standardizer, causal_windows
from learning.preprocessing.resample import causal_downsample
from sim.demonstrator import GeneratorConfig, generate_demonstrations


def percentiles_us(t: np.ndarray) -> dict[str, float]:
    return {"p50_us": float(np.percentile(t, 50) * 1e6), "p99_us": float(np.percentile(t, 99) * 1e6)}


def time_calls(fn, args: list[tuple], repeat: int = 1) -> np.ndarray:
    out = []
    for _ in range(repeat):
        for a in args:
            t0 = time.perf_counter()
            fn(*a)
            out.append(time.perf_counter() - t0)
    return np.array(out)


def prepare(subjects: int, minutes: float, seed: int, single_regime: bool = False) -> dict:
    config = GeneratorConfig(single_regime=single_regime)
    demos = causal_downsample(generate_demonstrations(subjects, minutes, seed, config=config))
    ids = demos.trial_ids
    test_ids = ids[3::4]
    train_ids = [i for i in ids if i not in test_ids]
    train = demos.select(train_ids)
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(train),
                       act=Standardizer("sensor", field="act").fit(train), target_hz=10.0, window_s=1.0)
    std = pre.standardize(demos)
    t0 = time.perf_counter()
    tr_std = std.select(train_ids)
    modes = TaskModes(n_modes=4, seed=seed).fit(np.vstack([t.obs for t in tr_std.trials]),
                                                [len(t) for t in tr_std.trials])
    t_modes = time.perf_counter() - t0
    post = [modes.filter_proba(t.obs) for t in std.trials]
    w = causal_windows(std, 1.0, rms=True)
    post_rows = np.vstack(post)[w.source_index]
    m = post_rows.argmax(axis=1)
    t0 = time.perf_counter()
    q = pointwise_quotients(w.X, w.Y, groups=m)
    t_q = time.perf_counter() - t0
    is_train = np.isin(w.trial, train_ids)
    return {"demos": demos, "std": std, "pre": pre, "post": post, "w": w, "mode": m, "q": q,
            "is_train": is_train, "train_ids": train_ids, "test_ids": test_ids,
            "timings": {"task_modes_fit_s": t_modes, "quotients_s": t_q}}


def bench_gates(d: dict, percentiles: tuple[float, ...], caps: tuple, quick: bool) -> dict:
    w, m, q, tr = d["w"], d["mode"], d["q"], d["is_train"]
    out: dict = {}
    for pct in percentiles:
        K = float(np.percentile(q[tr], pct))
        Z = (q <= K).astype(int)
        rows = {}
        variants = [("rbf", c) for c in caps] + ([] if quick else [("nystroem", None)])
        for kernel, cap in variants:
            name = f"{kernel}_{cap if cap is not None else 'all'}"
            t0 = time.perf_counter()
            g = ModeGates(kernel=kernel, max_samples_per_mode=cap).fit(w.X[tr], m[tr], Z[tr], 4)
            fit_s = time.perf_counter() - t0
            res = gate_metrics(g, w.X[~tr], m[~tr], Z[~tr])
            rows[name] = {"fit_s": fit_s, "n_train": g.n_train_, "constant_modes": sorted(g.constant_modes_),
                          **{k: res["overall"][k] for k in ("accuracy", "f1", "brier")},
                          "per_mode": {j: {k: r[k] for k in ("n", "accuracy", "f1", "brier")}
                                       for j, r in res["per_mode"].items()}}
            print(f"gates {pct} {name}: {fit_s:.1f} s acc {rows[name]['accuracy']:.4f}", file=sys.stderr)
        entry = {"K": K, "positive_share_train": float(Z[tr].mean()), "variants": rows}
        if "rbf_2000" in rows and "rbf_all" in rows:
            entry["cost_of_default"] = {k: rows["rbf_2000"][k] - rows["rbf_all"][k]
                                        for k in ("accuracy", "f1", "brier")}
        out[str(pct)] = entry
    return out


def bench_proba_one(d: dict, pct: float, n_calls: int) -> dict:
    w, m, q, tr = d["w"], d["mode"], d["q"], d["is_train"]
    Z = (q <= np.percentile(q[tr], pct)).astype(int)
    g = ModeGates().fit(w.X[tr], m[tr], Z[tr], 4)
    Xt, mt = w.X[~tr][:n_calls], m[~tr][:n_calls]
    fast = time_calls(g.proba_one, list(zip(Xt, mt.tolist())))
    slow = time_calls(lambda x, j: g.predict_proba(x[None], np.array([j])), list(zip(Xt, mt.tolist())))
    sk = next(j for j in range(4) if j not in g.constant_modes_)
    sk_rows = [(x,) for x in Xt[:200]]
    raw = time_calls(lambda x: g.gates_[sk].predict_proba(x[None])[0, 1], sk_rows)
    one = time_calls(lambda x: g.proba_one(x, sk), sk_rows)
    ref = g.predict_proba(Xt, mt)
    diff = max(abs(g.proba_one(x, j) - r) for x, j, r in zip(Xt, mt.tolist(), ref))
    return {"percentile": pct, "proba_one": percentiles_us(fast), "predict_proba_one_row": percentiles_us(slow),
            "speedup_p50": float(np.median(slow) / np.median(fast)), "max_abs_diff": float(diff),
            "sklearn_calibrated_one_row_mode": sk, "sklearn_calibrated_one_row": percentiles_us(raw),
            "proba_one_same_mode": percentiles_us(one),
            "speedup_vs_sklearn_p50": float(np.median(raw) / np.median(one)),
            "distinct_support_vectors": [None if f is None else int(f.centers.shape[0]) for f in g._fast],
            "support_vectors_over_folds": [None if f is None else int((f.weights != 0).sum()) for f in g._fast],
            "target_us": 300}


def sequences(d: dict, pct: float) -> dict:
    """Per-trial inputs concat(o_t, p_t), targets, R masks (False where no window / no label)."""
    std, post, w, q, tr = d["std"], d["post"], d["w"], d["q"], d["is_train"]
    K = float(np.percentile(q[tr], pct))
    reactive = np.zeros(std.n_samples, bool)
    reactive[w.source_index] = q <= K
    xs, ys, ms, ids, start = [], [], [], [], 0
    for t, p in zip(std.trials, post):
        n = len(t)
        xs.append(np.hstack([t.obs, p]))
        ys.append(t.act)
        ms.append(reactive[start:start + n])
        ids.append(t.trial_id)
        start += n
    return {"xs": xs, "ys": ys, "ms": ms, "ids": ids, "K": K}


def heldout_rmse(model, s: dict, test: list[int], pre: Preprocessor, names: list[str]) -> dict:
    pred = [model.predict(s["xs"][i]) for i in test]
    y = [s["ys"][i] for i in test]
    mk = [s["ms"][i] for i in test]
    P, Y, M = np.vstack(pred), np.vstack(y), np.concatenate(mk)
    phys_p, phys_y = pre.act.inverse_transform(P), pre.act.inverse_transform(Y)
    return {"rmse_R_std": float(np.sqrt(np.mean((P[M] - Y[M]) ** 2))),
            "rmse_all_std": float(np.sqrt(np.mean((P - Y) ** 2))),
            "rmse_R": rmse_by_group(phys_y[M], phys_p[M], names),
            "rmse_all": rmse_by_group(phys_y, phys_p, names)}


def bench_predictor(d: dict, pct: float, quick: bool) -> tuple[dict, ReactivePredictor, dict]:
    s = sequences(d, pct)
    pos = {tid: k for k, tid in enumerate(s["ids"])}
    train = [pos[i] for i in d["train_ids"]]
    test = [pos[i] for i in d["test_ids"]]
    names = list(d["demos"].act_names)
    def sub(key: str, idx: list[int]) -> list:
        return [s[key][i] for i in idx]

    out: dict = {"K": s["K"], "train_steps": int(sum(len(s["xs"][i]) for i in train)),
                 "train_reactive_steps": int(sum(s["ms"][i].sum() for i in train)),
                 "input_dim": int(s["xs"][0].shape[1]), "torch_threads": 1}
    kw = {"max_epochs": 20} if quick else {}
    # warm-up: torch's first forward/backward pays one-off set-up costs
    ReactivePredictor(max_epochs=1).fit(sub("xs", train[:2]), sub("ys", train[:2]), progress=False)
    t0 = time.perf_counter()
    lstm = ReactivePredictor(**kw).fit(sub("xs", train), sub("ys", train), sub("ms", train), progress=False)
    out["lstm_R"] = {"fit_s": time.perf_counter() - t0, "epochs": lstm.n_epochs_, "best_epoch": lstm.best_epoch_,
                     **heldout_rmse(lstm, s, test, d["pre"], names)}
    print(f"lstm R: {out['lstm_R']['fit_s']:.1f} s", file=sys.stderr)
    t0 = time.perf_counter()
    lstm_all = ReactivePredictor(**kw).fit(sub("xs", train), sub("ys", train), None, progress=False)
    out["lstm_all"] = {"fit_s": time.perf_counter() - t0, "epochs": lstm_all.n_epochs_,
                       "best_epoch": lstm_all.best_epoch_, **heldout_rmse(lstm_all, s, test, d["pre"], names)}
    t0 = time.perf_counter()
    ridge = RidgeWindowBaseline().fit(sub("xs", train), sub("ys", train), sub("ms", train))
    out["ridge_R"] = {"fit_s": time.perf_counter() - t0, **heldout_rmse(ridge, s, test, d["pre"], names)}
    return out, lstm, {"x": s["xs"][test[0]]}


def bench_stream(model: ReactivePredictor, x: np.ndarray, repeat: int) -> dict:
    stream = model.make_stream()
    diff = float(np.abs(np.array([stream.step(r) for r in x]) - model.predict(x)).max())
    stream.reset()
    t_np = time_calls(stream.step, [(r,) for r in x], repeat)
    net = model.net_.cpu().eval()
    state = [None]

    def torch_step(r: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            h, state[0] = net.lstm(torch.as_tensor(r, dtype=torch.float32)[None, None], state[0])
            return net.head(h)[0, 0].numpy()

    t_torch = time_calls(torch_step, [(r,) for r in x], repeat)
    return {"numpy_step": percentiles_us(t_np), "torch_step": percentiles_us(t_torch),
            "speedup_p50": float(np.median(t_torch) / np.median(t_np)), "max_abs_diff_vs_predict": diff,
            "target_us": 200}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="2 subjects × 3 min, fewer variants and epochs")
    ap.add_argument("--subjects", type=int, default=None)
    ap.add_argument("--minutes", type=float, default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--single-regime", action="store_true", help="generator without task modes")
    a = ap.parse_args()
    subjects = a.subjects or (2 if a.quick else 3)
    minutes = a.minutes or (3.0 if a.quick else 10.0)
    torch.set_num_threads(1)
    d = prepare(subjects, minutes, a.seed, a.single_regime)
    w = d["w"]
    caps = (1000, 2000, None) if a.quick else (1000, 2000, 5000, None)
    result = {
        "data": {"subjects": subjects, "minutes": minutes, "seed": a.seed, "single_regime": a.single_regime,
                 "windows": len(w),
                 "window_dim": int(w.X.shape[1]), "train_windows": int(d["is_train"].sum()),
                 "mode_counts": np.bincount(d["mode"], minlength=4).tolist(), **d["timings"]},
        "gates": bench_gates(d, (90.0, 50.0), caps, a.quick),
        "proba_one": bench_proba_one(d, 50.0, 300 if a.quick else 2000),
    }
    pred, lstm, extra = bench_predictor(d, 90.0, a.quick)
    result["predictor"] = pred
    result["stream"] = bench_stream(lstm, extra["x"], 3 if a.quick else 10)
    result["machine"] = {"python": platform.python_version(), "torch": torch.__version__,
                         "cpu_count": __import__("os").cpu_count(),
                         "loadavg": list(__import__("os").getloadavg())}
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
