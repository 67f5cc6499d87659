"""Speed of ``SharedController.step``; prints JSON.

The controller runs closed loop (the arm's state integrated from its commands) over
generated 30 s trials at 100 Hz, in one process, interleaved in rounds with the
baseline (the machine is shared and noisy: ratios to the in-process baseline are the
comparable figures):

* ``baseline_qp_step``: one bare ``robot.qp.QPController.step`` tracking a moving tip;
* ``step_no_mpc``: the whole step without MPC; targets median ≤ 1 ms, p99 ≤ 3 ms;
* ``step_mpc``: the whole step with ``mpcshare.mpc.TipMPC`` (when it can be imported);
  target p99 ≤ 5 ms.

Per-stage medians (``Command.timings``) and the statuses seen are reported too, with
the load average of the machine before and after.

The bundle: ``--bundle FOLDER`` loads a trained one (``mpcshare.bundle.load_bundle``);
without it a small one is built here on generated data: real preprocessing, task
modes (3) and ``learning.gate.ModeGates`` (labels: the ground-truth mode is not
"cutting"), with the reactive predictor ``learning.predictor.ReactivePredictor`` when
it can be imported, else a ridge regression with the same ``make_stream().step``
interface (reported as ``predictor``).

Usage: ``python benchmarks/bench_controller.py [--rounds 3] [--bundle DIR]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from types import SimpleNamespace

import numpy as np

from learning.gate import ModeGates
from learning.modes import TaskModes
from learning.preprocess import Preprocessor, Standardizer, causal_windows
from learning.resample import causal_downsample
from mpcshare.controller import SharedController
from robot.qp import QPController
from robot.superlimb import SuperLimbParams
from sim.demonstrator import (
    ACT_NAMES,
    OBS_NAMES,
    VOL_NAMES,
    GeneratorConfig,
    generate_demonstrations,
)


class _RidgeStream:
    def __init__(self, W: np.ndarray, b: np.ndarray) -> None:
        self.W, self.b = W, b

    def step(self, x: np.ndarray) -> np.ndarray:
        return self.W @ x + self.b

    def reset(self) -> None:
        pass


class _RidgePredictor:
    """Linear stand-in for the reactive predictor (same ``make_stream`` interface)."""

    def __init__(self, W: np.ndarray, b: np.ndarray) -> None:
        self.W, self.b = W, b

    def make_stream(self) -> _RidgeStream:
        return _RidgeStream(self.W, self.b)


def small_bundle(demos, seed: int = 0):
    """A bundle-like object fitted on ``demos`` (module docstring); returns (bundle, predictor kind)."""
    from sklearn.linear_model import Ridge

    low = causal_downsample(demos, 10.0)
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(low),
                       act=Standardizer("sensor", field="act").fit(low), target_hz=10.0, window_s=1.0)
    std = pre.standardize(low)
    X = np.concatenate([tr.obs for tr in std.trials])
    A = np.concatenate([tr.act for tr in std.trials])
    lengths = [len(tr) for tr in std.trials]
    modes = TaskModes(n_modes=3, n_restarts=1, seed=seed).fit(X, lengths)
    P = modes.filter_proba(X, lengths)
    win = causal_windows(std, 1.0, rms=True)
    hard = P.argmax(1)[win.source_index]
    labels = (np.concatenate([tr.mode for tr in low.trials])[win.source_index] != 0).astype(int)
    gates = ModeGates(max_samples_per_mode=600, seed=seed).fit(win.X, hard, labels, n_modes=3)
    try:
        from learning.predictor import ReactivePredictor

        seqs = [np.hstack([tr.obs, p]) for tr, p in zip(std.trials, np.split(P, np.cumsum(lengths)[:-1]))]
        predictor = ReactivePredictor(seed=seed, max_epochs=5).fit(
            seqs, [tr.act for tr in std.trials], [np.ones(len(tr), bool) for tr in std.trials])
        kind = "ReactivePredictor"
    except ImportError:
        ridge = Ridge(alpha=1e-3).fit(np.hstack([X, P]), A)
        predictor, kind = _RidgePredictor(ridge.coef_, ridge.intercept_), "ridge stand-in"
    bundle = SimpleNamespace(
        format_version=1, obs_names=OBS_NAMES, act_names=ACT_NAMES, vol_names=VOL_NAMES, rate_hz=100.0,
        model_hz=10.0, window_s=1.0, preprocessor=pre, modes=modes, gates=gates, predictor=predictor,
        novelty_threshold=float(np.percentile(-modes.log_predictive(X, lengths), 99.9)))
    return bundle, kind


def run_controller(ctl: SharedController, trial) -> tuple[list[float], dict[str, list[float]], dict[str, int]]:
    p = SuperLimbParams()
    q, v = 0.5 * (p.lower + p.upper), np.zeros(3)
    ctl.reset()
    totals, stages, statuses = [], {}, {}
    for k in range(len(trial)):
        t0 = time.perf_counter()
        c = ctl.step(trial.t[k], trial.obs[k], trial.voluntary[k], q, v)
        totals.append(time.perf_counter() - t0)
        for name, dt in c.timings.items():
            stages.setdefault(name, []).append(dt)
        statuses[c.status] = statuses.get(c.status, 0) + 1
        q, v = c.q_cmd, c.v_cmd
    return totals, stages, statuses


def run_qp(n: int) -> list[float]:
    ctl = QPController.for_superlimb()
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    out = []
    for k in range(n):
        t = 0.01 * k
        p = np.array([0.40 + 0.05 * np.cos(t), -0.15 + 0.05 * np.sin(t), 0.15])
        t0 = time.perf_counter()
        r = ctl.step(q, v, p)
        out.append(time.perf_counter() - t0)
        q, v = r.q_next, r.v_next
    return out


def _stats(x: list[float]) -> dict:
    us = np.asarray(x) * 1e6
    return {"p50_us": round(float(np.percentile(us, 50)), 1), "p99_us": round(float(np.percentile(us, 99)), 1),
            "max_us": round(float(us.max()), 1), "n": int(us.size)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds over the trials")
    ap.add_argument("--bundle", default=None, help="trained bundle folder (default: a small one built here)")
    args = ap.parse_args()
    load_before = os.getloadavg()
    demos = generate_demonstrations(n_subjects=1, minutes=2.0, seed=0, config=GeneratorConfig(trial_minutes=0.5))
    if args.bundle:
        bundle, kind = args.bundle, "from bundle"
    else:
        bundle, kind = small_bundle(demos.select(demos.trial_ids[:2]))
    trials = demos.trials[2:]
    variants = {"step_no_mpc": SharedController.from_bundle(bundle, use_mpc=False)}
    mpc_error = None
    try:
        variants["step_mpc"] = SharedController.from_bundle(bundle, use_mpc=True)
    except (RuntimeError, ImportError) as exc:
        mpc_error = str(exc)
    run_qp(300)
    samples: dict[str, list[float]] = {"baseline_qp_step": [], **{k: [] for k in variants}}
    stages: dict[str, dict[str, list[float]]] = {k: {} for k in variants}
    statuses: dict[str, dict[str, int]] = {k: {} for k in variants}
    for _ in range(args.rounds):
        for trial in trials:
            samples["baseline_qp_step"] += run_qp(len(trial))
            for name, ctl in variants.items():
                tot, st, stat = run_controller(ctl, trial)
                samples[name] += tot
                for s, x in st.items():
                    stages[name].setdefault(s, []).extend(x)
                for s, c in stat.items():
                    statuses[name][s] = statuses[name].get(s, 0) + c
    results = {k: _stats(v) for k, v in samples.items()}
    base = results["baseline_qp_step"]["p50_us"]
    targets = {"step_no_mpc": (1000.0, 3000.0), "step_mpc": (None, 5000.0)}
    for name in variants:
        r = results[name]
        r["ratio_p50_to_qp"] = round(r["p50_us"] / base, 2)
        r["stage_p50_us"] = {s: round(float(np.median(x)) * 1e6, 1) for s, x in stages[name].items()}
        r["stage_p99_us"] = {s: round(float(np.percentile(x, 99)) * 1e6, 1) for s, x in stages[name].items()}
        r["statuses"] = statuses[name]
        p50_t, p99_t = targets[name]
        r["target_p50_us"], r["target_p99_us"] = p50_t, p99_t
        r["meets_target"] = (p50_t is None or r["p50_us"] <= p50_t) and r["p99_us"] <= p99_t
    out = {"machine": platform.processor() or platform.machine(), "cpus": os.cpu_count(),
           "python": platform.python_version(), "load_avg_before": [round(x, 2) for x in load_before],
           "load_avg_after": [round(x, 2) for x in os.getloadavg()], "predictor": kind,
           "mpc": "TipMPC" if "step_mpc" in variants else f"not available: {mpc_error}", "results": results}
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
