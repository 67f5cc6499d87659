"""`mpcshare run` as its own process on loopback, fed by a test publisher from a held-out demonstration.

The publisher plays the arm (it moves to each received command's positions), the fork's motion capture and
the wearer's shoulder; then the fork goes silent (protective stop), then SIGTERM (a stop command, exit 0).
"""

from __future__ import annotations

import gc
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from scipy.spatial.transform import Rotation  # noqa: E402

from mpcshare.runtime.messages import (  # noqa: E402
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
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport  # noqa: E402
from robot.superlimb import SuperLimbParams  # noqa: E402
from sim.demonstrator import GeneratorConfig, generate_demonstrations  # noqa: E402
from tests.mpcshare.runtime.ros_helpers import DOMAIN, ROOT, write_config  # noqa: E402

FEED_S = 3.0  # seconds of control before the fork goes silent


def _fork(row: np.ndarray, stamp) -> tuple[PoseStamped, WrenchStamped]:
    x, y, z, roll, pitch, yaw, fx, fy, fz = (float(v) for v in row)
    qx, qy, qz, qw = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_quat()
    pose = PoseStamped(Header(stamp, "plate"), Pose(Point(x, y, z), Quaternion(qx, qy, qz, qw)))
    return pose, WrenchStamped(Header(stamp, "fork"), Wrench(Vector3(fx, fy, fz), Vector3()))


def _status_values(msg: DiagnosticArray) -> dict[str, str]:
    return {kv.key: kv.value for kv in msg.status[0].values}


def test_run_publishes_stamped_commands_at_100_hz_and_stops_when_an_input_goes_silent(ros_model, tmp_path):
    model, _ = ros_model
    held_out = generate_demonstrations(n_subjects=1, minutes=0.1, seed=11,
                                       config=GeneratorConfig(trial_minutes=0.1)).trials[0]
    # the arm's and the shoulder's stops after 1 s, not 0.1 and 0.3 s: this test's Python publisher stalls on a
    # loaded machine, and a stop for either would hide the fork's, which the test is about
    cfg = write_config(tmp_path, replace={r"^stop_after_s = 0.1": "stop_after_s = 1.0",
                                          r"^stop_after_s = 0.3": "stop_after_s = 1.0"})
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("CYCLONEDDS_URI", None)
    proc = subprocess.Popen([sys.executable, "-m", "mpcshare", "run", "--model", str(model), "--config", str(cfg),
                             "--duration", "60", "--timing", "timing.json"], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    gc.disable()  # the inputs are published from this process: no collector pause of the suite's large heap
    try:
        t = Transport(NetworkSettings(domain_id=DOMAIN))
        arm = t.writer("/joint_states", JointState)
        fork = t.writer("/mocap/fork/pose", PoseStamped)
        wrench = t.writer("/fork/wrench", WrenchStamped)
        shoulder = t.writer("/shoulder/joint_states", JointState)
        commands = t.reader("/joint_trajectory_controller/joint_trajectory", JointTrajectory,
                            QosSettings("reliable", 100))
        status = t.reader("/mpcshare/status", DiagnosticArray, QosSettings("reliable", 100))
        P = SuperLimbParams()
        q = 0.5 * (P.lower + P.upper)
        got: list[tuple[float, JointTrajectory]] = []
        stats: list[tuple[float, DiagnosticArray]] = []
        k, k_first, fork_silent_at = 0, None, None
        t_end = time.monotonic() + 120.0  # start-up (torch, the bundle) included
        t_next = time.monotonic()
        while time.monotonic() < t_end and proc.poll() is None:
            now = time.monotonic()
            stamp = ros_time(time.time())
            arm.write(JointState(Header(stamp, ""), ["elbow", "base_yaw", "shoulder"],  # by name, any order
                                 [float(q[2]), float(q[0]), float(q[1])], [0.0, 0.0, 0.0], []))
            i = min(k, len(held_out.t) - 1)
            if fork_silent_at is None:
                pose, wr = _fork(held_out.obs[i], stamp)
                fork.write(pose)
                wrench.write(wr)
            shoulder.write(JointState(Header(stamp, ""), ["e", "p", "a"], [float(x) for x in held_out.voluntary[i]]))
            for c in commands.take(100):
                got.append((now, c))
                q = np.array(c.points[0].positions)
            stats += [(now, s) for s in status.take(100)]
            if got and k_first is None:
                k_first = k
            if k_first is not None:
                k += 1
                if fork_silent_at is None and k - k_first >= FEED_S * 100:
                    fork_silent_at = time.monotonic()
                stopped = any(m.status and m.status[0].message.startswith("protective stop: fork") for _, m in stats)
                # a second after the silence, and the stop seen on /mpcshare/status (at most 5 s: a loaded machine)
                if fork_silent_at is not None and now - fork_silent_at > (1.0 if stopped else 5.0):
                    break
            # on a 10 ms schedule, not 10 ms after this loop's work: a loaded machine must not slow the inputs
            t_next = max(t_next + 0.01, time.monotonic() - 0.05)
            time.sleep(max(0.0, t_next - time.monotonic()))
        assert proc.poll() is None, proc.communicate()
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=30)
        time.sleep(0.2)
        got += [(time.monotonic(), c) for c in commands.take(100)]
    finally:
        gc.enable()
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "mpcshare run: superlimb at 100 Hz" in out and "stopped after" in out and "protective stop: fork" in out
    assert fork_silent_at is not None, "no command came back"

    # commands: one point each, the arm's joints, stamped with the wall clock, ~100 Hz while fed
    live = [(r, c) for r, c in got if r < fork_silent_at]
    assert len(live) >= 0.8 * FEED_S * 100, (len(live), out)
    for _, c in live:
        assert c.joint_names == ["base_yaw", "shoulder", "elbow"] and len(c.points) == 1
        assert seconds(c.points[0].time_from_start) == pytest.approx(0.01)
        assert np.isfinite(c.points[0].positions).all() and len(c.points[0].velocities) == 3
    stamps = np.array([seconds(c.header.stamp) for _, c in live])
    assert np.all(np.diff(stamps) > 0) and abs(stamps[-1] - time.time()) < 60
    period = np.median(np.diff(stamps))
    mean = (stamps[-1] - stamps[0]) / (len(stamps) - 1)
    assert period == pytest.approx(0.01, abs=0.002) and mean == pytest.approx(0.01, rel=0.25), (period, mean, out)

    # the fork goes silent: stale (named) within its deadline, protective stop after stop_after_s (0.5 s)
    after = [(r, s) for r, s in stats if r >= fork_silent_at]
    levels = [(s.status[0].message, _status_values(s)) for _, s in after]
    assert any("stale: fork (/mocap/fork/pose" in m for m, _ in levels)
    stop_at = next(r for r, s in after if s.status[0].message.startswith("protective stop: fork"))
    assert 0.45 <= stop_at - fork_silent_at <= 0.5 + 0.3, (stop_at - fork_silent_at, out)
    stops = [c for r, c in got if r > stop_at + 0.05]
    assert stops, "no stop command"
    held = np.array(stops[0].points[0].positions)
    for c in stops:
        assert np.allclose(c.points[0].velocities, 0.0) and np.allclose(c.points[0].positions, held)
    live_status = [_status_values(s) for r, s in stats if r < fork_silent_at and s.status[0].values]
    ok = [v for v in live_status if v["status"] not in ("waiting",)]
    assert ok and {"alpha", "beta", "leader", "mode", "mode_proba", "clearance_m", "age_arm"} <= set(ok[-1])
    assert ok[-1]["leader"] in ("robot", "wearer") and float(ok[-1]["clearance_m"]) > 0
    final = _status_values(stats[-1][1]) if stats else {}
    assert final.get("status") in ("stopped", "protective_stop")

    # --timing: the ticks' profile, the collector frozen after setup (the default policy)
    timing = json.loads((tmp_path / "timing.json").read_text())
    assert timing["ticks"] >= FEED_S * 100 * 0.8 and timing["phases_ms"]["step"]["median"] > 0
    assert timing["gc_policy"]["policy"] == "managed" and timing["gc_policy"]["full_ms"] > 0
    assert timing["gc_policy"]["frozen_full_ms"] < timing["gc_policy"]["full_ms"]  # the frozen heap is not scanned
    assert sum(timing["causes"].values()) <= timing["ticks"]
