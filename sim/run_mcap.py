"""A closed-loop run as an MCAP file, with JSON schemas a viewer understands (Foxglove).

:func:`write_run_mcap` writes an :class:`~sim.closed_loop.Episode` (fresh, or read back with
:meth:`Episode.load`) with the ``mcap`` package; opening it needs nothing of mpcshare. Messages are JSON with
JSON-Schema schemas; log and publish times are ``start_ns`` + the episode's time [ns], as is each message's
``timestamp`` ({sec, nsec}). Topics, topic (schema, rate): content:

- ``/knife/tip``, ``/knife/reference``, ``/wearer/intent`` (``foxglove.PoseInFrame``, control): the knife
  tip, the controller's reference (steps without one left out), the wearer's intended tip; plate frame,
  orientation identity;
- ``/fork/pose`` (``foxglove.PoseInFrame``, control): the fork tip, roll/pitch/yaw as a quaternion; only with ``fork``;
- ``/tf`` (``foxglove.FrameTransform``, control): ``plate`` → ``torso``, the base pose;
- ``/arm/joint_states`` (``mpcshare.JointState``, physics rate): q [rad], v [rad/s], applied τ [N·m];
- ``/wearer/shoulder`` (``mpcshare.JointState``, control): the shoulder angles [rad];
- ``/control/arbitration`` (``mpcshare.Arbitration``, control): α, β, the mode (argmax, −1 none), novelty;
- ``/control/status`` (``mpcshare.ControllerStatus``), ``/control/timing`` (``mpcshare.Timing``: the step's
  wall time [ms]), control rate; ``/control/log`` (``foxglove.Log``): a line at each status change.

Non-finite values (α before a first command, a missing novelty) are JSON ``null``. The run's ``info`` scalars
go into the metadata record ``mpcshare.run``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from learning.atomic import atomic_open
from learning.data import Trial

from .closed_loop import FORK_CHANNELS, Episode, fork_pose_rows

__all__ = ["JOINT_NAMES", "SCHEMAS", "TOPICS", "fork_poses", "mcap_bytes_estimate", "status_log", "step_messages",
           "write_run_mcap"]

#: measured sizes (ZSTD, the default scene, 15 s of ``gate``): the control-rate topics of one
#: control step, and one physics-rate joint state message [bytes]
MCAP_BYTES_PER_CONTROL_STEP = 390
MCAP_BYTES_PER_JOINT_STATE = 125

JOINT_NAMES: tuple[str, ...] = ("joint_1", "joint_2", "joint_3")
PLATE_FRAME = "plate"


def _obj(title: str, props: dict[str, Any], description: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {"title": title, "type": "object", "properties": props}
    if description:
        out["description"] = description
    return out


_NUM = {"type": "number"}
_NUM_OR_NULL = {"type": ["number", "null"]}
_TIME = _obj("time", {"sec": {"type": "integer", "minimum": 0},
                      "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}})
_VEC3 = _obj("foxglove.Vector3", {k: _NUM for k in "xyz"})
_QUAT = _obj("foxglove.Quaternion", {k: _NUM for k in "xyzw"})
_POSE = _obj("foxglove.Pose", {"position": _VEC3, "orientation": _QUAT})
_NUMS = {"type": "array", "items": _NUM}

#: schema name → JSON schema (Foxglove's for the standard types; ours are plain objects of numbers)
SCHEMAS: dict[str, dict[str, Any]] = {
    "foxglove.PoseInFrame": _obj("foxglove.PoseInFrame", {
        "timestamp": _TIME, "frame_id": {"type": "string"}, "pose": _POSE},
        "A timestamped pose for an object or reference frame in 3D space"),
    "foxglove.FrameTransform": _obj("foxglove.FrameTransform", {
        "timestamp": _TIME, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"},
        "translation": _VEC3, "rotation": _QUAT},
        "A transform between two reference frames in 3D space"),
    "foxglove.Log": _obj("foxglove.Log", {
        "timestamp": _TIME, "level": {"type": "integer", "enum": [0, 1, 2, 3, 4, 5]},
        "message": {"type": "string"}, "name": {"type": "string"}, "file": {"type": "string"},
        "line": {"type": "integer", "minimum": 0}}, "A log message"),
    "mpcshare.JointState": _obj("mpcshare.JointState", {
        "timestamp": _TIME, "name": {"type": "array", "items": {"type": "string"}},
        "position": _NUMS, "velocity": _NUMS, "effort": _NUMS},
        "Joint positions [rad], velocities [rad/s] and efforts [N·m], as sensor_msgs/JointState"),
    "mpcshare.Arbitration": _obj("mpcshare.Arbitration", {
        "timestamp": _TIME, "alpha": _NUM_OR_NULL, "beta": _NUM_OR_NULL, "mode": {"type": "integer"},
        "novelty": _NUM_OR_NULL}, "Who leads: u = alpha * u_reactive + beta * u_voluntary; the task mode"),
    "mpcshare.ControllerStatus": _obj("mpcshare.ControllerStatus", {
        "timestamp": _TIME, "status": {"type": "string"}, "ok": {"type": "boolean"}},
        "The shared controller's status after its step"),
    "mpcshare.Timing": _obj("mpcshare.Timing", {"timestamp": _TIME, "step_time_ms": _NUM},
                            "Wall time of one controller step [ms]"),
}

#: topic → schema name
TOPICS: dict[str, str] = {
    "/knife/tip": "foxglove.PoseInFrame",
    "/knife/reference": "foxglove.PoseInFrame",
    "/wearer/intent": "foxglove.PoseInFrame",
    "/fork/pose": "foxglove.PoseInFrame",
    "/tf": "foxglove.FrameTransform",
    "/arm/joint_states": "mpcshare.JointState",
    "/wearer/shoulder": "mpcshare.JointState",
    "/control/arbitration": "mpcshare.Arbitration",
    "/control/status": "mpcshare.ControllerStatus",
    "/control/timing": "mpcshare.Timing",
    "/control/log": "foxglove.Log",
}


def _stamp(ns: int) -> dict[str, int]:
    sec, nsec = divmod(int(ns), 1_000_000_000)
    return {"sec": sec, "nsec": nsec}


def _num(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _pose(ns: int, p: np.ndarray, q: Sequence[float] = (0.0, 0.0, 0.0, 1.0)) -> dict[str, Any]:
    return {"timestamp": _stamp(ns), "frame_id": PLATE_FRAME,
            "pose": {"position": {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])},
                     "orientation": {"x": float(q[0]), "y": float(q[1]), "z": float(q[2]), "w": float(q[3])}}}


def _nanoseconds(t: np.ndarray, start_ns: int) -> list[int]:
    return [start_ns + int(round(float(x) * 1e9)) for x in np.asarray(t, dtype=float)]


def _status_ok(status: str) -> bool:
    return status == "ok"


def fork_poses(trial: Trial, obs_names: Sequence[str]) -> np.ndarray | None:
    """The fork poses the loop gives the scene (:func:`sim.closed_loop.fork_pose_rows`), (T, 6); None when
    ``obs_names`` lacks a channel they need."""
    try:
        return fork_pose_rows(trial.obs, list(obs_names))
    except ValueError:
        return None


def mcap_bytes_estimate(seconds: float, control_hz: float, joint_hz: float) -> float:
    """About how many bytes :func:`write_run_mcap` writes for ``seconds`` of a run with the joint
    states at ``joint_hz`` (the measured sizes above; within ±30 % on the project's runs)."""
    return seconds * (control_hz * MCAP_BYTES_PER_CONTROL_STEP + joint_hz * MCAP_BYTES_PER_JOINT_STATE)


def write_run_mcap(episode: Episode, path: str | Path, *, fork: np.ndarray | None = None, start_ns: int = 0,
                   joint_stride: int = 1) -> Path:
    """Write ``episode`` as an MCAP file at ``path`` (atomic; module docstring for the topics).

    Args:
        episode: a run, fresh or from :meth:`Episode.load`.
        path: the file (``.mcap``).
        fork: optional (≥ Nc, 6) fork pose per control step (x, y, z [m], roll, pitch, yaw [rad],
            plate frame): the trial's fork channels (:data:`sim.closed_loop.FORK_CHANNELS`), as
            the loop placed it (:func:`fork_poses`); the first Nc rows are used. Rows with a
            non-finite entry are left out (the loop left the fork where it was).
        start_ns: time of the episode's t = 0 [ns] (0: times count from the epoch, as a
            viewer then shows them).
        joint_stride: keep every ``joint_stride``-th physics-rate joint state (1: all).
    """
    path = Path(path)
    if path.suffix != ".mcap":
        raise ValueError(f"an MCAP file must end in .mcap, got {path.name!r}")
    if joint_stride < 1:
        raise ValueError(f"joint_stride must be >= 1, got {joint_stride}")
    fork = _checked_fork(episode, fork)
    events: list[tuple[int, int, str, dict[str, Any]]] = []  # (time, order, topic, message)

    def add(ns: int, topic: str, msg: dict[str, Any]) -> None:
        events.append((ns, len(events), topic, msg))

    _control_events(episode, fork, _nanoseconds(episode.t, start_ns), add)
    _joint_events(episode, joint_stride, start_ns, add)
    events.sort(key=lambda e: (e[0], e[1]))
    _write_events(path, events, episode.info)
    return path


def _checked_fork(episode: Episode, fork: np.ndarray | None) -> np.ndarray | None:
    """The first Nc fork poses (``fork``, else the run file's ``fork_pose``); ValueError for a wrong shape."""
    nc = len(episode.t)
    if fork is None and episode.fork_pose is not None:
        fork = episode.fork_pose  # the pose the scene showed (the run file's fork_pose)
    if fork is None:
        return None
    fork = np.asarray(fork, dtype=float)
    if fork.ndim != 2 or fork.shape[0] < nc or fork.shape[1] != len(FORK_CHANNELS):
        raise ValueError(f"fork must be ({nc}, {len(FORK_CHANNELS)}) or longer (one pose per control step, "
                         f"{', '.join(FORK_CHANNELS)}), got {fork.shape}")
    return fork[:nc]


def step_messages(ns: int, *, tip: np.ndarray, reference: np.ndarray | None, intent: np.ndarray | None,
                  fork: np.ndarray | None, fork_quat: Sequence[float] | None, base: np.ndarray,
                  base_quat: Sequence[float], shoulder_names: list[str], voluntary: np.ndarray, alpha: float,
                  beta: float, mode: int, novelty: float, status: str,
                  step_time_s: float) -> list[tuple[str, dict[str, Any]]]:
    """The control-rate messages of one step at ``ns`` as (topic, message) (module docstring); a
    reference, intent or fork that is None or not finite is left out."""
    out: list[tuple[str, dict[str, Any]]] = [("/knife/tip", _pose(ns, tip))]
    if reference is not None and np.isfinite(reference).all():
        out.append(("/knife/reference", _pose(ns, reference)))
    if intent is not None and np.isfinite(intent).all():
        out.append(("/wearer/intent", _pose(ns, intent)))
    if fork is not None and fork_quat is not None and np.isfinite(fork).all():
        out.append(("/fork/pose", _pose(ns, fork[:3], fork_quat)))
    p = base[:3, 3]
    out += [("/tf", {"timestamp": _stamp(ns), "parent_frame_id": PLATE_FRAME, "child_frame_id": "torso",
                     "translation": {"x": float(p[0]), "y": float(p[1]), "z": float(p[2])},
                     "rotation": dict(zip("xyzw", (float(c) for c in base_quat)))}),
            ("/wearer/shoulder", {"timestamp": _stamp(ns), "name": shoulder_names,
                                  "position": [_num(x) for x in voluntary], "velocity": [], "effort": []}),
            ("/control/arbitration", {"timestamp": _stamp(ns), "alpha": _num(alpha), "beta": _num(beta),
                                      "mode": int(mode), "novelty": _num(novelty)}),
            ("/control/status", {"timestamp": _stamp(ns), "status": status, "ok": _status_ok(status)}),
            ("/control/timing", {"timestamp": _stamp(ns), "step_time_ms": float(step_time_s) * 1e3})]
    return out


def status_log(ns: int, status: str) -> tuple[str, dict[str, Any]]:
    """The ``/control/log`` line of a status change at ``ns``."""
    return "/control/log", {"timestamp": _stamp(ns), "level": 2 if _status_ok(status) else 3,
                            "message": f"status: {status}", "name": "controller", "file": "", "line": 0}


def _control_events(episode: Episode, fork: np.ndarray | None, ns_c: list[int], add: Any) -> None:
    """The control-rate messages (poses, frames, shoulder, arbitration, status, timing, log) via ``add``."""
    nc = len(episode.t)
    base = np.asarray(episode.base_pose, dtype=float)
    base_q = Rotation.from_matrix(base[:, :3, :3]).as_quat() if nc else np.zeros((0, 4))
    fork_q = None
    if fork is not None:
        ok_rows = np.isfinite(fork).all(axis=1)
        fork_q = np.zeros((nc, 4))
        if ok_rows.any():
            fork_q[ok_rows] = Rotation.from_euler("ZYX", fork[ok_rows][:, [5, 4, 3]]).as_quat()
    shoulder_names = episode.shoulder_names
    previous = None
    for k, ns in enumerate(ns_c):
        status = str(episode.status[k])
        for topic, msg in step_messages(
                ns, tip=episode.tip[k], reference=episode.tip_reference[k], intent=episode.tip_intent[k],
                fork=None if fork is None else fork[k], fork_quat=None if fork_q is None else fork_q[k],
                base=base[k], base_quat=base_q[k], shoulder_names=shoulder_names, voluntary=episode.voluntary[k],
                alpha=episode.alpha[k], beta=episode.beta[k], mode=episode.mode[k], novelty=episode.novelty[k],
                status=status, step_time_s=episode.step_time[k]):
            add(ns, topic, msg)
        if status != previous:
            add(ns, *status_log(ns, status))
            previous = status


def _joint_events(episode: Episode, joint_stride: int, start_ns: int, add: Any) -> None:
    """Every ``joint_stride``-th physics-rate joint state as ``/arm/joint_states`` via ``add``."""
    keep = slice(0, None, joint_stride)
    t_phys = np.asarray(episode.t_physics, dtype=float)[keep]
    n_joints = np.asarray(episode.q).shape[1] if np.ndim(episode.q) == 2 else len(JOINT_NAMES)
    joint_names = list(JOINT_NAMES) if n_joints == len(JOINT_NAMES) else [f"joint_{i + 1}" for i in range(n_joints)]
    for t, q, v, tau in zip(t_phys.tolist(), np.asarray(episode.q, dtype=float)[keep].tolist(),
                            np.asarray(episode.v, dtype=float)[keep].tolist(),
                            np.asarray(episode.tau, dtype=float)[keep].tolist()):
        ns = start_ns + int(round(t * 1e9))
        add(ns, "/arm/joint_states", {"timestamp": _stamp(ns), "name": joint_names, "position": q,
                                      "velocity": v, "effort": tau})


def _write_events(path: Path, events: list[tuple[int, int, str, dict[str, Any]]], info: dict[str, Any]) -> None:
    """The sorted ``events`` as JSON messages on their topics (schemas registered once), atomically."""
    from mcap.writer import CompressionType, Writer

    with atomic_open(path, "wb") as fh:
        writer = Writer(fh, compression=CompressionType.ZSTD)
        writer.start(profile="", library="mpcshare")
        schema_ids = {name: writer.register_schema(name=name, encoding="jsonschema",
                                                   data=json.dumps(schema).encode())
                      for name, schema in SCHEMAS.items()}
        used = dict.fromkeys(e[2] for e in events)
        channel_ids = {topic: writer.register_channel(topic=topic, message_encoding="json",
                                                      schema_id=schema_ids[TOPICS[topic]])
                       for topic in TOPICS if topic in used}
        encode = json.JSONEncoder(allow_nan=False, separators=(",", ":")).encode
        for ns, _, topic, msg in events:
            writer.add_message(channel_ids[topic], log_time=ns, data=encode(msg).encode(), publish_time=ns)
        writer.add_metadata("mpcshare.run", {str(k): "" if v is None else str(v) for k, v in info.items()})
        writer.finish()
