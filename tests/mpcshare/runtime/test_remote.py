"""The robot stand-in (`mpcshare.runtime.remote` behind `mpcshare sim --serve`) and `mpcshare run --sim-time`
as two processes on loopback.

One pair of processes, one trial of 6 s: it tracks as the in-process `mpcshare sim` does until the first
outage, then meets the faults of ``FAULTS`` (the fork and the arm's joint states silenced, the shoulder's
publisher restarted), then `run` is killed (the stand-in holds the arm); each is checked in its own test.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from learning.data import save  # noqa: E402
from mpcshare.cli import main  # noqa: E402
from mpcshare.runtime.config import RunConfigError, load_run_config  # noqa: E402
from mpcshare.runtime.convert import command_message, read_path  # noqa: E402
from mpcshare.runtime.messages import Clock, DiagnosticArray, JointTrajectory, Time, seconds  # noqa: E402
from mpcshare.runtime.remote import Outage, RemoteController, parse_outage  # noqa: E402
from mpcshare.runtime.setup import robot_description  # noqa: E402
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport  # noqa: E402
from tests.mpcshare.runtime.ros_helpers import DOMAIN, PANDA, ROOT, write_config  # noqa: E402

T = 0.01  # the control period [s]
RESUME_S = 0.3  # the test configuration's resume_after_s
CLEAN_S = 1.0  # seconds before the first outage
DURATION_S = 6.0  # the kill at 4.7 s lands up to ~0.3 s late on a quiet machine (the test polls the clock)
PANDA_S = 1.0  # the Panda's trial [s]
_TORSO = """
[inputs.torso]
topic = "/mocap/torso/pose"
optional = true
frame = "plate"
"""
FAULTS = ["--drop", "fork:1.0:1.7", "--drop", "arm:2.5:2.8", "--restart", "shoulder:3.5:3.7"]


def _start(argv: list[str], cwd: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("CYCLONEDDS_URI", None)
    return subprocess.Popen([sys.executable, "-m", "mpcshare", *argv], cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _end(*procs: subprocess.Popen) -> None:
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.communicate()


@pytest.fixture(scope="module")
def served(ros_model, tmp_path_factory):
    """The model and its data saved, a configuration of this test's DDS domain."""
    model, demos = ros_model
    root = tmp_path_factory.mktemp("serve")
    data = root / "demos.npz"
    save(demos, data)
    cfg = write_config(root, replace={r"^resume_after_s = 1.0": f"resume_after_s = {RESUME_S}"})
    return root, model, data, cfg


class _Listener:
    """The test's own participant: the clock, the commands and the statuses of the pair, kept by time."""

    def __init__(self) -> None:
        t = Transport(NetworkSettings(domain_id=DOMAIN))
        self.clock = t.reader("/clock", Clock, QosSettings("reliable", 1000))
        self.cmd = t.reader("/joint_trajectory_controller/joint_trajectory", JointTrajectory,
                            QosSettings("reliable", 1000))
        self.st = t.reader("/mpcshare/status", DiagnosticArray, QosSettings("reliable", 1000))
        self.times: list[float] = []
        self.commands: list[tuple[float, JointTrajectory]] = []
        self.statuses: list[tuple[float, str, dict[str, str]]] = []

    def poll(self) -> None:
        self.times += [seconds(c.clock) for c in self.clock.take(1000)]
        self.commands += [(seconds(c.header.stamp), c) for c in self.cmd.take(1000)]
        for s in self.st.take(1000):
            v = {kv.key: kv.value for kv in s.status[0].values}
            self.statuses.append((seconds(s.header.stamp), s.status[0].message, v))


def _pair(served, out: Path, extra: list[str], trials: int, duration: float,
          kill_at: tuple[int, float] | None = None, cfg: Path | None = None,
          meanwhile: Callable[[], None] = lambda: None) -> tuple[str, str, _Listener, bool]:
    """Run ``run --sim-time`` and ``sim --serve`` to the stand-in's end (``kill_at`` (episode, t): SIGKILL
    ``run`` when the clock reaches t in that episode); then SIGTERM ``run``. (run's stdout, the stand-in's
    stdout, what was heard, whether run was killed); ``cfg``: another configuration than ``served``'s;
    ``meanwhile`` is called once both processes are started (while they load)."""
    root, model, data, served_cfg = served
    cfg = cfg or served_cfg
    listen = _Listener()
    run = _start(["run", "--model", str(model), "--config", str(cfg), "--sim-time"], root)
    stand = _start(["sim", "--model", str(model), "--data", str(data), "--out", str(out), "--serve", "--config",
                    str(cfg), "--trials", str(trials), "--duration", str(duration), "--serve-wait", "90", *extra],
                   root)
    killed = False
    try:
        meanwhile()
        episode, last, end = 0, -1.0, time.monotonic() + 180
        while stand.poll() is None and time.monotonic() < end:
            n = len(listen.times)
            listen.poll()
            for t in listen.times[n:]:
                episode, last = episode + (t < last), t
                if kill_at is not None and not killed and (episode, t) >= kill_at:
                    run.kill()
                    killed = True
            time.sleep(0.005)
        s_out, s_err = stand.communicate(timeout=60)
        assert stand.returncode == 0, s_out + s_err
        time.sleep(0.1)
        listen.poll()
        if not killed:
            run.send_signal(signal.SIGTERM)
        r_out, r_err = run.communicate(timeout=30)
        assert killed or run.returncode == 0, r_err
    finally:
        _end(stand, run)
    return r_out, s_out, listen, killed


@pytest.fixture(scope="module")
def pair(served):
    """One trial of 6 s across processes with the outages of ``FAULTS``, ``run`` killed at t = 4.7 s."""
    root = served[0]
    r_out, s_out, listen, killed = _pair(served, root / "across", FAULTS, 1, DURATION_S, kill_at=(0, 4.7))
    assert killed, s_out
    return root / "across", s_out, listen, json.loads((root / "across" / "comparison.json").read_text())


def _episode(folder: Path):
    return np.load(next((folder / "runs").glob("gate_trial*.npz")))


def test_across_processes_tracks_as_in_one_process(served, pair):
    root, model, data, _ = served
    across, _, _, comp = pair
    assert main(["sim", "--model", str(model), "--data", str(data), "--out", str(root / "inproc"), "--runs", "gate",
                 "--trials", "1", "--duration", str(DURATION_S)]) == 0
    a, b = _episode(across), _episode(root / "inproc")
    n = round(CLEAN_S / T)  # the steps before the first outage: the same inputs in both loops
    assert np.array_equal(a["t"], b["t"]) and np.array_equal(a["tip_intent"], b["tip_intent"])
    rms = [float(np.sqrt(np.mean(np.sum((e["tip"][:n] - e["tip_intent"][:n]) ** 2, axis=1)))) for e in (a, b)]
    assert abs(rms[0] - rms[1]) <= 0.05 * rms[1], rms
    assert np.abs(a["tip"][:n] - b["tip"][:n]).max() < 1e-6  # lockstep: the same loop, to the wire's rounding
    m = comp["per_trial"]["gate"][next(iter(comp["per_trial"]["gate"]))]
    assert m["limit_violations"] == 0 and m["keepout_steps_driven_in"] == 0  # the whole run, faults included


def test_a_killed_run_leaves_the_arm_held_by_the_stand_in(pair):
    across, s_out, listen, _ = pair
    e = _episode(across)
    status, t = e["status"], e["t"]
    last_cmd = max(t for t, _ in listen.commands)
    assert 4.6 <= last_cmd < DURATION_S - 0.3, last_cmd  # killed at 4.7 s, heard late; held periods follow
    held = status == "invalid_command"
    # the command run was sending as it died may not reach the stand-in (no retransmission from a dead writer)
    assert held.any() and not held[t < last_cmd - 1e-9].any(), np.unique(status)
    first = int(np.flatnonzero(held)[0])
    assert t[first] <= last_cmd + T + 1e-9 and held[first:].all()  # held from the first period without a command
    assert int(e["info_limit_violations"]) == 0
    assert "control steps without a command" in s_out


def _stop_check(listen: _Listener, name: str, last_msg: float, deadline: float, stop_after: float, back: float):
    stale = [t for t, _, v in listen.statuses if name in v.get("stale_inputs", "").split(",") and t > last_msg]
    assert stale and min(stale) <= last_msg + deadline + 2 * T + 1e-9, stale[:3]
    stops = [(t, v["protective_stop"]) for t, _, v in listen.statuses
             if "protective_stop" in v and last_msg < t < back + 1.0]
    assert stops and stops[0][1].startswith(f"{name}: no message"), stops[:1]
    t_stop = stops[0][0]
    assert last_msg + stop_after - 1e-9 <= t_stop <= last_msg + stop_after + 2 * T + 1e-9, t_stop
    held = [c for t, c in listen.commands if t_stop <= t < back]
    assert held and all(np.allclose(c.points[0].velocities, 0.0) for c in held)
    q_stop = held[0].points[0].positions
    assert all(np.allclose(c.points[0].positions, q_stop) for c in held)
    resumed = [t for t, _, v in listen.statuses if t > back and v.get("status") not in ("protective_stop",)
               and "resumed_after" in v]
    assert resumed and resumed[0] <= back + RESUME_S + 2 * T + 1e-9, resumed[:1]
    moving = [c for t, c in listen.commands if resumed[0] <= t < resumed[0] + 0.5]
    assert any(not np.allclose(c.points[0].velocities, 0.0) for c in moving)


def test_the_fork_silenced_stops_the_arm_then_resumes(pair):
    _stop_check(pair[2], "fork", 0.99, 0.05, 0.5, 1.7)


def test_the_joint_states_silenced_stop_the_arm_then_resume(pair):
    _stop_check(pair[2], "arm", 2.49, 0.03, 0.1, 2.8)
    assert sum("resumed_after" in v for _, _, v in pair[2].statuses) == 2


def test_a_restarted_publisher_is_heard_again_without_a_stop(pair):
    _, _, listen, comp = pair
    gap = [v for t, _, v in listen.statuses if 3.5 < t < 3.7]
    assert any("shoulder" in v.get("stale_inputs", "") for v in gap)
    assert not any("protective_stop" in v for v in gap)
    after = [v for t, _, v in listen.statuses if 3.75 <= t < 4.4]
    assert after and not any("shoulder" in v.get("stale_inputs", "") for v in after)
    m = comp["per_trial"]["gate"][next(iter(comp["per_trial"]["gate"]))]
    assert m["limit_violations"] == 0 and m["keepout_steps_driven_in"] == 0


def test_each_input_is_built_from_its_channels_and_reads_back(tmp_path):
    config = load_run_config(write_config(tmp_path))
    obs = ["fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw", "fork_fx", "fork_fy", "fork_fz"]
    vol = ["shoulder_elevation", "shoulder_protraction", "shoulder_abduction"]
    remote = RemoteController(config, Transport(NetworkSettings(domain_id=DOMAIN)), obs_names=obs, vol_names=vol)
    row = {("obs", n): v for n, v in zip(obs, [0.1, -0.2, 0.05, 0.3, -0.4, 2.9, 1.0, -2.0, 3.0])}
    row.update({("voluntary", n): v for n, v in zip(vol, [0.5, -0.1, 0.2])})
    for w in remote.inputs:
        msg = w.message(Time(3, 4), row)
        assert msg.header.stamp == Time(3, 4) and msg.header.frame_id == config.inputs[w.name].frame
        for kind, name, path in w.channels:
            assert read_path(msg, path) == pytest.approx(row[(kind, name)], abs=1e-12), (w.name, name)
    assert {w.name for w in remote.inputs} == {"fork", "fork_wrench", "shoulder"}


def test_bad_stand_in_requests_are_named():
    with pytest.raises(ValueError, match="expected INPUT:START:END"):
        parse_outage("fork:5")
    with pytest.raises(ValueError, match="need 0 <= START < END"):
        parse_outage("fork:7:5")
    assert parse_outage("arm:1:2.5", restart=True) == Outage("arm", 1.0, 2.5, True)


def test_the_stand_in_refuses_what_it_cannot_follow(tmp_path):
    config = load_run_config(write_config(tmp_path))
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    with pytest.raises(RunConfigError, match=r"\[obs\] fork_x: the simulator has no such channel"):
        RemoteController(config, t, obs_names=["x"], vol_names=[])
    with pytest.raises(RunConfigError, match="no input 'hand' to silence"):
        RemoteController(config, t, obs_names=list(config.names("obs")), vol_names=list(config.names("voluntary")),
                         outages=[Outage("hand", 0.0, 1.0)])
    remote = RemoteController(config, t, obs_names=list(config.names("obs")),
                              vol_names=list(config.names("voluntary")))
    with pytest.raises(RunConfigError, match=r"\[inputs.arm\] joints: .* are not the simulated arm's"):
        remote.bind(robot_description(load_run_config(PANDA)))


@pytest.mark.parametrize("kind, interface", [("trajectory_msgs/msg/JointTrajectory", "position"),
                                             ("std_msgs/msg/Float64MultiArray", "position"),
                                             ("std_msgs/msg/Float64MultiArray", "velocity"),
                                             ("std_msgs/msg/Float64MultiArray", "effort")])
def test_every_command_form_gives_back_the_controllers_segment(tmp_path, kind, interface):
    pin = pytest.importorskip("pinocchio")
    config = load_run_config(write_config(tmp_path, PANDA, replace={
        r"^type = \"std_msgs/msg/Float64MultiArray\"": f'type = "{kind}"',
        r"^interface = \"position\"": "" if kind.startswith("trajectory") else f'interface = "{interface}"'}))
    robot = robot_description(load_run_config(PANDA))
    remote = RemoteController(config, Transport(NetworkSettings(domain_id=DOMAIN)),
                              obs_names=list(config.names("obs")), vol_names=list(config.names("voluntary")))
    remote.bind(robot)
    rng = np.random.default_rng(3)
    q, v, a = rng.uniform(-1, 1, 7), rng.uniform(-0.5, 0.5, 7), rng.uniform(-3, 3, 7)
    v1, q1 = v + a * T, q + (v + 0.5 * T * a) * T  # the QP's integration
    tau = pin.rnea(robot.model, robot.model.createData(), q, v, a)
    msg = command_message(kind, interface, config.arm.joints, Time(1, 0), T, q1, v1, a, tau)
    got = remote._segment(msg, q, v)
    for x, want in zip(got, (q1, v1, a)):
        assert np.allclose(x, want, rtol=0, atol=1e-9 if interface != "position" or kind.startswith("traj") else 1e-6)
    bad = command_message(kind, interface, config.arm.joints[:3], Time(1, 0), T, q1[:3], v1[:3], a[:3], tau[:3])
    assert remote._segment(bad, q, v) is None  # not the arm's joints


def test_the_stand_in_plays_a_driver_that_adds_gravity(tmp_path):
    pin = pytest.importorskip("pinocchio")
    kind = "std_msgs/msg/Float64MultiArray"
    config = load_run_config(write_config(tmp_path, PANDA, replace={
        r"^interface = \"position\"": 'interface = "effort"\ndriver_compensates_gravity = true'}))
    robot = robot_description(config)
    remote = RemoteController(config, Transport(NetworkSettings(domain_id=DOMAIN)),
                              obs_names=list(config.names("obs")), vol_names=list(config.names("voluntary")))
    remote.bind(robot)
    rng = np.random.default_rng(4)
    q, v, a = rng.uniform(-1, 1, 7), rng.uniform(-0.5, 0.5, 7), rng.uniform(-3, 3, 7)
    data = robot.model.createData()
    sent = pin.rnea(robot.model, data, q, v, a) - pin.computeGeneralizedGravity(robot.model, data, q)
    msg = command_message(kind, "effort", config.arm.joints, Time(1, 0), T, q, v, a, sent)
    assert np.allclose(remote._segment(msg, q, v)[2], a, rtol=0, atol=1e-9)  # τ − g(q) + g(q): the same motion


def test_the_panda_over_forward_commands_tracks_as_in_one_process(served, tmp_path):
    """The Panda of examples/ros2/panda.toml (a Float64MultiArray position command) against ``sim --robot
    panda``; with the torso's pose as an input, since the simulator sways the arm's base with the torso."""
    root, model, data, _ = served
    cfg = write_config(tmp_path, PANDA, append=_TORSO)
    arm = ["--robot", "panda", "--velocity-limit", "1.5", "--acceleration-limit", "6.0"]
    inproc = ["sim", "--model", str(model), "--data", str(data), "--out", str(tmp_path / "inproc"), "--runs", "gate",
              "--trials", "1", "--duration", str(PANDA_S), *arm]
    codes: list[int] = []
    _, s_out, _, _ = _pair(served, tmp_path / "across", arm, 1, PANDA_S, cfg=cfg,
                           meanwhile=lambda: codes.append(main(inproc)))
    assert "0 control steps without a command" in s_out and codes == [0]
    a, b = _episode(tmp_path / "across"), _episode(tmp_path / "inproc")
    assert np.array_equal(a["t"], b["t"]) and (a["status"] == "ok").all()
    assert np.abs(a["tip"] - b["tip"]).max() < 1e-6
    assert int(a["info_limit_violations"]) == 0


@pytest.mark.parametrize("argv, words", [
    (["--drop", "fork:1:2"], "--drop needs --serve"),
    (["--realtime", "--live"], "--realtime, --live need --serve"),
    (["--serve", "--video"], "--serve runs the controller of `mpcshare run`: --video cannot apply to it"),
    (["--serve", "--no-keepout", "--scenario", "push"], "--scenario, --no-keepout cannot apply"),
])
def test_stand_in_options_that_cannot_apply_are_one_line(tmp_path, capsys, argv, words):
    assert main(["sim", "--model", str(tmp_path / "none"), "--out", str(tmp_path / "out"), *argv]) == 1
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1, err


def test_an_effort_stop_holds_the_arm_where_it_stopped(served, tmp_path):
    """The SuperLimb over a Float64MultiArray effort command (total torques, gravity included; the stand-in
    applies them through ABA), the fork silenced past its stop: the stop's torques brake the arm and hold it
    against gravity, where zero efforts would let it fall."""
    cfg = write_config(tmp_path, replace={
        r"^resume_after_s = 1.0": f"resume_after_s = {RESUME_S}",
        r'^type = "trajectory_msgs/msg/JointTrajectory"': 'type = "std_msgs/msg/Float64MultiArray"\n'
                                                         'interface = "effort"'})
    _pair(served, tmp_path / "across", ["--drop", "fork:0.3:1.2"], 1, 1.4, cfg=cfg)
    pin = pytest.importorskip("pinocchio")
    e = _episode(tmp_path / "across")
    stopped = np.flatnonzero(e["status"] == "protective_stop")
    assert stopped.size > 30 and 0.8 - 1e-9 <= e["t"][stopped[0]] <= 0.8 + 2 * T + 1e-9  # stop_after_s 0.5 s
    robot = robot_description(load_run_config(cfg))
    data = robot.model.createData()

    def tip(q):  # the knife tip in the arm's frame: the arm's own motion, not the wearer's torso under it
        pin.framesForwardKinematics(robot.model, data, q)
        return data.oMf[robot.tip_frame_id].translation.copy()

    moved = max(np.linalg.norm(tip(e["q"][k]) - tip(e["q"][stopped[0]])) for k in stopped)
    assert moved < 0.002, moved  # braked from ~0.1 m/s; zero efforts: the shoulder falls ~1 rad in 0.4 s
    assert np.linalg.norm(e["tip"][stopped] - e["tip"][stopped[0]], axis=1).max() < 0.005  # plate frame
    assert int(e["info_limit_violations"]) == 0
