"""The live view: the run file's MCAP channels streamed to Foxglove while ``run`` or the stand-in runs, and recorded.

:class:`LiveView` opens a Foxglove WebSocket server (the ``foxglove-sdk`` package, the optional extra
``live``) on 127.0.0.1 only (port 8765 by default; in Foxglove: Open connection, ``ws://127.0.0.1:8765``)
and an MCAP file, and logs each control step on the topics and JSON schemas of :mod:`sim.run_mcap` (the
run files' MCAP, so one layout serves both) to both sinks: the knife tip (forward kinematics of the
measured joints, plate frame), its reference, the fork, the torso (``/tf``), the arm's joint states (at
the control rate), the shoulder, α/β/mode/novelty, the status (and a log line when it changes) and the
step time. Message times are the step's time [ns] (sim time, or the wall clock).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from mpcshare.arms import rest_base_pose
from robot.description import RobotDescription
from sim.closed_loop import FORK_CHANNELS
from sim.run_mcap import SCHEMAS, TOPICS, status_log, step_messages

__all__ = ["DEFAULT_LIVE_PORT", "LiveView"]

#: Foxglove's default WebSocket port.
DEFAULT_LIVE_PORT = 8765


class LiveView:
    """Streams and records the control steps (module docstring) of the arm ``robot`` (joint order of ``q``);
    ``shoulder_names``: the voluntary channels' names. RuntimeError when ``foxglove-sdk`` is missing or the
    port cannot be opened. :meth:`close` stops the server and finishes the file."""

    def __init__(self, mcap_path: str | Path, robot: RobotDescription, shoulder_names: Sequence[str], *,
                 port: int = DEFAULT_LIVE_PORT, name: str = "mpcshare") -> None:
        try:
            import foxglove
        except ImportError:
            raise RuntimeError("the live view needs the foxglove-sdk package (pip install 'mpcshare[live]')") from None
        import pinocchio as pin

        self._pin, self.robot = pin, robot
        self._data = robot.model.createData()
        self.shoulder_names = list(shoulder_names)
        self.joint_names = list(robot.joint_names)
        self.path = Path(mcap_path)
        self._ctx = foxglove.Context()
        try:
            self.server = foxglove.start_server(name=name, host="127.0.0.1", port=port, context=self._ctx)
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own error types for a busy port
            raise RuntimeError(f"the live view cannot serve on 127.0.0.1:{port} ({exc})") from None
        self.writer = foxglove.open_mcap(self.path, allow_overwrite=True, context=self._ctx)
        self.channels = {topic: foxglove.Channel(topic, message_encoding="json", context=self._ctx,
                                                 schema=foxglove.Schema(name=schema, encoding="jsonschema",
                                                                        data=json.dumps(SCHEMAS[schema]).encode()))
                         for topic, schema in TOPICS.items()}
        self._status: str | None = None
        self.steps = 0

    @property
    def port(self) -> int:
        """The server's port (the one given, or the one chosen for 0)."""
        return int(self.server.port)

    def _tip(self, q: np.ndarray, base: np.ndarray) -> np.ndarray:
        """The tip in the plate frame: ``base`` (T_plate_torso) · the forward kinematics of ``q`` (torso frame)."""
        if not np.isfinite(q).all():
            return np.full(3, np.nan)
        self._pin.framesForwardKinematics(self.robot.model, self._data, q)
        p = self._data.oMf[self.robot.tip_frame_id].translation
        return base[:3, :3] @ p + base[:3, 3]

    def step(self, ns: int, *, q: np.ndarray, v: np.ndarray, base: np.ndarray | None, obs: dict[str, float],
             voluntary: np.ndarray, command: Any, status: str, step_time_s: float) -> None:
        """Log one control step at ``ns`` [ns]: measured ``q``, ``v`` [rad, rad/s], ``base`` (T_plate_torso;
        None or not finite: the torso at rest, :func:`mpcshare.arms.rest_base_pose`), ``obs`` by channel name
        (the fork's channels used), ``voluntary``, ``command`` (anything with ``tip_reference``, ``alpha``,
        ``beta``, ``mode_proba``, ``novelty``; None: no command)."""
        q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
        base = rest_base_pose() if base is None or not np.isfinite(base).all() else np.asarray(base, dtype=float)
        fork = np.array([obs.get(c, math.nan) for c in FORK_CHANNELS], dtype=float)
        fork_q = Rotation.from_euler("ZYX", fork[[5, 4, 3]]).as_quat() if np.isfinite(fork).all() else None
        proba = np.asarray(getattr(command, "mode_proba", ()), dtype=float).reshape(-1)
        mode = int(np.argmax(proba)) if proba.size and np.isfinite(proba).all() else -1
        tip = self._tip(q, base)
        messages = step_messages(
            ns, tip=tip, reference=getattr(command, "tip_reference", None), intent=None, fork=fork,
            fork_quat=fork_q, base=base, base_quat=Rotation.from_matrix(base[:3, :3]).as_quat(),
            shoulder_names=self.shoulder_names, voluntary=np.asarray(voluntary, dtype=float),
            alpha=float(getattr(command, "alpha", math.nan)), beta=float(getattr(command, "beta", math.nan)),
            mode=mode, novelty=float(getattr(command, "novelty", math.nan)), status=status, step_time_s=step_time_s)
        if not np.isfinite(tip).all():  # no measured joints: no tip
            messages = [m for m in messages if m[0] != "/knife/tip"]
        sec, nsec = divmod(int(ns), 1_000_000_000)
        messages.append(("/arm/joint_states", {"timestamp": {"sec": sec, "nsec": nsec}, "name": self.joint_names,
                                               "position": [float(x) if math.isfinite(x) else None for x in q],
                                               "velocity": [float(x) if math.isfinite(x) else None for x in v],
                                               "effort": []}))
        if status != self._status:
            messages.append(status_log(ns, status))
            self._status = status
        for topic, msg in messages:
            self.channels[topic].log(msg, log_time=int(ns))
        self.steps += 1

    def close(self) -> None:
        """Stop the server and finish the MCAP file."""
        self.server.stop()
        self.writer.close()
