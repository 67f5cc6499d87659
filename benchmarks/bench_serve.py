"""Across processes against in one process: ``mpcshare run --sim-time`` + ``mpcshare sim --serve`` on loopback
versus ``mpcshare sim`` on the same held-out trials and strategy; prints JSON.

Runs ``run`` (its own DDS domain, loopback only) and the stand-in as two processes, then the in-process
``sim --runs gate`` on the same trials, and reports per trial the tracking RMS of both, their relative
difference (target: within 5 %), limit violations and steps driven into a body zone (target: 0), the
largest difference of the knife tip between the two loops, the steps without a command, and wall times.

Another arm: ``--config examples/ros2/panda.toml --arm "--robot panda --velocity-limit 1.5
--acceleration-limit 6.0"`` (``--arm``: ``sim``'s arm options, given to both sims). The simulator sways
the arm's base with the wearer's torso, so a configuration without a torso input gets one (optional,
``/mocap/torso/pose``) here; otherwise ``run`` would hold the base at rest while the simulated one moves.

Usage: ``python benchmarks/bench_serve.py --model MODEL --data DATA [--trials 2] [--duration S] [--config
ARM.toml] [--arm "SIM ARM OPTIONS"]``.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _mpcshare(argv: list[str], env: dict[str, str]) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mpcshare", *argv], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--trials", type=int, default=2)
    ap.add_argument("--duration", type=float, default=None, help="seconds per trial (default: whole trials)")
    ap.add_argument("--config", default=str(ROOT / "examples/ros2/superlimb.toml"), help="the arm's configuration")
    ap.add_argument("--arm", default="", help="sim's arm options for both sims, e.g. \"--robot panda\"")
    args = ap.parse_args()
    env = {k: v for k, v in os.environ.items() if k != "CYCLONEDDS_URI"}
    env["PYTHONPATH"] = str(ROOT)
    common = ["--model", args.model, "--data", args.data, "--trials", str(args.trials), *shlex.split(args.arm)] + \
        ([] if args.duration is None else ["--duration", str(args.duration)])
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "arm.toml"
        text = Path(args.config).read_text()
        text = text.replace("domain_id = 0", f"domain_id = {200 + os.getpid() % 30}") if "domain_id = 0" in text \
            else text.replace("[network]\n", f"[network]\ndomain_id = {200 + os.getpid() % 30}\n", 1)
        if "[inputs.torso]" not in text:
            text += '\n[inputs.torso]\ntopic = "/mocap/torso/pose"\noptional = true\nframe = "plate"\n'
        file = 'file = "example-robot-data:'
        if 'file = "' in text and file not in text:  # a relative robot file: as seen from the configuration
            text = text.replace('file = "', f'file = "{Path(args.config).resolve().parent}/', 1)
        cfg.write_text(text)
        t0 = time.perf_counter()
        run = _mpcshare(["run", "--model", args.model, "--config", str(cfg), "--sim-time"], env)
        stand = _mpcshare(["sim", *common, "--out", f"{tmp}/across", "--serve", "--config", str(cfg)], env)
        try:
            s_out, s_err = stand.communicate()
            across_s = time.perf_counter() - t0
            run.send_signal(signal.SIGTERM)
            r_out, r_err = run.communicate(timeout=60)
        finally:
            for p in (stand, run):
                if p.poll() is None:
                    p.kill()
                    p.communicate()
        if stand.returncode != 0:
            raise SystemExit(f"the stand-in failed: {s_err.strip()[-500:]}")
        t1 = time.perf_counter()
        inproc = _mpcshare(["sim", *common, "--out", f"{tmp}/inproc", "--runs", "gate"], env)
        i_out, i_err = inproc.communicate()
        inproc_s = time.perf_counter() - t1
        if inproc.returncode != 0:
            raise SystemExit(f"the in-process sim failed: {i_err.strip()[-500:]}")
        a = json.loads(Path(f"{tmp}/across/comparison.json").read_text())["per_trial"]["gate"]
        b = json.loads(Path(f"{tmp}/inproc/comparison.json").read_text())["per_trial"]["gate"]
        rows = []
        for tid in b:
            ea = np.load(f"{tmp}/across/runs/gate_trial{tid}.npz")
            eb = np.load(f"{tmp}/inproc/runs/gate_trial{tid}.npz")
            ra, rb = a[tid]["tracking_rmse_m"], b[tid]["tracking_rmse_m"]
            rows.append({"trial": int(tid), "rms_across_mm": ra * 1e3, "rms_in_process_mm": rb * 1e3,
                         "relative_difference": (ra - rb) / rb,
                         "max_tip_difference_m": float(np.nanmax(np.abs(ea["tip"] - eb["tip"]))),
                         "limit_violations_across": a[tid]["limit_violations"],
                         "limit_violations_in_process": b[tid]["limit_violations"],
                         "body_zone_steps_across": a[tid]["keepout_steps_driven_in"],
                         "body_zone_steps_in_process": b[tid]["keepout_steps_driven_in"],
                         "steps": int(len(ea["t"])), "statuses_across": sorted(set(ea["status"].tolist()))})
    missing = next((ln for ln in s_out.splitlines() if "without a command" in ln), "")
    print(json.dumps({"trials": rows, "wall_s": {"across_processes": across_s, "in_process": inproc_s},
                      "stand_in": missing, "run_summary": (r_out.strip().splitlines() or [""])[-1],
                      "load_average": os.getloadavg()}, indent=2))


if __name__ == "__main__":
    main()
