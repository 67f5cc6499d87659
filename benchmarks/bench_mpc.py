"""Speed and quality of the knife-tip MPC solvers in closed loop; prints JSON.

Every solver runs the same closed loop on the model (the planned first
acceleration integrated exactly, 10 ms steps) along a moving tip reference (a
circle with a 3 cm jump every second), from the same start.  Per solver:
solve time median and p99 [µs] (``TipMPC.solve``, everything included),
their ratio to IPOPT measured in the same process (the machine is shared and
noisy: ratios are the comparable figures), tip tracking error (median and
p95 after a 0.5 s transient [mm], ‖p(q) − p_ref‖), the largest constraint
violation of the executed step and of the whole plan (fraction of the limit),
the share of ``ok`` solves and the mean iterations.  A ``baseline_rnea`` (one
``pinocchio.rnea`` call) scales the figures to the machine.  Solver libraries
that print to stdout (qpOASES's banner, OSQP's polishing note) are silenced
at the file-descriptor level so that stdout carries only the JSON.

Usage: ``python benchmarks/bench_mpc.py [--steps 400] [--slow-steps 60]``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import sys
import time

import numpy as np
import pinocchio as pin

from robot.model_files import build_pinocchio_model
from robot.mpc.tip_mpc import TipMPC
from robot.superlimb import SuperLimbParams

H, DT = 20, 0.01
Q0 = np.array([0.1, 0.6, 1.1])
FAST = [("rti-daqp", {}), ("rti-qpoases", {}), ("rti-osqp", {}), ("rti-casadi-daqp", {}),
        ("rti-daqp", {"max_iterations": 3, "tolerance": 1e-6})]
SLOW = [("ipopt", {}), ("fatrop", {}), ("sqpmethod", {})]
TARGETS_US = {"median": 1000.0, "p99": 3000.0}


@contextlib.contextmanager
def quiet_stdout():
    """Send fd 1 to /dev/null (C libraries print there directly)."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(null)
        os.close(saved)


def reference(t: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Circle of 4 cm radius at 2 rad/s with a figure-eight z and a 3 cm x jump every second [m]."""
    jump = 0.03 * (np.floor(t) % 2)
    return centre + np.stack([0.04 * np.cos(2 * t) + jump, 0.04 * np.sin(2 * t), 0.02 * np.sin(4 * t)], -1)


def run(solver: str, options: dict, steps: int, model, data, fid) -> dict:
    params = SuperLimbParams()
    mpc = TipMPC(params, horizon=H, dt=DT, solver=solver, **options)
    pin.framesForwardKinematics(model, data, Q0)
    centre = data.oMf[fid].translation + np.array([0.02, 0.0, -0.02])
    q, v = Q0.copy(), np.zeros(3)
    times, errors, oks, iters, plan_viol, step_viol = [], [], [], [], [], []
    scale = {"torque": params.torque_limit.min(), "velocity": params.velocity_limit.min(), "position": 1.0,
             "acceleration": params.acceleration_limit.min()}
    for k in range(steps):
        p_ref = reference(DT * (k + np.arange(H + 1)), centre)
        res = mpc.solve(q, v, p_ref)
        times.append(res.solve_time)
        oks.append(res.ok)
        iters.append(res.iterations)
        if res.violation:
            plan_viol.append(max(res.violation[key] / scale[key] for key in res.violation))
        a = res.a
        tau = pin.rnea(model, data, q, v, a)
        q_next, v_next = q + v * DT + 0.5 * a * DT * DT, v + a * DT
        over = [np.max(np.abs(tau) / params.torque_limit) - 1, np.max(np.abs(v_next) / params.velocity_limit) - 1,
                np.max(np.abs(a) / params.acceleration_limit) - 1,
                np.max(np.maximum(q_next - params.upper, params.lower - q_next))]
        step_viol.append(max(0.0, *over))
        pin.framesForwardKinematics(model, data, q)
        errors.append(np.linalg.norm(data.oMf[fid].translation - p_ref[0]))
        q, v = q_next, v_next
    t = np.array(times) * 1e6
    e = np.array(errors[50:] if steps > 100 else errors[steps // 2:]) * 1e3
    return {"solver": solver, "options": options, "steps": steps, "evaluation": mpc.evaluation_.split(":")[0],
            "median_us": float(np.median(t)), "p99_us": float(np.percentile(t, 99)),
            "tracking_median_mm": float(np.median(e)), "tracking_p95_mm": float(np.percentile(e, 95)),
            "step_violation": float(max(step_viol)), "plan_violation": float(max(plan_viol, default=np.nan)),
            "ok_share": float(np.mean(oks)), "mean_iterations": float(np.mean(iters))}


def warm_vs_cold(model, data, fid, steps: int = 60) -> dict:
    """Converged SQP (rti-daqp, up to 30 iterations): iterations and time, warm start vs reset before every solve."""
    out = {}
    for mode in ("warm", "cold"):
        mpc = TipMPC(horizon=H, dt=DT, max_iterations=30, tolerance=1e-7)
        pin.framesForwardKinematics(model, data, Q0)
        centre = data.oMf[fid].translation + np.array([0.02, 0.0, -0.02])
        q, v, its, ts = Q0.copy(), np.zeros(3), [], []
        for k in range(steps):
            if mode == "cold":
                a_prev = mpc._a_prev
                mpc.reset()
                mpc._a_prev = a_prev
            res = mpc.solve(q, v, reference(DT * (k + np.arange(H + 1)), centre))
            its.append(res.iterations)
            ts.append(res.solve_time)
            q, v = q + v * DT + 0.5 * res.a * DT * DT, v + res.a * DT
        out[mode] = {"mean_iterations": float(np.mean(its[10:])), "median_us": float(np.median(ts[10:]) * 1e6)}
    return out


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=400)
    parser.add_argument("--slow-steps", type=int, default=60)
    args = parser.parse_args(argv)
    model, data, fid = build_pinocchio_model()
    rnea = []
    for _ in range(2000):
        t0 = time.perf_counter_ns()
        pin.rnea(model, data, Q0, Q0, Q0)
        rnea.append(time.perf_counter_ns() - t0)
    table = []
    with quiet_stdout():
        for solver, options in SLOW[:1] + FAST + SLOW[1:]:
            steps = args.slow_steps if solver in dict(SLOW) else args.steps
            try:
                table.append(run(solver, options, steps, model, data, fid))
            except Exception as exc:  # noqa: BLE001 — a solver that cannot be built is a result too
                table.append({"solver": solver, "options": options, "error": f"{type(exc).__name__}: {exc}"})
        warm = warm_vs_cold(model, data, fid)
    ipopt = next(r for r in table if r["solver"] == "ipopt")
    for row in table:
        if "median_us" in row and "median_us" in ipopt:
            row["median_vs_ipopt"] = row["median_us"] / ipopt["median_us"]
            row["p99_vs_ipopt"] = row["p99_us"] / ipopt["p99_us"]
    result = {"benchmark": "mpc", "python": platform.python_version(), "machine": platform.machine(),
              "cpu_count": os.cpu_count(), "load_average": os.getloadavg(), "horizon": H, "dt": DT,
              "baseline_rnea_us": float(np.median(rnea) / 1e3), "targets_us": TARGETS_US,
              "solvers": table, "warm_vs_cold": warm}
    print(json.dumps(result, indent=1))
    return result


if __name__ == "__main__":
    main()
