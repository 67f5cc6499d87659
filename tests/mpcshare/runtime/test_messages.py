"""The ROS 2 messages of `mpcshare run`: byte-equal to an independent ROS 2 CDR serialiser (rosbags), ROS 2's names."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from rosbags.typesys import Stores, get_typestore  # noqa: E402

from mpcshare.runtime import messages as m  # noqa: E402

TS = get_typestore(Stores.ROS2_HUMBLE)


def _time(s, ns):
    return m.Time(s, ns)


#: one filled-in sample of every message type, non-default in every field
SAMPLES = {
    "builtin_interfaces/msg/Time": m.Time(1_700_000_000, 123_456_789),
    "builtin_interfaces/msg/Duration": m.Duration(0, 10_000_000),
    "std_msgs/msg/Header": m.Header(_time(5, 6), "plate"),
    "std_msgs/msg/MultiArrayDimension": m.MultiArrayDimension("joints", 7, 7),
    "std_msgs/msg/MultiArrayLayout": m.MultiArrayLayout([m.MultiArrayDimension("joints", 3, 3),
                                                        m.MultiArrayDimension("x", 1, 1)], 2),
    "std_msgs/msg/Float64MultiArray": m.Float64MultiArray(m.MultiArrayLayout([m.MultiArrayDimension("joints", 3, 3)]),
                                                          [0.1, -2.5, 3e-9]),
    "sensor_msgs/msg/JointState": m.JointState(m.Header(_time(7, 8), "arm"), ["base_yaw", "shoulder", "elbow"],
                                               [0.1, 0.2, 0.3], [1.0, -1.0, 0.5], [2.0]),
    "geometry_msgs/msg/Point": m.Point(1.0, 2.0, -3.0),
    "geometry_msgs/msg/Vector3": m.Vector3(0.5, -0.5, 9.81),
    "geometry_msgs/msg/Quaternion": m.Quaternion(0.1, 0.2, 0.3, 0.9),
    "geometry_msgs/msg/Pose": m.Pose(m.Point(0.1, 0.2, 0.3), m.Quaternion(0.0, 0.0, 0.7071, 0.7071)),
    "geometry_msgs/msg/PoseStamped": m.PoseStamped(m.Header(_time(9, 10), "plate"),
                                                   m.Pose(m.Point(0.1, -0.2, 0.05), m.Quaternion(0.1, 0.0, 0.0, 0.99))),
    "geometry_msgs/msg/Wrench": m.Wrench(m.Vector3(1, 2, 3), m.Vector3(-1, -2, -3)),
    "geometry_msgs/msg/WrenchStamped": m.WrenchStamped(m.Header(_time(1, 2), "fork"),
                                                       m.Wrench(m.Vector3(0.1, 0.2, -4.0), m.Vector3(0, 0.01, 0))),
    "trajectory_msgs/msg/JointTrajectoryPoint": m.JointTrajectoryPoint([1.0, 2.0], [0.1], [], [5.0, 6.0, 7.0],
                                                                       m.Duration(1, 5)),
    "trajectory_msgs/msg/JointTrajectory": m.JointTrajectory(
        m.Header(_time(3, 4), ""), ["j1", "j2", "j3"],
        [m.JointTrajectoryPoint([0.1, 0.2, 0.3], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [], m.Duration(0, 10_000_000)),
         m.JointTrajectoryPoint([0.2, 0.3, 0.4], [], [], [], m.Duration(0, 20_000_000))]),
    "diagnostic_msgs/msg/KeyValue": m.KeyValue("alpha", "0.5"),
    "diagnostic_msgs/msg/DiagnosticStatus": m.DiagnosticStatus(2, "mpcshare", "stale_fork_sensor", "superlimb",
                                                               [m.KeyValue("a", "1"), m.KeyValue("bb", "")]),
    "diagnostic_msgs/msg/DiagnosticArray": m.DiagnosticArray(
        m.Header(_time(11, 12), ""), [m.DiagnosticStatus(1, "n", "msg", "hw", [m.KeyValue("k", "v")]),
                                      m.DiagnosticStatus(0, "", "", "", [])]),
    "rosgraph_msgs/msg/Clock": m.Clock(m.Time(12, 340_000_000)),
}


def _to_rosbags(x):
    """The same message built with rosbags' ROS 2 Humble types (float arrays as numpy, as rosbags wants)."""
    name = next(n for n, cls in m.MESSAGE_TYPES.items() if cls is type(x))
    cls = TS.types[name]
    kwargs = {}
    for f in dataclasses.fields(x):
        v = getattr(x, f.name)
        if dataclasses.is_dataclass(v):
            v = _to_rosbags(v)
        elif isinstance(v, list):
            if v and dataclasses.is_dataclass(v[0]):
                v = [_to_rosbags(e) for e in v]
            elif not v or isinstance(v[0], (int, float)):
                v = np.array(v, dtype=np.float64) if f.name not in ("name", "joint_names") else list(v)
        kwargs[f.name] = v
    return cls(**kwargs)


def test_every_message_type_has_a_sample():
    assert set(SAMPLES) == set(m.MESSAGE_TYPES)


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_bytes_equal_rosbags_ros2_cdr(name):
    msg = SAMPLES[name]
    ours = bytes(msg.serialize())
    theirs = bytes(TS.serialize_cdr(_to_rosbags(msg), name))
    assert ours == theirs
    assert type(msg).deserialize(theirs) == msg  # and ROS 2's bytes read back


@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_dds_type_names_are_ros2s(name):
    pkg, _, short = name.split("/")
    assert m.MESSAGE_TYPES[name].__idl_typename__ == f"{pkg}::msg::dds_::{short}_" == m.dds_type_name(name)


def test_names_and_times():
    assert m.dds_type_name("sensor_msgs/msg/JointState") == "sensor_msgs::msg::dds_::JointState_"
    assert m.dds_topic("/joint_states") == "rt/joint_states"
    assert m.dds_topic("/a/b") == "rt/a/b"
    for bad in ("joint_states", "/", "/a//b", "/a/"):
        with pytest.raises(ValueError, match="absolute ROS name"):
            m.dds_topic(bad)
    with pytest.raises(ValueError, match="package/msg/Name"):
        m.dds_type_name("sensor_msgs/JointState")
    assert m.ros_time(12.25) == m.Time(12, 250_000_000)
    assert m.seconds(m.ros_time(1.5)) == 1.5
    assert m.Quaternion() == m.Quaternion(0, 0, 0, 1)  # ROS 2's identity default


def test_the_status_serialised_by_rosbags_is_the_status_message():
    from mpcshare.runtime.convert import status_cdr, status_message

    values = {"status": "ok", "tick": 3, "alpha": 0.123456789, "mode_proba": np.array([0.25, 0.75]), "reasons": "",
              "tip_reference": np.array([0.1, np.nan, 3.0]), "leader": "robot"}
    args = (m.Time(12, 34), "mpcshare: shared controller", "superlimb", 1, "reference_unreachable", values)
    ours = status_cdr(*args)
    assert ours == bytes(status_message(*args).serialize())
    back = m.DiagnosticArray.deserialize(ours).status[0]
    assert {kv.key: kv.value for kv in back.values} == {"status": "ok", "tick": "3", "alpha": "0.123457",
                                                        "mode_proba": "0.25,0.75", "reasons": "",
                                                        "tip_reference": "0.1,nan,3", "leader": "robot"}
