"""Timing of ``mpcshare run`` across processes on loopback; prints JSON.

Starts ``mpcshare run --model MODEL --config examples/ros2/superlimb.toml`` (a domain of its own) and
plays, in this process at 100 Hz, the arm (moving to each command's positions), the fork's motion
capture, its wrench and the wearer's shoulder from a generated trial; after ``--seconds`` the fork
goes silent, then SIGTERM. Figures (wall clock; the machine may be shared):

* ``period_ms``: median, p99, max of the commands' header-stamp differences (target 10 ms);
  ``jitter_p99_ms``: p99 of |period − 10 ms| (target ≤ 2 ms);
* ``delivery_ms``: a command's arrival here minus its stamp (same wall clock): median, p99;
* ``input_to_command_ms``: a command's stamp minus the stamp of the arm's joint state it was computed from
  (the status's ``input_stamp``; target p99 ≤ 5 ms): median, p99, max; the loop takes its inputs once per
  tick, so a joint state waits up to one period for its tick;
* ``stop_after_silence_s``: the first ``protective_stop`` status after the fork's last message
  (its stop_after_s is 0.5 s; target ≤ 0.5 s + 2 periods);
* ``late_ticks``: the ticks ``run`` skipped (it overran 1.5 periods); ``run_timing``: ``run``'s own
  profile (``mpcshare run --timing``, :mod:`mpcshare.runtime.tick_profile`): periods, phases, garbage
  collections, and ``causes``: each period longer than T + 2 ms by cause (``late_ticks`` by cause too);
* ``feeder``: this process's own lateness publishing the inputs (its sends after their schedule: p99,
  max, and how many were more than 2 ms late); its garbage collector is frozen after setup, so that
  the feeder's pauses do not count against ``run``;
* ``run_summary``: the process's own last lines (step median and p99, late ticks, long periods).

Usage: ``python benchmarks/bench_run.py --model MODEL [--seconds 10] [--tick arm] [--gc managed|python]``
(a 10-minute run: ``--seconds 600``).
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from mpcshare.runtime.messages import (
    DiagnosticArray,
    Header,
    JointState,
    JointTrajectory,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Vector3,
    Wrench,
    WrenchStamped,
    ros_time,
    seconds,
)
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport
from robot.superlimb import SuperLimbParams
from sim.demonstrator import GeneratorConfig, generate_demonstrations

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--tick", choices=("schedule", "arm"), default="arm",
                    help="the configuration's tick: every period, or on the arm's joint states")
    ap.add_argument("--gc", choices=("managed", "python"), default="managed", help="`mpcshare run --gc`")
    args = ap.parse_args()
    domain = 200 + os.getpid() % 30
    trial = generate_demonstrations(1, max(0.2, args.seconds / 60 + 0.05), seed=11,
                                    config=GeneratorConfig(trial_minutes=max(0.2, args.seconds / 60 + 0.05))).trials[0]
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "arm.toml"
        text = (ROOT / "examples/ros2/superlimb.toml").read_text().replace("domain_id = 0", f"domain_id = {domain}")
        cfg.write_text(text.replace('tick = "arm"', f'tick = "{args.tick}"'))
        env = {k: v for k, v in os.environ.items() if k != "CYCLONEDDS_URI"}
        env["PYTHONPATH"] = str(ROOT)
        timing = Path(tmp) / "timing.json"
        proc = subprocess.Popen([sys.executable, "-m", "mpcshare", "run", "--model", args.model, "--config",
                                 str(cfg), "--gc", args.gc, "--timing", str(timing)], env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        t = Transport(NetworkSettings(domain_id=domain))
        arm, fork = t.writer("/joint_states", JointState), t.writer("/mocap/fork/pose", PoseStamped)
        wrench, shoulder = t.writer("/fork/wrench", WrenchStamped), t.writer("/shoulder/joint_states", JointState)
        cmds = t.reader("/joint_trajectory_controller/joint_trajectory", JointTrajectory, QosSettings("reliable", 200))
        stat = t.reader("/mpcshare/status", DiagnosticArray, QosSettings("reliable", 200))
        P = SuperLimbParams()
        q = 0.5 * (P.lower + P.upper)
        got, stops, latency, k, k0, silent = [], [], [], 0, None, None
        gc.collect()
        gc.freeze()
        feeder_late: list[float] = []
        nxt = time.monotonic()
        while proc.poll() is None:
            now = time.monotonic()
            if k0 is not None and silent is None:
                feeder_late.append(now - nxt)
            stamp = ros_time(time.time())
            arm.write(JointState(Header(stamp, ""), ["base_yaw", "shoulder", "elbow"], [float(x) for x in q],
                                 [0.0] * 3, []))
            i = min(k, len(trial.t) - 1)
            if silent is None:
                x, y, z, r, p, yw, fx, fy, fz = (float(v) for v in trial.obs[i])
                qx, qy, qz, qw = Rotation.from_euler("ZYX", [yw, p, r]).as_quat()
                fork.write(PoseStamped(Header(stamp, "plate"), Pose(Point(x, y, z), Quaternion(qx, qy, qz, qw))))
                wrench.write(WrenchStamped(Header(stamp, "fork"), Wrench(Vector3(fx, fy, fz), Vector3())))
            shoulder.write(JointState(Header(stamp, ""), [], [float(v) for v in trial.voluntary[i]]))
            arrived = time.time()
            for c in cmds.take(200):
                got.append((arrived, seconds(c.header.stamp), silent is None))
                q = np.array(c.points[0].positions)
            for s in stat.take(200):
                if s.status and s.status[0].message.startswith("protective stop") and silent is not None:
                    stops.append(now - silent)
                values = {kv.key: kv.value for kv in s.status[0].values} if s.status else {}
                if silent is None and "input_stamp" in values and "alpha" in values:
                    latency.append((float(values["stamp"]) - float(values["input_stamp"])) * 1e3)
            if got and k0 is None:
                k0 = k
            if k0 is not None:
                k += 1
                if silent is None and (k - k0) >= args.seconds * 100:
                    silent = time.monotonic()
                if silent is not None and now - silent > 1.0:
                    break
            nxt += 0.01
            time.sleep(max(0.0, nxt - time.monotonic()))
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
        profile = json.loads(timing.read_text()) if timing.exists() else None
    live = np.array([(a, s) for a, s, fed in got if fed])
    period = np.diff(live[:, 1]) * 1e3
    delivery = (live[:, 0] - live[:, 1]) * 1e3
    print(json.dumps({
        "commands": int(len(live)),
        "period_ms": {"median": float(np.median(period)), "p99": float(np.percentile(period, 99)),
                      "max": float(period.max())},
        "jitter_p99_ms": float(np.percentile(np.abs(period - 10.0), 99)),
        "delivery_ms": {"median": float(np.median(delivery)), "p99": float(np.percentile(delivery, 99))},
        "input_to_command_ms": {"median": float(np.median(latency)), "p99": float(np.percentile(latency, 99)),
                                "max": float(np.max(latency))} if latency else None,
        "stop_after_silence_s": float(stops[0]) if stops else None,
        "tick": args.tick,
        "exit_status": proc.returncode,
        "late_ticks": int(m.group(1)) if (m := re.search(r"(\d+) late ticks", out)) else None,
        "late_tick_causes": profile["late_ticks"] if profile else None,
        "long_period_causes": profile["causes"] if profile else None,
        "max_period_ms": float(period.max()),
        "run_timing": profile,
        "feeder": {"late_p99_ms": float(np.percentile(feeder_late, 99) * 1e3),
                   "late_max_ms": float(np.max(feeder_late) * 1e3),
                   "late_over_2ms": int(np.sum(np.array(feeder_late) > 2e-3))} if feeder_late else None,
        "gc": args.gc,
        "run_summary": out.strip().splitlines()[-2:] if out.strip() else err.strip()[-300:],
        "load_average": os.getloadavg(),
    }, indent=2))


if __name__ == "__main__":
    main()
