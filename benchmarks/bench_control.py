"""Speed of the robot-side control step; prints JSON.

Measures, in one process and interleaved in rounds (the machine is shared and
noisy, so ratios to the in-process baseline are the comparable figures):

* ``baseline_rnea``: one bare ``pinocchio.rnea`` call on the SuperLimb;
* ``qp_step_<solver>``: one ``QPController.step`` (Pinocchio kinematics and
  dynamics, constraint rows, tasks, QP solve, clip+verify) while tracking a
  moving knife-tip reference in closed loop; target median ≤ 150 µs;
* ``ruckig_update``: one ``ReferenceSmoother.update`` with a target moving
  every cycle and jumping now and then; target median ≤ 20 µs;
* ``ruckig_raw``: the bare ``Ruckig.update`` + ``pass_to_input`` it wraps.

Usage: ``python benchmarks/bench_control.py [--n 5000] [--rounds 5]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np
import pinocchio as pin
from ruckig import InputParameter, OutputParameter, Ruckig

from robot.model_files import build_pinocchio_model
from robot.qp import QPConfig, QPController
from robot.smoothing import ReferenceSmoother
from robot.solvers import daqp_available

SOLVERS = ("daqp", "osqp") if daqp_available() else ("osqp",)
TARGETS_US = {"qp_step_daqp": 150.0, "qp_step_osqp": 150.0, "ruckig_update": 20.0}


def _tip_path(k: int) -> np.ndarray:
    """A slow circle in front of the arm with a 5 cm jump every 2 s [m]."""
    t = 0.01 * k
    jump = 0.05 * ((k // 200) % 2)
    return np.array([0.40 + 0.05 * np.cos(t), -0.15 + 0.05 * np.sin(t) + jump, 0.15])


def bench_rnea(n: int) -> list[int]:
    model, data, _ = build_pinocchio_model()
    q, v, a = np.array([0.1, 0.5, 1.0]), np.array([0.2, -0.1, 0.3]), np.zeros(3)
    out = []
    for _ in range(n):
        t0 = time.perf_counter_ns()
        pin.rnea(model, data, q, v, a)
        out.append(time.perf_counter_ns() - t0)
    return out


def bench_qp(solver: str, n: int) -> tuple[list[int], dict]:
    ctl = QPController.for_superlimb(config=QPConfig(solver=solver))
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    out, statuses, err = [], {}, []
    for k in range(n):
        p = _tip_path(k)
        t0 = time.perf_counter_ns()
        r = ctl.step(q, v, p)
        out.append(time.perf_counter_ns() - t0)
        statuses[r.status.value] = statuses.get(r.status.value, 0) + 1
        err.append(r.tip_error)
        q, v = r.q_next, r.v_next
    return out, {"statuses": statuses, "median_tip_error_m": float(np.median(err))}


def bench_smoother(n: int) -> list[int]:
    sm = ReferenceSmoother(3, 0.01, 0.3, 2.0, 30.0)
    rng = np.random.default_rng(0)
    targets = [(_tip_path(k) + rng.normal(scale=0.002, size=3)).tolist() for k in range(n)]
    out = []
    for tgt in targets:
        t0 = time.perf_counter_ns()
        sm.update(tgt)
        out.append(time.perf_counter_ns() - t0)
    return out


def bench_ruckig_raw(n: int) -> list[int]:
    otg, inp, res = Ruckig(3, 0.01), InputParameter(3), OutputParameter(3)
    inp.current_position = [0.4, -0.15, 0.15]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [0.3] * 3, [2.0] * 3, [30.0] * 3
    targets = [_tip_path(k).tolist() for k in range(n)]
    out = []
    for tgt in targets:
        t0 = time.perf_counter_ns()
        inp.target_position = tgt
        otg.update(inp, res)
        res.pass_to_input(inp)
        out.append(time.perf_counter_ns() - t0)
    return out


def _stats(samples: list[int]) -> dict:
    us = np.asarray(samples, dtype=float) / 1e3
    return {"p50_us": round(float(np.percentile(us, 50)), 2), "p99_us": round(float(np.percentile(us, 99)), 2),
            "min_us": round(float(us.min()), 2), "n": int(us.size)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=4000, help="calls per measurement and round")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (samples are pooled)")
    args = ap.parse_args()

    for solver in SOLVERS:  # warm-up: imports, allocations, first OSQP setup
        bench_qp(solver, 200)
    bench_smoother(200)
    names = ["baseline_rnea", *(f"qp_step_{s}" for s in SOLVERS), "ruckig_update", "ruckig_raw"]
    samples: dict[str, list[int]] = {k: [] for k in names}
    info: dict[str, dict] = {}
    for _ in range(args.rounds):
        samples["baseline_rnea"] += bench_rnea(args.n)
        for solver in SOLVERS:
            s, info[solver] = bench_qp(solver, args.n)
            samples[f"qp_step_{solver}"] += s
        samples["ruckig_update"] += bench_smoother(args.n)
        samples["ruckig_raw"] += bench_ruckig_raw(args.n)

    results = {k: _stats(v) for k, v in samples.items()}
    base = results["baseline_rnea"]["p50_us"]
    for name, stats in results.items():
        stats["ratio_p50_to_rnea"] = round(stats["p50_us"] / base, 1)
        if name in TARGETS_US:
            stats["target_p50_us"] = TARGETS_US[name]
            stats["meets_target"] = stats["p50_us"] <= TARGETS_US[name]
    for solver in SOLVERS:
        results[f"qp_step_{solver}"].update(info[solver])
    print(json.dumps({"machine": platform.processor() or platform.machine(), "python": platform.python_version(),
                      "results": results}, indent=2))


if __name__ == "__main__":
    main()
