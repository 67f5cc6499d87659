"""Real-time factor of the closed-loop simulation; prints JSON.

Measured in one process, interleaved in rounds (the machine is shared and noisy,
so the ratios to the in-process baseline are the comparable figures):

* ``baseline_physics``: the bare MuJoCo loop of the same scene (``mj_step1`` +
  ``mj_step2`` at 1 kHz, zero torque, the torso sway set every step);
* ``hold``: :func:`sim.closed_loop.run_episode` with a controller that costs
  nothing (it commands the current state): scene, servo, wearer, recording —
  the simulator's own cost; target ≥ 10× real time;
* ``qp``: the same with a cheap real controller (Pinocchio QP + ruckig tracking
  the demonstration's knife, ≈ 0.2–0.3 ms a step).

``projected_full_controller_rtf``: the hold run's simulator time plus
``--controller-ms`` (default 1 ms, the full SharedController's step) per
control step — the figure to hold against the ≥ 5× target until the full
controller is measured in ``mpcshare sim``.  Real-time factor = simulated time /
wall time; ``rtf_cpu_time`` uses the process's CPU time instead (what one
free core would give: on a shared machine the wall time also counts waiting for
a core).  Single thread (BLAS/OpenMP threads pinned to 1).

Usage: ``python benchmarks/bench_sim.py [--seconds 20] [--rounds 3] [--controller-ms 1.0]``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from robot.qp import QPConfig, QPController  # noqa: E402
from robot.smoothing import ReferenceSmoother  # noqa: E402
from sim.closed_loop import run_episode  # noqa: E402
from sim.demonstrator import generate_demonstrations  # noqa: E402
from sim.scene import EatingScene  # noqa: E402
from sim.wearer import smooth_intent  # noqa: E402


@dataclass
class _Command:
    q_cmd: np.ndarray
    v_cmd: np.ndarray
    a_cmd: np.ndarray
    tau: np.ndarray
    alpha: float
    beta: float
    mode_proba: np.ndarray
    tip_reference: np.ndarray
    status: str = "ok"


class HoldController:
    """Commands the current state (zero acceleration): no controller cost at all."""

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        return _Command(q, v, np.zeros(3), np.zeros(3), 0.0, 1.0, np.ones(1), np.full(3, np.nan))


class QPTracker:
    """QP + ruckig tracking the demonstration's knife (as tests/sim/controllers.py's oracle)."""

    def __init__(self, knife: np.ndarray) -> None:
        self.knife = smooth_intent(knife, 100.0, 5.0)[0]
        self.qp = QPController.for_superlimb(None, QPConfig(dt=0.01))
        self.smoother = ReferenceSmoother(3, 0.01, max_velocity=1.0, max_acceleration=10.0, max_jerk=300.0)

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        k = min(round(t / 0.01) + 1, len(self.knife) - 1)
        s = self.smoother.update(self.knife[k])
        R, p = base_pose[:3, :3], base_pose[:3, 3]
        r = self.qp.step(q, v, R.T @ (s.position - p), R.T @ s.velocity, R.T @ s.acceleration)
        return _Command(r.q_next, r.v_next, r.a, r.tau, 1.0, 0.0, np.ones(1), s.position, r.status.value)


def _baseline(seconds: float) -> tuple[float, float]:
    """Wall and CPU time [s] of the bare physics loop over ``seconds`` of simulated time."""
    scene = EatingScene()
    m, d = scene.model, scene.data
    scene.set_state(np.array([0.3, 0.5, 0.9]), np.zeros(3))
    n = round(seconds / m.opt.timestep)
    t0, c0 = time.perf_counter(), time.process_time()
    for i in range(n):
        scene.set_time(i * m.opt.timestep)
        mujoco.mj_step1(m, d)
        mujoco.mj_step2(m, d)
    return time.perf_counter() - t0, time.process_time() - c0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="simulated seconds per run (default 20)")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default 3)")
    ap.add_argument("--controller-ms", type=float, default=1.0,
                    help="full controller step time used for the projection [ms] (default 1)")
    args = ap.parse_args()
    trial = generate_demonstrations(1, max(args.seconds / 60.0 + 0.1, 0.5), seed=0).trials[0]
    wall: dict[str, list[float]] = {"baseline_physics": [], "hold": [], "qp": []}
    cpu: dict[str, list[float]] = {"baseline_physics": [], "hold": [], "qp": []}
    ctrl_ms: dict[str, list[float]] = {"hold": [], "qp": []}
    violations = 0
    for _ in range(args.rounds):
        w, c = _baseline(args.seconds)
        wall["baseline_physics"].append(w)
        cpu["baseline_physics"].append(c)
        for name, ctrl in (("hold", HoldController()), ("qp", QPTracker(trial.act[:, :3]))):
            c0 = time.process_time()
            ep = run_episode(ctrl, trial, duration_s=args.seconds)
            cpu[name].append(time.process_time() - c0)  # includes the episode's set-up (scene compile)
            wall[name].append(ep.info["wall_time_s"])
            ctrl_ms[name].append(float(np.sum(ep.step_time)) * 1e3)
            violations += ep.info["limit_violations"]
    med = {k: statistics.median(v) for k, v in wall.items()}
    med_cpu = {k: statistics.median(v) for k, v in cpu.items()}
    n_ctrl = round(args.seconds / 0.01)
    sim_only = med["hold"] - statistics.median(ctrl_ms["hold"]) / 1e3  # simulator time without controller
    sim_only_cpu = med_cpu["hold"] - statistics.median(ctrl_ms["hold"]) / 1e3
    out = {
        "machine": platform.processor() or platform.machine(), "python": platform.python_version(),
        "mujoco": mujoco.__version__, "simulated_s": args.seconds, "rounds": args.rounds,
        "rtf": {k: args.seconds / v for k, v in med.items()},
        "rtf_cpu_time": {k: args.seconds / v for k, v in med_cpu.items()},
        "wall_s": med,
        "ratio_to_baseline_physics": {k: med[k] / med["baseline_physics"] for k in ("hold", "qp")},
        "simulator_us_per_physics_step": sim_only / (n_ctrl * 10) * 1e6,
        "qp_controller_ms_per_step": statistics.median(ctrl_ms["qp"]) / n_ctrl,
        "projected_full_controller_rtf": args.seconds / (sim_only + n_ctrl * args.controller_ms / 1e3),
        "projected_full_controller_rtf_cpu_time": args.seconds / (sim_only_cpu + n_ctrl * args.controller_ms / 1e3),
        "limit_violations": violations,
        "targets": {"hold_rtf_min": 10.0, "full_controller_rtf_min": 5.0},
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
