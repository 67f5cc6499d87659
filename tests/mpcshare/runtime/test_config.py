"""The arm's configuration of `mpcshare run`: the examples load; each bad file is one line, exit 1, nothing sent."""

from __future__ import annotations

import time

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from mpcshare.cli import main  # noqa: E402
from mpcshare.runtime.config import RunConfigError, load_run_config  # noqa: E402
from mpcshare.runtime.messages import DiagnosticArray, JointTrajectory  # noqa: E402
from mpcshare.runtime.transport import NetworkSettings, Transport  # noqa: E402
from tests.mpcshare.runtime.ros_helpers import DOMAIN, PANDA, SUPERLIMB, write_config  # noqa: E402


def test_the_examples_load():
    s = load_run_config(SUPERLIMB)
    assert s.arm.joints == ("base_yaw", "shoulder", "elbow") and s.rate_hz == 100.0
    assert s.network == NetworkSettings()  # loopback, multicast off, domain 0
    assert s.names("obs")[:3] == ["fork_x", "fork_y", "fork_z"] and len(s.names("voluntary")) == 3
    assert s.inputs["fork_wrench"].optional and not s.inputs["fork"].optional
    assert s.command.type == "trajectory_msgs/msg/JointTrajectory"
    p = load_run_config(PANDA)
    assert len(p.arm.joints) == 7 and p.command.type == "std_msgs/msg/Float64MultiArray"
    assert p.command.interface == "position" and p.robot.tip_frame == "panda_hand_tcp"


def test_the_panda_example_builds_its_arm():
    pytest.importorskip("example_robot_data")
    from mpcshare.runtime.setup import robot_description

    robot = robot_description(load_run_config(PANDA))
    assert list(robot.joint_names) == list(load_run_config(PANDA).arm.joints)


BAD = [  # (replace {regex: text}, append, what the one line names)
    ({r'^type = "geometry_msgs/msg/PoseStamped"': 'type = "geometry_msgs/msg/Twist"'}, "",
     "[inputs.fork] type: unknown message type 'geometry_msgs/msg/Twist'"),
    ({r'^topic = "/mocap/fork/pose"\n': ""}, "", "[inputs.fork] topic: missing"),
    ({r'^fork_x = "fork pose.position.x"': 'fork_x = "fork pose.positon.x"'}, "",
     "[obs] fork_x: field path 'pose.positon.x': Pose has no field 'positon'"),
    ({r'^fork_y = .*$': 'fork_y = "fork pose.position"'}, "", "[obs] fork_y: field path 'pose.position' ends at"),
    ({r'^fork_z = .*$': 'fork_z = "hand pose.position.z"'}, "", "[obs] fork_z: no input 'hand'"),
    ({r'^fork_fz = .*\n': ""}, "", "[obs] fork_fz: missing: the model reads this channel"),
    ({r'^shoulder_abduction = .*$': 'shoulder_abduction = "shoulder position[2]"\nelbow_angle = '
                                    '"shoulder position[3]"'}, "", "[voluntary] elbow_angle: the model has no such"),
    ({r'"shoulder", "elbow"\]': '"shoulder", "wrist"]'}, "", "[inputs.arm] joints: the model has no joint 'wrist'"),
    ({r'"base_yaw", "shoulder", "elbow"\]': '"shoulder", "base_yaw", "elbow"]'}, "",
     "[inputs.arm] joints: ['shoulder', 'base_yaw', 'elbow'] must be the model's joints in its order"),
    ({r'^rate_hz = 100.0': "rate_hz = 50.0"}, "", "top level rate_hz: 50 Hz is not the model's rate (100 Hz)"),
    ({r'^rate_hz = 100.0': "rate_hz = 5000.0"}, "", "top level rate_hz: must be a number in (0, 1000]"),
    ({r'^deadline_s = 0.03': "deadline_s = 0.002"}, "", "[inputs.arm] deadline_s: 0.002 s is shorter than one "
                                                       "control period"),
    ({r'^stop_after_s = 0.1': "stop_after_s = 0.02"}, "", "[inputs.arm] stop_after_s: 0.02 s must be longer"),
    ({r'^type = "trajectory_msgs/msg/JointTrajectory"': 'type = "std_msgs/msg/Float32MultiArray"'}, "",
     "[outputs.command] type: unknown message type 'std_msgs/msg/Float32MultiArray'"),
    ({r'^\[outputs.status\]': "[outputs.status]\nreliability = \"sometimes\""}, "",
     "[outputs.status] reliability: 'sometimes' is not one of best_effort, reliable"),
    ({r'^strategy = "gate"': 'strategy = "coin"'}, "", "[controller]: "),
    ({}, "\n[extra]\nx = 1\n", "top level extra: unknown key"),
    ({r'^\[inputs.arm\]': "[inputs.arm"}, "", "not valid TOML"),
    ({r'^tick = "arm"': 'tick = "fork"'}, "",
     "top level tick: 'fork' is not one of schedule, arm"),
    ({r'^resume_after_s = 1.0': "resume_after_s = -1"}, "", "top level resume_after_s: must be a number > 0"),
    ({r'^type = "trajectory_msgs/msg/JointTrajectory"': 'type = "std_msgs/msg/Float64MultiArray"\n'
                                                       'interface = "velocity"\ndriver_compensates_gravity = true'},
     "", "[outputs.command] driver_compensates_gravity: applies to an effort command only"),
    ({r'^type = "trajectory_msgs/msg/JointTrajectory"': 'type = "std_msgs/msg/Float64MultiArray"\n'
                                                       'interface = "effort"\ndriver_compensates_gravity = 1'},
     "", "[outputs.command] driver_compensates_gravity: must be true or false"),
]


@pytest.fixture(scope="module")
def listener():
    """Readers of the command and status topics in the test's domain: what a bad run must never send."""
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    return (t.reader("/joint_trajectory_controller/joint_trajectory", JointTrajectory),
            t.reader("/mpcshare/status", DiagnosticArray))


@pytest.mark.parametrize("replace,append,named", BAD, ids=[b[2][:40] for b in BAD])
def test_a_bad_config_is_one_line_exit_1_and_nothing_sent(replace, append, named, ros_model, listener, tmp_path,
                                                         capsys):
    model, _ = ros_model
    cfg = write_config(tmp_path, replace=replace, append=append)
    assert main(["run", "--model", str(model), "--config", str(cfg), "--duration", "1"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"mpcshare run: {cfg}"), err
    assert named in err, err
    time.sleep(0.05)
    assert [r.take() for r in listener] == [[], []]


def test_config_errors_are_value_errors_naming_the_file(tmp_path):
    with pytest.raises(RunConfigError, match="no such configuration file"):
        load_run_config(tmp_path / "none.toml")
    cfg = write_config(tmp_path, replace={r"^\[inputs.arm\]": "[inputs.knee]"})
    with pytest.raises(ValueError, match=r"superlimb.toml, \[inputs.arm\]: missing"):
        load_run_config(cfg)


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", "--config", str(SUPERLIMB)])
    assert exc.value.code == 2 and "--model" in capsys.readouterr().err


def test_the_rest_base_pose_is_the_mounts_convention():
    from mpcshare.runtime.setup import rest_base_pose
    from sim.scene import SceneConfig

    m = (0.0, -0.45, 0.0)  # a mount in the plate frame, the torso at rest
    p_torso = SceneConfig().mount_in_torso(m)
    np.testing.assert_allclose((rest_base_pose() @ np.append(p_torso, 1.0))[:3], m, atol=1e-12)
