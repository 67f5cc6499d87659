"""The ROS 2 messages ``mpcshare run`` reads and writes, as Cyclone DDS types with ROS 2's DDS names.

ROS 2 (rmw) maps a message ``pkg/msg/Name`` to the DDS type ``pkg::msg::dds_::Name_`` and a topic
``/name`` to the DDS topic ``rt/name``; the payload is XCDR1 (plain CDR, little endian), the bytes an
unmodified ROS 2 node sends. Each class below declares the fields of the ROS 2 (Humble onwards)
definition in order, so its ``serialize()`` equals ROS 2's bytes (tested against ``rosbags``).
No ``from __future__ import annotations`` here: Cyclone DDS reads the field annotations as types.

:data:`MESSAGE_TYPES` maps the ROS names (``sensor_msgs/msg/JointState``) to the classes;
:func:`dds_topic` and :func:`dds_type_name` give the DDS names of a ROS topic and message type.
"""

import math
from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import byte, float64, int32, sequence, uint32

__all__ = ["MESSAGE_TYPES", "Clock", "DiagnosticArray", "DiagnosticStatus", "Duration", "Float64MultiArray", "Header",
           "JointState", "JointTrajectory", "JointTrajectoryPoint", "KeyValue", "MultiArrayDimension",
           "MultiArrayLayout", "Point", "Pose", "PoseStamped", "Quaternion", "Time", "Vector3", "Wrench",
           "WrenchStamped", "dds_topic", "dds_type_name", "ros_time", "seconds"]


def dds_type_name(ros_type: str) -> str:
    """``pkg/msg/Name`` → ``pkg::msg::dds_::Name_`` (ROS 2's DDS type name); ValueError for another form."""
    parts = ros_type.split("/")
    if len(parts) != 3 or not all(parts) or parts[1] != "msg":
        raise ValueError(f"message type {ros_type!r} is not of the form package/msg/Name")
    return f"{parts[0]}::msg::dds_::{parts[2]}_"


def dds_topic(ros_topic: str) -> str:
    """``/a/b`` → ``rt/a/b`` (ROS 2's DDS topic name of an absolute topic); ValueError for a relative one."""
    if not ros_topic.startswith("/") or ros_topic == "/" or "//" in ros_topic or ros_topic.endswith("/"):
        raise ValueError(f"topic {ros_topic!r} is not an absolute ROS name (/name/name)")
    return "rt" + ros_topic


# --------------------------------------------------------------------------- builtin_interfaces, std_msgs
@dataclass
class Time(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):
    """builtin_interfaces/msg/Time: sec [s], nanosec [ns] (0 ≤ nanosec < 1e9)."""

    sec: int32 = 0
    nanosec: uint32 = 0


@dataclass
class Duration(IdlStruct, typename="builtin_interfaces::msg::dds_::Duration_"):
    """builtin_interfaces/msg/Duration: sec [s], nanosec [ns]."""

    sec: int32 = 0
    nanosec: uint32 = 0


def ros_time(t: float) -> Time:
    """Seconds (e.g. ``time.time()``) as a :class:`Time`, nanoseconds rounded down."""
    ns = int(math.floor(t * 1e9))
    return Time(ns // 1_000_000_000, ns % 1_000_000_000)


def seconds(stamp: Time | Duration) -> float:
    """A :class:`Time` or :class:`Duration` in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


@dataclass
class Header(IdlStruct, typename="std_msgs::msg::dds_::Header_"):
    """std_msgs/msg/Header: stamp, frame_id."""

    stamp: Time = field(default_factory=Time)
    frame_id: str = ""


@dataclass
class MultiArrayDimension(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayDimension_"):
    """std_msgs/msg/MultiArrayDimension: label, size, stride."""

    label: str = ""
    size: uint32 = 0
    stride: uint32 = 0


@dataclass
class MultiArrayLayout(IdlStruct, typename="std_msgs::msg::dds_::MultiArrayLayout_"):
    """std_msgs/msg/MultiArrayLayout: dim, data_offset."""

    dim: sequence[MultiArrayDimension] = field(default_factory=list)
    data_offset: uint32 = 0


@dataclass
class Float64MultiArray(IdlStruct, typename="std_msgs::msg::dds_::Float64MultiArray_"):
    """std_msgs/msg/Float64MultiArray: layout, data (ros2_control's forward command controllers)."""

    layout: MultiArrayLayout = field(default_factory=MultiArrayLayout)
    data: sequence[float64] = field(default_factory=list)


# --------------------------------------------------------------------------- sensor_msgs, geometry_msgs
@dataclass
class JointState(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):
    """sensor_msgs/msg/JointState: header, name, position [rad], velocity [rad/s], effort [N·m]."""

    header: Header = field(default_factory=Header)
    name: sequence[str] = field(default_factory=list)
    position: sequence[float64] = field(default_factory=list)
    velocity: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)


@dataclass
class Point(IdlStruct, typename="geometry_msgs::msg::dds_::Point_"):
    """geometry_msgs/msg/Point [m]."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """geometry_msgs/msg/Vector3."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0


@dataclass
class Quaternion(IdlStruct, typename="geometry_msgs::msg::dds_::Quaternion_"):
    """geometry_msgs/msg/Quaternion (x, y, z, w); the identity by default, as in ROS 2."""

    x: float64 = 0.0
    y: float64 = 0.0
    z: float64 = 0.0
    w: float64 = 1.0


@dataclass
class Pose(IdlStruct, typename="geometry_msgs::msg::dds_::Pose_"):
    """geometry_msgs/msg/Pose: position, orientation."""

    position: Point = field(default_factory=Point)
    orientation: Quaternion = field(default_factory=Quaternion)


@dataclass
class PoseStamped(IdlStruct, typename="geometry_msgs::msg::dds_::PoseStamped_"):
    """geometry_msgs/msg/PoseStamped: header, pose."""

    header: Header = field(default_factory=Header)
    pose: Pose = field(default_factory=Pose)


@dataclass
class Wrench(IdlStruct, typename="geometry_msgs::msg::dds_::Wrench_"):
    """geometry_msgs/msg/Wrench: force [N], torque [N·m]."""

    force: Vector3 = field(default_factory=Vector3)
    torque: Vector3 = field(default_factory=Vector3)


@dataclass
class WrenchStamped(IdlStruct, typename="geometry_msgs::msg::dds_::WrenchStamped_"):
    """geometry_msgs/msg/WrenchStamped: header, wrench."""

    header: Header = field(default_factory=Header)
    wrench: Wrench = field(default_factory=Wrench)


# --------------------------------------------------------------------------- trajectory_msgs
@dataclass
class JointTrajectoryPoint(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectoryPoint_"):
    """trajectory_msgs/msg/JointTrajectoryPoint: positions, velocities, accelerations, effort, time_from_start."""

    positions: sequence[float64] = field(default_factory=list)
    velocities: sequence[float64] = field(default_factory=list)
    accelerations: sequence[float64] = field(default_factory=list)
    effort: sequence[float64] = field(default_factory=list)
    time_from_start: Duration = field(default_factory=Duration)


@dataclass
class JointTrajectory(IdlStruct, typename="trajectory_msgs::msg::dds_::JointTrajectory_"):
    """trajectory_msgs/msg/JointTrajectory: header, joint_names, points (ros2_control's trajectory controller)."""

    header: Header = field(default_factory=Header)
    joint_names: sequence[str] = field(default_factory=list)
    points: sequence[JointTrajectoryPoint] = field(default_factory=list)


# --------------------------------------------------------------------------- diagnostic_msgs
@dataclass
class KeyValue(IdlStruct, typename="diagnostic_msgs::msg::dds_::KeyValue_"):
    """diagnostic_msgs/msg/KeyValue."""

    key: str = ""
    value: str = ""


@dataclass
class DiagnosticStatus(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticStatus_"):
    """diagnostic_msgs/msg/DiagnosticStatus: level (OK 0, WARN 1, ERROR 2, STALE 3), name, message,
    hardware_id, values."""

    level: byte = 0
    name: str = ""
    message: str = ""
    hardware_id: str = ""
    values: sequence[KeyValue] = field(default_factory=list)


@dataclass
class DiagnosticArray(IdlStruct, typename="diagnostic_msgs::msg::dds_::DiagnosticArray_"):
    """diagnostic_msgs/msg/DiagnosticArray: header, status."""

    header: Header = field(default_factory=Header)
    status: sequence[DiagnosticStatus] = field(default_factory=list)


@dataclass
class Clock(IdlStruct, typename="rosgraph_msgs::msg::dds_::Clock_"):
    """rosgraph_msgs/msg/Clock: the simulated time (ROS 2's ``/clock``, followed with ``use_sim_time``)."""

    clock: Time = field(default_factory=Time)


#: The messages ``mpcshare run`` speaks, by ROS 2 name.
MESSAGE_TYPES: dict[str, type[IdlStruct]] = {
    "builtin_interfaces/msg/Time": Time,
    "builtin_interfaces/msg/Duration": Duration,
    "std_msgs/msg/Header": Header,
    "std_msgs/msg/MultiArrayDimension": MultiArrayDimension,
    "std_msgs/msg/MultiArrayLayout": MultiArrayLayout,
    "std_msgs/msg/Float64MultiArray": Float64MultiArray,
    "sensor_msgs/msg/JointState": JointState,
    "geometry_msgs/msg/Point": Point,
    "geometry_msgs/msg/Vector3": Vector3,
    "geometry_msgs/msg/Quaternion": Quaternion,
    "geometry_msgs/msg/Pose": Pose,
    "geometry_msgs/msg/PoseStamped": PoseStamped,
    "geometry_msgs/msg/Wrench": Wrench,
    "geometry_msgs/msg/WrenchStamped": WrenchStamped,
    "trajectory_msgs/msg/JointTrajectoryPoint": JointTrajectoryPoint,
    "trajectory_msgs/msg/JointTrajectory": JointTrajectory,
    "diagnostic_msgs/msg/KeyValue": KeyValue,
    "diagnostic_msgs/msg/DiagnosticStatus": DiagnosticStatus,
    "diagnostic_msgs/msg/DiagnosticArray": DiagnosticArray,
    "rosgraph_msgs/msg/Clock": Clock,
}
