"""The loop of `mpcshare run` tick by tick in one process: what the controller is given, what is published."""

from __future__ import annotations

import dataclasses
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from mpcshare.runtime.config import load_run_config  # noqa: E402
from mpcshare.runtime.loop import RunLoop  # noqa: E402
from mpcshare.runtime.messages import Clock as ClockMsg  # noqa: E402
from mpcshare.runtime.messages import (  # noqa: E402
    DiagnosticArray,
    Float64MultiArray,
    Header,
    JointState,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Time,
)
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport  # noqa: E402
from tests.mpcshare.runtime.ros_helpers import DOMAIN, write_config  # noqa: E402

OBS = ["fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw", "fork_fx", "fork_fy", "fork_fz"]
VOL = ["shoulder_elevation", "shoulder_protraction", "shoulder_abduction"]


class Recorder:
    """A controller that records its arguments and commands q + 0.01."""

    def __init__(self):
        self.calls = []

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        self.calls.append((t, np.array(obs), np.array(voluntary), np.array(q), np.array(v), base_pose))
        n = len(q)
        return SimpleNamespace(q_cmd=np.nan_to_num(q) + 0.01, v_cmd=np.ones(n), a_cmd=np.zeros(n), tau=np.full(n, 2.0),
                               alpha=1.0, beta=0.5, mode_proba=np.array([0.2, 0.8]), novelty=1.0, status="ok",
                               reasons=(), timings={"total": 1e-4})


class Clock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def _wait(reader, n=1, timeout=5.0):
    got, end = [], time.monotonic() + timeout
    while len(got) < n and time.monotonic() < end:
        got += reader.take()
        time.sleep(0.005)
    return got


@pytest.fixture()
def setup(tmp_path):
    cfg = load_run_config(write_config(tmp_path, replace={
        r'^topic = "/joint_trajectory_controller/joint_trajectory"\ntype = .*$':
            'topic = "/test_loop/commands"\ntype = "std_msgs/msg/Float64MultiArray"\ninterface = "velocity"',
        r'^topic = "/mpcshare/status"': 'topic = "/test_loop/status"'}))
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    clock, ctl = Clock(), Recorder()
    loop = RunLoop(cfg, ctl, t, obs_names=OBS, vol_names=VOL, clock=clock, wall=lambda: 1234.5)
    pubs = {n: t.writer(s.topic, {"sensor_msgs/msg/JointState": JointState,
                                  "geometry_msgs/msg/PoseStamped": PoseStamped}.get(s.type, PoseStamped))
            for n, s in cfg.inputs.items() if n != "fork_wrench"}
    out = (t.reader("/test_loop/commands", Float64MultiArray, QosSettings("reliable", 100)),
           t.reader("/test_loop/status", DiagnosticArray, QosSettings("reliable", 100)))
    end = time.monotonic() + 5.0
    while any(loop.readers[n]._reader.get_matched_publications() == [] for n in pubs) and time.monotonic() < end:
        time.sleep(0.01)
    time.sleep(0.05)
    return loop, ctl, clock, pubs, out


def _feed(pubs, frame="plate"):
    pubs["arm"].write(JointState(Header(Time(1, 0), ""), ["shoulder", "elbow", "base_yaw"], [0.2, 0.3, 0.1],
                                 [0.02, 0.03, 0.01], []))
    pubs["fork"].write(PoseStamped(Header(Time(1, 0), frame), Pose(Point(0.1, 0.2, 0.3), Quaternion(0, 0, 0, 1))))
    pubs["shoulder"].write(JointState(Header(Time(1, 0), ""), [], [0.5, 0.6, 0.7], [], []))
    pubs["torso"].write(PoseStamped(Header(Time(1, 0), "plate"), Pose(Point(-0.2, 0.1, 0.0), Quaternion())))
    time.sleep(0.05)


def test_inputs_reach_the_controller_in_its_order_and_stale_ones_are_withheld(setup):
    loop, ctl, clock, pubs, (commands, status) = setup
    assert loop.tick(0) == "waiting" and ctl.calls == []  # no joint state yet: status only
    _feed(pubs)
    clock.t += 0.01
    assert loop.tick(1) == "ok"
    t, obs, vol, q, v, base = ctl.calls[-1]
    assert t == pytest.approx(0.01)
    np.testing.assert_allclose(q, [0.1, 0.2, 0.3])  # by joint name, in the model's order
    np.testing.assert_allclose(v, [0.01, 0.02, 0.03])
    np.testing.assert_allclose(obs[:6], [0.1, 0.2, 0.3, 0, 0, 0])
    assert np.isnan(obs[6:]).all()  # the optional wrench never sent
    np.testing.assert_allclose(vol, [0.5, 0.6, 0.7])
    np.testing.assert_allclose(base[:3, 3], [-0.2, 0.1, 0.0])
    cmd = _wait(commands)[-1]
    assert list(cmd.data) == [1.0, 1.0, 1.0] and cmd.layout.dim[0].size == 3  # the velocity interface
    st = _wait(status, 2)[-1].status[0]
    values = {kv.key: kv.value for kv in st.values}
    assert st.level == 0 and values["leader"] == "robot" and values["mode"] == "1" and values["stamp"] == \
        "1234.500000000"
    clock.t += 0.06  # everything 0.06 s old: the arm (0.03 s), fork and shoulder (0.05 s) are stale, not the torso
    loop.tick(7)
    _, obs, vol, q, v, base = ctl.calls[-1]
    assert np.isnan(q).all() and np.isnan(v).all() and np.isnan(obs).all() and np.isnan(vol).all()
    assert np.isfinite(base).all()
    st = _wait(status)[-1].status[0]
    assert st.level == 1 and "stale: arm (/joint_states, 0.060 s), fork (/mocap/fork/pose, 0.060 s), shoulder" \
        in st.message
    clock.t += 0.1  # the arm past its stop_after_s (0.1 s): protective stop, the controller no longer called
    n = len(ctl.calls)
    assert loop.tick(17) == "protective_stop" and len(ctl.calls) == n
    assert list(_wait(commands)[-1].data) == [0.0, 0.0, 0.0]  # a velocity stop
    _feed(pubs)
    clock.t += 0.01
    assert loop.tick(18) == "protective_stop"  # latched


def test_a_message_in_another_frame_is_dropped_and_counted(setup):
    loop, ctl, clock, pubs, (commands, status) = setup
    _feed(pubs, frame="world")
    clock.t += 0.01
    loop.tick(1)
    assert np.isnan(ctl.calls[-1][1][:6]).all() and loop.wrong_frame["fork"] == 1
    values = {kv.key: kv.value for kv in _wait(status)[-1].status[0].values}
    assert values["wrong_frame_fork"] == "1"


def test_a_stop_for_a_silent_input_ends_once_every_input_is_fresh_again(setup):
    loop, ctl, clock, pubs, (commands, status) = setup
    loop.config = dataclasses.replace(loop.config, resume_after_s=0.05)
    _feed(pubs)
    loop.tick(0)
    clock.t += 0.2  # every input silent past its stop_after_s
    assert loop.tick(20) == "protective_stop"
    got = []
    for k in range(21, 27):
        _feed(pubs)
        clock.t += 0.02
        got.append(loop.tick(k))
    # fresh from tick 21: stopped while fresh for < 0.05 s, then called again
    assert got[:3] == ["protective_stop"] * 3 and got[3:] == ["ok"] * 3 and loop.summary.resumes == 1
    values = [{kv.key: kv.value for kv in s.status[0].values} for s in _wait(status, 8)]  # ticks 0, 20–26
    assert sum("resumed_after" in v for v in values) == 1


def test_sim_time_ticks_on_the_clock_and_a_jump_back_starts_afresh(tmp_path):
    cfg = load_run_config(write_config(tmp_path, replace={
        r'^topic = "/joint_trajectory_controller/joint_trajectory"': 'topic = "/test_sim_time/commands"',
        r'^topic = "/mpcshare/status"': 'topic = "/test_sim_time/status"'}))
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    ctl = Recorder()
    loop = RunLoop(cfg, ctl, t, obs_names=OBS, vol_names=VOL, sim_time=True)
    clock = t.writer("/clock", ClockMsg, QosSettings("reliable", 10))
    status = t.reader("/test_sim_time/status", DiagnosticArray, QosSettings("reliable", 100))
    end = time.monotonic() + 5.0
    while not clock.matched and time.monotonic() < end:
        time.sleep(0.01)
    done = threading.Thread(target=loop.run, args=(1.5,))
    done.start()
    for sec, ns in ((5, 0), (5, 10_000_000), (0, 0)):
        clock.write(ClockMsg(Time(sec, ns)))
        time.sleep(0.1)
    done.join()
    s = loop.summary
    assert s.ticks == 3 and s.clock_resets == 1
    stamps = [v for v in ({kv.key: kv.value for kv in m.status[0].values} for m in _wait(status, 4)) if "tick" in v]
    assert [(v["stamp"], v["tick"]) for v in stamps] == [("5.000000000", "0"), ("5.010000000", "1"),
                                                          ("0.000000000", "0")]


def test_ticking_on_the_arm_keeps_its_period_while_the_arm_is_silent(tmp_path):
    cfg = load_run_config(write_config(tmp_path, replace={
        r'^topic = "/joint_trajectory_controller/joint_trajectory"': 'topic = "/test_tick_arm/commands"',
        r'^topic = "/mpcshare/status"': 'topic = "/test_tick_arm/status"'}))
    loop = RunLoop(cfg, Recorder(), Transport(NetworkSettings(domain_id=DOMAIN)), obs_names=OBS, vol_names=VOL)
    t0 = time.monotonic()
    s = loop.run(0.3)
    wall = time.monotonic() - t0
    # no joint state: every tick at its window's end (half a period late), and the watchdog still stops
    assert s.ticks + s.late_ticks == 30 and wall < 3.0
    assert s.stop_reason.startswith("arm: no message") and s.statuses["protective_stop"] >= 10


def test_without_a_torso_pose_the_controller_is_given_the_rest_pose(setup):
    loop, ctl, clock, pubs, _ = setup
    rest = np.eye(4)
    rest[:3, 3] = [-0.4, 0.1, -0.21]
    loop.rest_base_pose = rest
    pubs["arm"].write(JointState(Header(Time(1, 0), ""), ["shoulder", "elbow", "base_yaw"], [0.2, 0.3, 0.1],
                                 [0.0, 0.0, 0.0], []))
    time.sleep(0.05)
    clock.t += 0.01
    loop.tick(1)
    np.testing.assert_array_equal(ctl.calls[-1][5], rest)
    _feed(pubs)  # then the torso's own pose
    clock.t += 0.01
    loop.tick(2)
    np.testing.assert_allclose(ctl.calls[-1][5][:3, 3], [-0.2, 0.1, 0.0])


class ArmRecorder(Recorder):
    """A Recorder on the SuperLimb's model (``robot``, as the shared controller has it)."""

    def __init__(self):
        super().__init__()
        from robot.default_arm import as_description

        self.robot = as_description(None)


@pytest.mark.parametrize("compensated", [False, True])
def test_an_effort_stop_holds_the_arm_against_gravity(tmp_path, compensated):
    pin = pytest.importorskip("pinocchio")
    cfg = load_run_config(write_config(tmp_path, replace={
        r'^topic = "/joint_trajectory_controller/joint_trajectory"\ntype = .*$':
            f'topic = "/test_effort_{compensated}/commands"\ntype = "std_msgs/msg/Float64MultiArray"\n'
            f'interface = "effort"\ndriver_compensates_gravity = {str(compensated).lower()}',
        r'^topic = "/mpcshare/status"': f'topic = "/test_effort_{compensated}/status"'}))
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    clock, ctl = Clock(), ArmRecorder()
    loop = RunLoop(cfg, ctl, t, obs_names=OBS, vol_names=VOL, clock=clock, wall=lambda: 1234.5)
    arm = t.writer(cfg.inputs["arm"].topic, JointState)
    commands = t.reader(f"/test_effort_{compensated}/commands", Float64MultiArray, QosSettings("reliable", 100))
    status = t.reader(f"/test_effort_{compensated}/status", DiagnosticArray, QosSettings("reliable", 100))
    end = time.monotonic() + 5.0
    while not arm.matched and time.monotonic() < end:
        time.sleep(0.01)
    q = np.array([0.1, 0.4, -0.3])  # base_yaw, shoulder, elbow: at rest
    arm.write(JointState(Header(Time(1, 0), ""), ["base_yaw", "shoulder", "elbow"], list(q), [0.0] * 3, []))
    time.sleep(0.05)
    loop.tick(0)
    g = pin.computeGeneralizedGravity(ctl.robot.model, ctl.robot.model.createData(), q)
    sent = np.array(_wait(commands)[-1].data)
    np.testing.assert_allclose(sent, 2.0 - g if compensated else 2.0, atol=1e-12)  # the controller's, less g
    clock.t += 1.0  # every input silent: protective stop
    assert loop.tick(100) == "protective_stop"
    stop = np.array(_wait(commands)[-1].data)
    # the arm's joint state is stale: gravity alone at the last measured posture (zeros for the driver's own)
    np.testing.assert_allclose(stop, 0.0 if compensated else g, atol=1e-12)
    values = {kv.key: kv.value for kv in _wait(status, 2)[-1].status[0].values}
    assert values["stop_torque"] == "gravity"
    arm.write(JointState(Header(Time(2, 0), ""), ["base_yaw", "shoulder", "elbow"], list(q), [0.0] * 3, []))
    time.sleep(0.05)
    clock.t += 0.01  # the arm fresh again, the other inputs still silent: the brake, at rest the holding torque
    assert loop.tick(101) == "protective_stop" and loop.effort.source == "brake"
    np.testing.assert_allclose(np.array(_wait(commands)[-1].data), 0.0 if compensated else g, atol=1e-12)


def test_gravity_compensation_by_the_driver_needs_an_arm_model(tmp_path):
    cfg = load_run_config(write_config(tmp_path, replace={
        r'^type = "trajectory_msgs/msg/JointTrajectory"':
            'type = "std_msgs/msg/Float64MultiArray"\ninterface = "effort"\ndriver_compensates_gravity = true'}))
    with pytest.raises(ValueError, match=r"\[outputs.command\] driver_compensates_gravity: needs the arm's model"):
        RunLoop(cfg, Recorder(), Transport(NetworkSettings(domain_id=DOMAIN)), obs_names=OBS, vol_names=VOL)
