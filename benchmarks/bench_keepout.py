"""The keep-out's cost and its soak; prints JSON.

``timing`` (default): ``SharedController.step`` with the keep-out (the default), without it
(``ControllerConfig(keepout=None)``, the baseline measured in the same process, interleaved in
rounds), and with the MPC, its zones over the horizon on and off; closed loop over generated
30 s trials (the arm integrated from its commands); wall-clock and thread-CPU percentiles.

``soak``: ≥ ``--steps`` control steps (default 10⁵) of closed-loop MuJoCo physics
(:func:`sim.closed_loop.run_episode`) with faults: 60 s episodes cycling through the conflict
scenarios of :mod:`mpcshare.conflicts` (a command into the hand, the hand sweeping into the
knife, an approach to the face, the fork marker lost, a predictor fault) and the strategies
``voluntary``, ``reactive``, ``gate``, plus the shoulder signal lost for 0.3 s every 7 s. Reports
the steps driven into a body zone (issue 30's definition), the time inside and the deepest
intrusion, the limit violations at the physics rate (1e-6) and the statuses seen.

The bundle: ``--bundle FOLDER`` (a trained one), else a small one trained here on 3 generated
trials (as ``benchmarks/bench_controller.py``).

Usage: ``python benchmarks/bench_keepout.py [timing|soak] [--bundle DIR] [--rounds 2] [--steps 100000]``.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import time

import numpy as np

from mpcshare.conflicts import SCENARIOS, Scenario
from mpcshare.control.controller import ControllerConfig, SharedController
from mpcshare.control.keepout import KeepOutSettings
from robot.superlimb import SuperLimbParams
from sim.closed_loop import run_episode
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from sim.keepout_metrics import episode_keepout_metrics

#: The arm's mount (T_plate_torso) these runs give the controller: the plate 0.22 m in front of the torso
#: origin and 0.12 m to its right, at its height (the demonstrations' knife positions mid-range of the
#: joints from 0.5·(lower + upper); the figures of earlier runs were taken at this mount).
MOUNT = np.eye(4)
MOUNT[:3, 3] = (-0.22, 0.12, 0.0)

def _bundle(path: str | None, demos):
    """The bundle of ``--bundle``, else one trained on the first 3 trials with short settings."""
    if path:
        from mpcshare.bundle import load_bundle

        return load_bundle(path)
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig

    cfg = TrainConfig(n_modes=4, hmm_restarts=1, max_epochs=10, patience=3, gate_max_samples=600, seed=0)
    return train_bundle(demos.select(demos.trial_ids[:3]), cfg, progress=False)


def _run(ctl: SharedController, trial) -> tuple[list[float], list[float]]:
    p = SuperLimbParams()
    q, v = 0.5 * (p.lower + p.upper), np.zeros(3)
    ctl.reset()
    wall, cpu = [], []
    for k in range(len(trial)):
        c0, t0 = time.thread_time(), time.perf_counter()
        c = ctl.step(trial.t[k], trial.obs[k], trial.voluntary[k], q, v, MOUNT)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.thread_time() - c0)
        q, v = c.q_cmd, c.v_cmd
    return wall, cpu


def _stats(x: list[float]) -> dict:
    us = np.asarray(x) * 1e6
    return {"p50_us": round(float(np.percentile(us, 50)), 1), "p99_us": round(float(np.percentile(us, 99)), 1),
            "n": int(us.size)}


def timing(bundle, trials, rounds: int) -> dict:
    """Step percentiles per variant, interleaved in rounds (module docstring)."""
    off = ControllerConfig(keepout=None)
    no_mpc_zones = ControllerConfig(keepout=KeepOutSettings(mpc_zones=False))
    variants = {"no_keepout": SharedController.from_bundle(bundle, config=off),
                "keepout": SharedController.from_bundle(bundle),
                "mpc_no_keepout": SharedController.from_bundle(bundle, use_mpc=True, config=off),
                "mpc_filter_only": SharedController.from_bundle(bundle, use_mpc=True, config=no_mpc_zones),
                "mpc_zones": SharedController.from_bundle(bundle, use_mpc=True)}
    wall: dict[str, list[float]] = {k: [] for k in variants}
    cpu: dict[str, list[float]] = {k: [] for k in variants}
    for _ in range(rounds):
        for trial in trials:
            for name, ctl in variants.items():
                w, c = _run(ctl, trial)
                wall[name] += w
                cpu[name] += c
    out = {k: {"wall": _stats(wall[k]), "cpu": _stats(cpu[k])} for k in variants}
    for k in variants:
        base = "no_keepout" if not k.startswith("mpc") else "mpc_no_keepout"
        out[k]["p50_ratio_to_" + base] = round(out[k]["wall"]["p50_us"] / out[base]["wall"]["p50_us"], 2)
        out[k]["meets_p99_5ms"] = out[k]["wall"]["p99_us"] <= 5000.0
    return out


def _shoulder_dropouts(trial, period_s: float = 7.0, length_s: float = 0.3):
    """A copy of ``trial`` whose shoulder signal is NaN for ``length_s`` every ``period_s``."""
    import copy

    out = copy.copy(trial)
    vol = np.array(trial.voluntary, dtype=float)
    t = trial.t - trial.t[0]
    vol[(t % period_s) < length_s] = np.nan
    out.voluntary = vol
    return out


def soak(bundle, demos, steps: int, duration_s: float = 60.0) -> dict:
    """The soak (module docstring): totals over episodes until ``steps`` control steps ran."""
    done, episodes, violations, driven, inside, deepest = 0, 0, 0, 0, 0.0, 0.0
    statuses: dict[str, int] = {}
    per_scenario: dict[str, dict[str, float]] = {}
    combos = itertools.cycle(itertools.product(SCENARIOS, ("voluntary", "reactive", "gate")))
    trials = itertools.cycle(demos.trials)
    t0 = time.perf_counter()
    while done < steps:
        (name, strategy), trial = next(combos), next(trials)
        sc = Scenario(name, demos.obs_names, demos.act_names)
        st = sc.apply(trial, duration_s)
        ctl = SharedController.from_bundle(sc.wrap_bundle(bundle, st, demos.act_names), strategy=strategy)
        ep = run_episode(ctl, _shoulder_dropouts(st.trial), duration_s=duration_s, seed=episodes, record=False,
                         obs_names=list(demos.obs_names), act_names=list(demos.act_names),
                         fork_truth=st.fork_truth)
        m = episode_keepout_metrics(ep)
        episodes += 1
        done += ep.t.size
        violations += int(ep.info["limit_violations"])
        driven += int(m["keepout_steps_driven_in"])
        inside += float(m["keepout_time_inside_s"])
        deepest = max(deepest, float(m["keepout_max_depth_m"]))
        row = per_scenario.setdefault(name, {"steps_driven_in": 0, "time_inside_s": 0.0, "deepest_m": 0.0})
        row["steps_driven_in"] += int(m["keepout_steps_driven_in"])
        row["time_inside_s"] = round(row["time_inside_s"] + float(m["keepout_time_inside_s"]), 3)
        row["deepest_m"] = max(row["deepest_m"], round(float(m["keepout_max_depth_m"]), 4))
        for s in ep.status:
            statuses[str(s)] = statuses.get(str(s), 0) + 1
    return {"control_steps": done, "episodes": episodes, "wall_s": round(time.perf_counter() - t0, 1),
            "steps_driven_in": driven, "time_inside_s": round(inside, 3), "deepest_m": round(deepest, 4),
            "limit_violations": violations, "per_scenario": per_scenario, "statuses": statuses,
            "meets_target": driven == 0 and violations == 0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", nargs="?", choices=("timing", "soak"), default="timing")
    ap.add_argument("--bundle", default=None, help="trained bundle folder (default: a small one built here)")
    ap.add_argument("--rounds", type=int, default=2, help="interleaved timing rounds over the trials")
    ap.add_argument("--steps", type=int, default=100_000, help="control steps of the soak")
    args = ap.parse_args()
    load_before = os.getloadavg()
    demos = generate_demonstrations(n_subjects=1, minutes=5.0, seed=1, config=GeneratorConfig(trial_minutes=1.0))
    bundle = _bundle(args.bundle, demos)
    held_out = demos.select(demos.trial_ids[3:])
    if args.what == "timing":
        trials = [tr.__class__(obs=tr.obs[:3000], act=tr.act[:3000], t=tr.t[:3000], trial_id=tr.trial_id,
                               subject=tr.subject, mode=None if tr.mode is None else tr.mode[:3000],
                               voluntary=tr.voluntary[:3000]) for tr in held_out.trials]
        result = timing(bundle, trials, args.rounds)
    else:
        result = soak(bundle, held_out, args.steps)
    print(json.dumps({"what": args.what, "machine": platform.processor() or platform.machine(),
                      "cpus": os.cpu_count(), "load_avg_before": [round(x, 2) for x in load_before],
                      "load_avg_after": [round(x, 2) for x in os.getloadavg()],
                      "bundle": args.bundle or "trained here (small)", "result": result}, indent=2))


if __name__ == "__main__":
    main()
