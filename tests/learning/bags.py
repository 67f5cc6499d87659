"""Real ROS bags for the import tests, written with rosbags' own writers from analytic signals.

:func:`write_bag` writes a rosbag2 folder (MCAP or sqlite3 storage) or a ROS 1 bag
with PoseStamped (fork, knife), WrenchStamped (fork force) and JointState
(shoulder) messages at different rates, with jittered header stamps, a receive
time later than the stamp, and the knife starting late. :data:`SIGNALS` gives each
mapped channel's value as a function of time [s] since :data:`BASE_NS`, and a bound
on its second derivative (the error of linear interpolation is at most h²/8·|f''|).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

BASE_NS = 1_700_000_000_000_000_000  # header stamp of the first message [ns]


def _yaw(t):  # turns through ±π: exercises the unwrapping
    return 2.5 * t - 0.3


SIGNALS: dict[str, tuple[Callable[[np.ndarray], np.ndarray], float]] = {
    # channel: (f(t), max |f''(t)|)
    "fork_x": (lambda t: 0.10 * np.sin(2 * np.pi * 0.5 * t), 0.10 * (np.pi) ** 2),
    "fork_y": (lambda t: 0.05 * np.cos(2 * np.pi * 0.3 * t), 0.05 * (0.6 * np.pi) ** 2),
    "fork_z": (lambda t: 0.02 + 0.01 * t, 0.0),
    "fork_roll": (lambda t: 0.3 * np.sin(t), 0.3),
    "fork_pitch": (lambda t: 0.2 * np.cos(0.7 * t), 0.2 * 0.49),
    "fork_yaw": (_yaw, 0.0),
    "fork_fx": (lambda t: 2.0 * np.sin(2 * np.pi * t), 2.0 * (2 * np.pi) ** 2),
    "fork_fz": (lambda t: -1.0 + 0.5 * np.cos(3 * t), 0.5 * 9),
    "knife_x": (lambda t: 0.05 + 0.04 * np.sin(2 * np.pi * 0.8 * t), 0.04 * (1.6 * np.pi) ** 2),
    "knife_y": (lambda t: -0.03 * np.cos(2 * np.pi * 0.4 * t), 0.03 * (0.8 * np.pi) ** 2),
    "knife_z": (lambda t: 0.03 + 0.005 * np.sin(5 * t), 0.005 * 25),
    "shoulder_elevation": (lambda t: 0.2 * np.sin(1.5 * t), 0.2 * 2.25),
    "shoulder_protraction": (lambda t: -0.1 * np.cos(2 * t), 0.1 * 4),
}

MAPPING_TOML = """\
subject = "s(\\\\d+)"
[obs]
fork_x = "/fork/pose pose.position.x"
fork_y = "/fork/pose pose.position.y"
fork_z = "/fork/pose pose.position.z"
fork_roll = "/fork/pose pose.orientation@roll"
fork_pitch = "/fork/pose pose.orientation@pitch"
fork_yaw = "/fork/pose pose.orientation@yaw"
fork_fx = "/fork/wrench wrench.force.x"
fork_fz = "/fork/wrench wrench.force.z"
[act]
knife_x = "/knife/pose pose.position.x"
knife_y = "/knife/pose pose.position.y"
knife_z = "/knife/pose pose.position.z"
[voluntary]
shoulder_elevation = "/shoulder position[0]"
shoulder_protraction = "/shoulder position[1]"
"""


@dataclass(frozen=True)
class TopicPlan:
    """A topic's messages: type, rate [Hz], start [s], stamp jitter [s] (uniform ±), end [s] (None: the bag's)."""

    msgtype: str
    rate_hz: float
    start_s: float = 0.0
    jitter_s: float = 0.0
    stop_s: float | None = None


TOPICS: dict[str, TopicPlan] = {
    "/fork/pose": TopicPlan("geometry_msgs/msg/PoseStamped", 120.0, 0.0, 0.002),
    "/fork/wrench": TopicPlan("geometry_msgs/msg/WrenchStamped", 200.0, 0.0, 0.001),
    "/knife/pose": TopicPlan("geometry_msgs/msg/PoseStamped", 90.0, 0.5, 0.002),  # starts late
    "/shoulder": TopicPlan("sensor_msgs/msg/JointState", 50.0, 0.0, 0.003),
    "/camera/info": TopicPlan("std_msgs/msg/String", 5.0),  # not mapped: must be skipped
}


def rpy_quaternion(roll, pitch, yaw):
    """(x, y, z, w) of Rz(yaw)·Ry(pitch)·Rx(roll)."""
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def stamps(plan: TopicPlan, duration_s: float, rng: np.random.Generator, gap: tuple[float, float] | None = None
           ) -> np.ndarray:
    """Header stamps [s]: a regular clock from ``start_s`` with jitter (the first sample exact), minus a gap."""
    stop = duration_s if plan.stop_s is None else min(plan.stop_s, duration_s)
    n = int(np.floor((stop - plan.start_s) * plan.rate_hz))
    t = plan.start_s + np.arange(n) / plan.rate_hz
    t[1:] += rng.uniform(-plan.jitter_s, plan.jitter_s, n - 1)
    if gap is not None:
        t = t[(t < gap[0]) | (t > gap[1])]
    return t


def _message(ts, msgtype: str, t: float, frame: str, zero_stamp: bool = False):
    sec, nsec = (0, 0) if zero_stamp else divmod(BASE_NS + int(round(t * 1e9)), 1_000_000_000)
    Header = ts.types["std_msgs/msg/Header"]
    Time = ts.types["builtin_interfaces/msg/Time"]
    extra = {"seq": 0} if "seq" in Header.__dataclass_fields__ else {}  # ROS 1 headers count messages
    hdr = Header(stamp=Time(sec=sec, nanosec=nsec), frame_id=frame, **extra)
    V3 = ts.types["geometry_msgs/msg/Vector3"]
    if msgtype == "geometry_msgs/msg/PoseStamped":
        P, Q = ts.types["geometry_msgs/msg/Point"], ts.types["geometry_msgs/msg/Quaternion"]
        Pose = ts.types["geometry_msgs/msg/Pose"]
        who = "knife" if frame == "knife" else "fork"
        xyz = [float(SIGNALS[f"{who}_{a}"][0](t)) for a in "xyz"]
        if who == "fork":
            q = rpy_quaternion(*(float(SIGNALS[f"fork_{a}"][0](t)) for a in ("roll", "pitch", "yaw")))
        else:
            q = (0.0, 0.0, 0.0, 1.0)
        return ts.types[msgtype](header=hdr, pose=Pose(position=P(*xyz), orientation=Q(*q)))
    if msgtype == "geometry_msgs/msg/WrenchStamped":
        W = ts.types["geometry_msgs/msg/Wrench"]
        f = V3(x=float(SIGNALS["fork_fx"][0](t)), y=0.0, z=float(SIGNALS["fork_fz"][0](t)))
        return ts.types[msgtype](header=hdr, wrench=W(force=f, torque=V3(x=0.0, y=0.0, z=0.0)))
    if msgtype == "sensor_msgs/msg/JointState":
        pos = np.array([SIGNALS["shoulder_elevation"][0](t), SIGNALS["shoulder_protraction"][0](t), 0.0])
        return ts.types[msgtype](header=hdr, name=["elevation", "protraction", "abduction"], position=pos,
                                 velocity=np.zeros(3), effort=np.zeros(3))
    return ts.types[msgtype](data=f"frame at {t:.3f}")


def write_bag(path: str | Path, *, storage: str = "mcap", duration_s: float = 4.0, seed: int = 0,
              gap: tuple[str, float, float] | None = None, topics: dict[str, TopicPlan] | None = None,
              zero_stamps: bool = False) -> int:
    """Write a bag; returns the number of messages.

    ``storage``: ``"mcap"`` or ``"sqlite3"`` (rosbag2 folders) or ``"ros1"`` (a ``.bag`` file).
    ``gap``: (topic, from [s], to [s]) without messages. Receive times are the stamps
    plus 3–8 ms (so that a reader using them would be off). Messages are written in
    receive-time order, as a recorder would.
    """
    from rosbags.typesys import Stores, get_typestore

    rng = np.random.default_rng(seed)
    topics = TOPICS if topics is None else topics
    events = []
    for topic, plan in topics.items():
        g = (gap[1], gap[2]) if gap is not None and gap[0] == topic else None
        for t in stamps(plan, duration_s, rng, g):
            events.append((t + rng.uniform(0.003, 0.008), topic, t))
    events.sort()
    if storage == "ros1":
        from rosbags.rosbag1 import Writer as Writer1

        ts = get_typestore(Stores.ROS1_NOETIC)
        writer = Writer1(Path(path))
        serialize = ts.serialize_ros1
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        ts = get_typestore(Stores.ROS2_HUMBLE)
        plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(Path(path), version=9, storage_plugin=plugin)
        serialize = ts.serialize_cdr
    with writer:
        conns = {topic: writer.add_connection(topic, plan.msgtype, typestore=ts) for topic, plan in topics.items()}
        for recv, topic, t in events:
            msg = _message(ts, topics[topic].msgtype, t, "knife" if topic.startswith("/knife") else "fork",
                           zero_stamps)
            writer.write(conns[topic], BASE_NS + int(round(recv * 1e9)), serialize(msg, topics[topic].msgtype))
    return len(events)


#: the topics :func:`write_trial_bag` records, as the README's mapping names them
TRIAL_TOPICS = {"/mocap/fork/pose": "geometry_msgs/msg/PoseStamped",
                "/mocap/knife/pose": "geometry_msgs/msg/PoseStamped",
                "/shoulder/joint_states": "sensor_msgs/msg/JointState"}


def write_trial_bag(path: str | Path, trial, obs_names, act_names, vol_names) -> None:
    """One demonstration trial as a rosbag2 (MCAP) folder, as a motion-capture set-up would record it.

    The fork's and the knife's poses (``PoseStamped``: position, and the quaternion of the trial's
    roll/pitch/yaw, or identity where the trial has no angles) and the shoulder (``JointState``, one
    position per voluntary channel) on :data:`TRIAL_TOPICS`, every sample, stamped with the trial's time
    (from :data:`BASE_NS`) and received 4 ms later.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    columns = {"fork": dict(zip(obs_names, trial.obs.T)), "knife": dict(zip(act_names, trial.act.T))}
    shoulder = np.asarray(trial.voluntary, dtype=float)
    zero = [np.zeros(len(trial.t))] * 3

    def header(t: float, frame: str):
        sec, nsec = divmod(BASE_NS + int(round(t * 1e9)), 1_000_000_000)
        return T["std_msgs/msg/Header"](stamp=T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                                        frame_id=frame)

    def pose(t: float, who: str, i: int):
        ch = columns[who]
        xyz = [float(ch[f"{who}_{a}"][i]) for a in "xyz"]
        angles = [ch.get(f"{who}_{a}", z)[i] for a, z in zip(("roll", "pitch", "yaw"), zero)]
        return T["geometry_msgs/msg/PoseStamped"](
            header=header(t, who), pose=T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](*xyz),
                orientation=T["geometry_msgs/msg/Quaternion"](*rpy_quaternion(*(float(a) for a in angles)))))

    with Writer(Path(path), version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {topic: writer.add_connection(topic, msgtype, typestore=ts) for topic, msgtype in TRIAL_TOPICS.items()}
        for i, t in enumerate(np.asarray(trial.t, dtype=float) - float(trial.t[0])):
            messages = {"/mocap/fork/pose": pose(t, "fork", i), "/mocap/knife/pose": pose(t, "knife", i),
                        "/shoulder/joint_states": T["sensor_msgs/msg/JointState"](
                            header=header(t, "shoulder"), name=list(vol_names), position=shoulder[i],
                            velocity=np.zeros(len(vol_names)), effort=np.zeros(len(vol_names)))}
            for topic, msg in messages.items():
                writer.write(conns[topic], BASE_NS + int(round((t + 0.004) * 1e9)),
                             ts.serialize_cdr(msg, TRIAL_TOPICS[topic]))
