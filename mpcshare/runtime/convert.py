"""Messages ↔ the controller's arrays for ``mpcshare run``.

Inputs: a channel's value is its field path's number in the input's latest message (a quaternion's
roll, pitch or yaw as ``mpcshare import``: ZYX, tf2's getRPY); NaN when the path does not exist in
that message (an index past the end) or the value is not finite. The arm's q [rad], v [rad/s] are
read by joint name. Outputs: the joint command as a one-point ``JointTrajectory`` (positions
q_cmd, velocities v_cmd, accelerations a_cmd, reached ``time_from_start`` = one period after the
stamp) or a ``Float64MultiArray`` (q_cmd, v_cmd or τ per the interface), and the status as a
``DiagnosticArray`` (:func:`status_message`; :func:`status_cdr`: its bytes, serialised by rosbags).
"""

from __future__ import annotations

import functools
import math
from typing import Any, Sequence

import numpy as np

from learning.data.mapping import FieldPath, quaternion_angles
from mpcshare.runtime.messages import (
    DiagnosticArray,
    DiagnosticStatus,
    Duration,
    Float64MultiArray,
    Header,
    JointState,
    JointTrajectory,
    JointTrajectoryPoint,
    KeyValue,
    MultiArrayDimension,
    MultiArrayLayout,
    Pose,
    Time,
)

__all__ = ["OK", "WARN", "ERROR", "STALE", "command_message", "controller_values", "joint_state", "pose_matrix",
           "read_path", "status_cdr", "status_message", "status_text"]

#: diagnostic_msgs/DiagnosticStatus levels.
OK, WARN, ERROR, STALE = 0, 1, 2, 3


def read_path(message: Any, path: FieldPath) -> float:
    """The number at ``path`` in ``message`` (module docstring); NaN when absent or not finite."""
    x = message
    try:
        for step in path.steps:
            x = getattr(x, step) if isinstance(step, str) else x[step]
        if path.angle is not None:
            v = float(quaternion_angles(np.array([[x.x, x.y, x.z, x.w]], dtype=float), path.angle)[0])
        else:
            v = float(x)
    except (AttributeError, IndexError, TypeError, ValueError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def joint_state(message: JointState, joints: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """(q, v) of ``joints`` from a JointState by name; NaN for a joint or a value the message lacks."""
    index = {n: i for i, n in enumerate(message.name)}
    q, v = np.full(len(joints), np.nan), np.full(len(joints), np.nan)
    for k, j in enumerate(joints):
        i = index.get(j)
        if i is not None:
            if i < len(message.position):
                q[k] = message.position[i]
            if i < len(message.velocity):
                v[k] = message.velocity[i]
    return q, v


def pose_matrix(pose: Pose) -> np.ndarray:
    """The 4×4 homogeneous transform of a Pose (quaternion normalised; NaN for a zero one)."""
    p, o = pose.position, pose.orientation
    x, y, z, w = o.x, o.y, o.z, o.w
    n = math.sqrt(x * x + y * y + z * z + w * w)
    T = np.full((4, 4), np.nan)
    if n > 0 and math.isfinite(n):
        x, y, z, w = x / n, y / n, z / n, w / n
        T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    T[:3, 3] = (p.x, p.y, p.z)
    T[3] = (0.0, 0.0, 0.0, 1.0)
    return T


def command_message(kind: str, interface: str, joints: Sequence[str], stamp: Time, period_s: float,
                    q: np.ndarray, v: np.ndarray, a: np.ndarray,
                    tau: np.ndarray) -> JointTrajectory | Float64MultiArray:
    """The joint command of one period (module docstring); ``kind``: a ROS message name of
    :data:`mpcshare.runtime.config.COMMAND_TYPES`."""
    if kind == "trajectory_msgs/msg/JointTrajectory":
        ns = int(round(period_s * 1e9))
        point = JointTrajectoryPoint(positions=[float(x) for x in q], velocities=[float(x) for x in v],
                                     accelerations=[float(x) for x in a],
                                     time_from_start=Duration(ns // 1_000_000_000, ns % 1_000_000_000))
        return JointTrajectory(Header(stamp, ""), list(joints), [point])
    data = {"position": q, "velocity": v, "effort": tau}[interface]
    n = len(joints)
    return Float64MultiArray(MultiArrayLayout([MultiArrayDimension("joints", n, n)], 0), [float(x) for x in data])


def controller_values(cmd: Any, keepout: Any = None) -> dict[str, object]:
    """The status's values of a ``ControlCommand``: α, β, who leads (robot when α ≥ 0.5), the most probable
    mode (-1: none), its probabilities, novelty, the fault reasons, the step's time [s], the tip reference
    [m]; with the controller's ``keepout``, the clearance to each body zone and the least of them [m]."""
    alpha = float(cmd.alpha)
    proba = np.asarray(cmd.mode_proba, dtype=float)
    out: dict[str, object] = {"alpha": alpha, "beta": float(cmd.beta),
                              "leader": "robot" if alpha >= 0.5 else "wearer",
                              "mode": int(np.argmax(proba)) if proba.size and np.isfinite(proba).all() else -1,
                              "mode_proba": proba, "novelty": float(cmd.novelty),
                              "reasons": " | ".join(cmd.reasons),
                              "step_s": float(cmd.timings.get("total", math.nan)),
                              "tip_reference": np.asarray(getattr(cmd, "tip_reference", (math.nan,) * 3),
                                                          dtype=float)}
    if keepout is not None and keepout.limit.clearances:
        dist = [float(c.distance) for c in keepout.limit.clearances]
        out["clearance_m"] = min(dist)
        out.update({f"clearance_{z.name}_m": d for z, d in zip(keepout.limit.zones, dist)})
    return out


def status_text(x: object) -> str:
    """A status value as its key/value string: floats with 6 significant digits, sequences comma-joined."""
    if isinstance(x, float):
        return f"{x:.6g}"
    if isinstance(x, np.ndarray):
        x = x.tolist()
    if isinstance(x, (list, tuple)):
        return ",".join(f"{e:.6g}" if isinstance(e, (float, np.floating)) else str(e) for e in x)
    return str(x)


def status_message(stamp: Time, name: str, hardware_id: str, level: int, message: str,
                   values: dict[str, object]) -> DiagnosticArray:
    """One DiagnosticStatus in a DiagnosticArray; ``values`` as key/value strings (:func:`status_text`)."""
    kv = [KeyValue(k, status_text(v)) for k, v in values.items()]
    return DiagnosticArray(Header(stamp, ""), [DiagnosticStatus(level, name, message, hardware_id, kv)])


@functools.cache
def _rosbags_status_types() -> tuple[Any, ...]:
    """rosbags' ROS 2 Humble typestore and its DiagnosticArray, DiagnosticStatus, KeyValue, Header, Time."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    return store, *(store.types[t] for t in (
        "diagnostic_msgs/msg/DiagnosticArray", "diagnostic_msgs/msg/DiagnosticStatus", "diagnostic_msgs/msg/KeyValue",
        "std_msgs/msg/Header", "builtin_interfaces/msg/Time"))


def status_cdr(stamp: Time, name: str, hardware_id: str, level: int, message: str,
               values: dict[str, object]) -> bytes:
    """:func:`status_message`'s XCDR1 bytes (encapsulation header included), serialised by rosbags' ROS 2 CDR
    serialiser (generated per type; the same bytes as Cyclone's, a fraction of its CPU: docs/results.md)."""
    store, array, status, key_value, header, time_ = _rosbags_status_types()
    msg = array(header(time_(stamp.sec, stamp.nanosec), ""), [status(
        level, name, message, hardware_id, [key_value(k, status_text(v)) for k, v in values.items()])])
    return bytes(store.serialize_cdr(msg, "diagnostic_msgs/msg/DiagnosticArray"))
