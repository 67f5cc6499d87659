"""The controller in another process, behind the controller's ``step`` interface: the robot stand-in's side.

:class:`RemoteController` is what ``mpcshare sim --serve`` gives :func:`sim.closed_loop.run_episode`: each
``step(t, obs, voluntary, q, v, base_pose)`` publishes the configuration's inputs (the arm's joint states by
name; the others built from the ``[obs]`` and ``[voluntary]`` field paths, a quaternion from its ZYX angles; the
torso's pose if configured) and returns the joint command ``mpcshare run`` sends back, with α, β, the mode,
novelty, the tip reference and the status read from its status message. Two clocks:

- **sim time** (default): inputs stamped t, then ``/clock`` at t (``run --sim-time`` ticks on it); the step
  waits for the command stamped t (``first_timeout_s`` before the first command, ``timeout_s`` after a step that
  got one, ``lost_timeout_s`` after one that did not): lockstep, the inputs of one process at the same times;
- **wall clock**: sleep to the episode's start + t, stamp with the wall clock, take the newest command that
  arrives within 0.8 periods.

Each command form becomes the runner's segment over the period (:mod:`mpcshare.runtime.stand_in_command`); a
``Float64MultiArray`` has no header, so its status (same stamp, published after it) says whether a command went
out (``alpha`` or ``stop_command = 1``). No command for a step: ``None`` (the runner holds the arm, as
ros2_control's trajectory controller after ``cmd_timeout``). An :class:`Outage` silences an input over a time
window: ``drop`` stops writing, ``restart`` deletes its DDS writer at the start and creates a new one at the end.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from scipy.spatial.transform import Rotation

from learning.data.mapping import FieldPath
from mpcshare.runtime.config import RunConfig, RunConfigError
from mpcshare.runtime.loop import CLOCK_TOPIC
from mpcshare.runtime.messages import (
    MESSAGE_TYPES,
    Clock,
    DiagnosticArray,
    Header,
    JointState,
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Time,
    ros_time,
    seconds,
)
from mpcshare.runtime.stand_in_command import RemoteCommand, command_segment, remote_command
from mpcshare.runtime.transport import QosSettings, Transport, Writer

__all__ = ["Outage", "RemoteCommand", "RemoteController", "parse_outage"]


@dataclass(frozen=True)
class Outage:
    """Input ``input`` silent over [start, end) [s] of each episode; ``restart``: its writer deleted, then new."""

    input: str
    start: float
    end: float
    restart: bool = False


def parse_outage(text: str, restart: bool = False) -> Outage:
    """``INPUT:START:END`` (seconds) → :class:`Outage`; ValueError naming what is wrong."""
    parts = text.split(":")
    if len(parts) != 3:
        raise ValueError(f"{text!r}: expected INPUT:START:END (e.g. fork:5:7)")
    try:
        start, end = float(parts[1]), float(parts[2])
    except ValueError:
        raise ValueError(f"{text!r}: START and END must be numbers of seconds") from None
    if not (math.isfinite(start) and math.isfinite(end) and 0.0 <= start < end):
        raise ValueError(f"{text!r}: need 0 <= START < END")
    return Outage(parts[0], start, end, restart)


def _set(message: Any, path: FieldPath, value: float) -> None:
    """Set the number at ``path`` (attributes and list indexes; a list grows with zeros) in ``message``."""
    x = message
    steps = path.steps
    for i, step in enumerate(steps):
        last = i == len(steps) - 1
        if isinstance(step, int):
            while len(x) <= step:
                x.append(0.0)
            if last:
                x[step] = float(value)
            else:
                x = x[step]
        elif last:
            setattr(x, step, float(value))
        else:
            x = getattr(x, step)


class _InputWriter:
    """One input's writer and how its message is built from the step's values."""

    def __init__(self, transport: Transport, config: RunConfig, name: str,
                 channels: Sequence[tuple[str, str, FieldPath]]) -> None:
        self.transport, self.name, self.spec = transport, name, config.inputs[name]
        self.channels = list(channels)  # (kind, channel, path)
        self.writer: Writer | None = None
        self.open()

    def open(self) -> None:
        self.writer = self.transport.writer(self.spec.topic, MESSAGE_TYPES[self.spec.type],
                                            QosSettings("reliable", self.spec.qos.depth))

    def close(self) -> None:
        if self.writer is not None:
            self.writer.close()
        self.writer = None

    def message(self, stamp: Time, values: dict[tuple[str, str], float]) -> Any:
        msg = MESSAGE_TYPES[self.spec.type](header=Header(stamp, self.spec.frame))
        angles: dict[tuple, dict[str, float]] = {}
        for kind, channel, path in self.channels:
            v = values[(kind, channel)]
            if path.angle is not None:
                angles.setdefault(tuple(path.steps), {})[path.angle] = v
            else:
                _set(msg, path, v)
        for steps, rpy in angles.items():
            q = Rotation.from_euler("ZYX", [rpy.get("yaw", 0.0), rpy.get("pitch", 0.0), rpy.get("roll", 0.0)])
            x, y, z, w = (float(c) for c in q.as_quat())
            target = msg
            for step in steps:
                target = getattr(target, step) if isinstance(step, str) else target[step]
            target.x, target.y, target.z, target.w = x, y, z, w
        if isinstance(msg, JointState) and not msg.name:
            msg.name = [f"{self.name}_{i}" for i in range(len(msg.position))]
        return msg


class RemoteController:
    """The controller's ``step`` interface, answered by ``mpcshare run`` over ``transport`` (module docstring).

    ``obs_names``, ``vol_names``: the order of the runner's obs and voluntary vectors; ``outages``: inputs
    silenced over windows; ``sim_time``: publish ``/clock`` and wait for each step's command (lockstep).
    ``missing`` counts the steps without a command. ``live``: a :class:`mpcshare.runtime.live.LiveView` given
    every step (its failure ends it, named in ``live_error``); :meth:`close` closes it.
    """

    def __init__(self, config: RunConfig, transport: Transport, *, obs_names: Sequence[str],
                 vol_names: Sequence[str], sim_time: bool = True, outages: Sequence[Outage] = (),
                 first_timeout_s: float = 60.0, timeout_s: float = 2.0, lost_timeout_s: float = 0.02,
                 live: Any = None) -> None:
        names = {"obs": list(obs_names), "voluntary": list(vol_names)}
        by_input: dict[str, list[tuple[str, str, FieldPath]]] = {}
        for c in config.channels:
            if c.name not in names[c.kind]:
                raise RunConfigError(f"{config.source}, [{c.kind}] {c.name}: the simulator has no such channel "
                                     f"(its {c.kind} channels: {', '.join(names[c.kind])})")
            by_input.setdefault(c.input, []).append((c.kind, c.name, c.path))
        known = set(config.inputs)
        for o in outages:
            if o.input not in known:
                raise RunConfigError(f"{config.source}: no input {o.input!r} to silence (inputs: {', '.join(known)})")
        self.config, self.transport, self.sim_time = config, transport, sim_time
        self.obs_index = {n: i for i, n in enumerate(obs_names)}
        self.vol_index = {n: i for i, n in enumerate(vol_names)}
        self.outages = list(outages)
        self.first_timeout_s, self.timeout_s, self.lost_timeout_s = first_timeout_s, timeout_s, lost_timeout_s
        self.arm = _InputWriter(transport, config, "arm", [])
        self.torso = _InputWriter(transport, config, "torso", []) if "torso" in config.inputs else None
        self.inputs = [_InputWriter(transport, config, n, ch) for n, ch in by_input.items()]
        self.clock = transport.writer(CLOCK_TOPIC, Clock, QosSettings("reliable", 64))
        self.trajectory = config.command.type == "trajectory_msgs/msg/JointTrajectory"
        self.interface = "trajectory" if self.trajectory else config.command.interface
        self.commands = transport.reader(config.command.topic, MESSAGE_TYPES[config.command.type],
                                         QosSettings("reliable", 64))
        self._dynamics: tuple[Any, Any] | None = None  # the arm's (pinocchio model, data) for an effort command
        self.status = transport.reader(config.status_topic, DiagnosticArray, QosSettings("reliable", 64))
        self.missing = 0
        self._got_any, self._last_ok = False, False
        self._last: Any = None  # the last command used, and (wall clock) its arrival [s, monotonic]
        self._last_arrival = -math.inf
        self._newest_status: dict[str, str] = {}
        self._t0: float | None = None
        self._statuses: dict[str, dict[str, str]] = {}
        self.live, self.live_error = live, None

    def bind(self, robot: Any) -> None:
        """The simulated arm (a ``robot.description.RobotDescription``): its joints must be the configuration's,
        in order; with an effort command its rigid-body model turns τ into the acceleration. RunConfigError
        naming the joints otherwise."""
        if list(robot.joint_names) != list(self.config.arm.joints):
            raise RunConfigError(f"{self.config.source}, [inputs.arm] joints: {list(self.config.arm.joints)} are "
                                 f"not the simulated arm's {list(robot.joint_names)}")
        if self.interface == "effort":
            self._dynamics = (robot.model, robot.model.createData())

    def wait_for_run(self, timeout_s: float) -> bool:
        """Wait up to ``timeout_s`` [s] until ``mpcshare run`` listens (reads the arm, with sim time the clock)
        and publishes the command; True when it does."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            if self.arm.writer is not None and self.arm.writer.matched > 0 and self.commands.matched and \
                    (not self.sim_time or self.clock.matched):
                return True
            time.sleep(0.02)
        return False

    def reset(self) -> None:
        """A new episode: its time starts again (with sim time, ``run`` resets when the clock jumps back)."""
        self._t0, self._last, self._last_ok = None, None, self._got_any

    # ------------------------------------------------------------------ publishing
    def _live(self, w: _InputWriter, t: float) -> Writer | None:
        """``w``'s writer at ``t``, None while an outage silences it (a restart: deleted, then created anew)."""
        windows = [o for o in self.outages if o.input == w.name and o.start <= t < o.end]
        if any(o.restart for o in windows):
            w.close()
        elif w.writer is None:
            w.open()
            writer = w.writer
            end = time.monotonic() + 1.0  # a new writer: let discovery match it before its first message
            while writer is not None and not writer.matched and time.monotonic() < end:
                time.sleep(0.002)
        return None if windows else w.writer

    def _publish(self, t: float, stamp: Time, obs: np.ndarray, voluntary: np.ndarray, q: np.ndarray,
                 v: np.ndarray, base_pose: np.ndarray | None) -> None:
        values: dict[tuple[str, str], float] = {}
        for (kind, index), row in (("obs", self.obs_index), obs), (("voluntary", self.vol_index), voluntary):
            values.update({(kind, n): float(row[i]) for n, i in index.items()})
        if (writer := self._live(self.arm, t)) is not None:
            writer.write(JointState(Header(stamp, self.arm.spec.frame), list(self.config.arm.joints),
                                    [float(x) for x in q], [float(x) for x in v], []))
        for w in self.inputs:
            if (writer := self._live(w, t)) is not None:
                writer.write(w.message(stamp, values))
        if self.torso is not None and base_pose is not None and (writer := self._live(self.torso, t)) is not None:
            T = np.asarray(base_pose, dtype=float)
            x, y, z, w_ = (float(c) for c in Rotation.from_matrix(T[:3, :3]).as_quat())
            writer.write(PoseStamped(Header(stamp, self.torso.spec.frame),
                                     Pose(Point(*(float(c) for c in T[:3, 3])), Quaternion(x, y, z, w_))))

    # ------------------------------------------------------------------ the step
    def _take_statuses(self) -> None:
        for msg in self.status.take():
            if msg.status:
                values = {kv.key: kv.value for kv in msg.status[0].values}
                if "stamp" in values:
                    self._statuses[values["stamp"]] = values
                    self._newest_status = values
        if len(self._statuses) > 256:
            for key in list(self._statuses)[:-64]:
                del self._statuses[key]

    def _segment(self, msg: Any, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, ...] | None:
        return command_segment(msg, self.interface, self.config.arm.joints, self.config.period_s, q, v,
                               self._dynamics, self.config.command.driver_compensates_gravity)

    def _command(self, msg: Any, values: dict[str, str], q: np.ndarray, v: np.ndarray) -> RemoteCommand | None:
        segment = self._segment(msg, q, v)
        return None if segment is None else remote_command(segment, values)

    def step(self, t: float, obs: Any, voluntary: Any, q: Any, v: Any, base_pose: Any = None) -> RemoteCommand | None:
        """Publish the inputs at ``t`` [s] and return ``run``'s command for them (None: none came)."""
        t0 = time.perf_counter()
        cmd = self._step(t, obs, voluntary, q, v, base_pose)
        if self.live is not None:
            obs_row = np.asarray(obs, dtype=float).reshape(-1)
            try:
                self.live.step(int(round((t if self.sim_time else time.time()) * 1e9)), q=q, v=v, base=base_pose,
                               obs={n: float(obs_row[i]) for n, i in self.obs_index.items()}, voluntary=voluntary,
                               command=cmd, status="invalid_command" if cmd is None else cmd.status,
                               step_time_s=time.perf_counter() - t0)
            except Exception as exc:  # noqa: BLE001  (the view must never stop the loop: it ends, and says why)
                self.live_error, self.live = f"{type(exc).__name__}: {exc}", None
        return cmd

    def close(self) -> None:
        """Close the live view, if any."""
        if self.live is not None:
            self.live.close()
            self.live = None

    def _step(self, t: float, obs: Any, voluntary: Any, q: Any, v: Any, base_pose: Any) -> RemoteCommand | None:
        obs, voluntary = np.asarray(obs, dtype=float).reshape(-1), np.asarray(voluntary, dtype=float).reshape(-1)
        q, v = np.asarray(q, dtype=float).reshape(-1), np.asarray(v, dtype=float).reshape(-1)
        if self.sim_time:
            stamp = ros_time(t + 1e-10)  # the nearest nanosecond below t + 0.1 ns: k·T exactly
            self.commands.take()  # in lockstep nothing before this clock is this step's
            self._publish(t, stamp, obs, voluntary, q, v, base_pose)
            self.clock.write(Clock(stamp))
            wait = self.timeout_s if self._last_ok else self.first_timeout_s if not self._got_any else \
                self.lost_timeout_s
            if self.trajectory:
                msg = self._wait(time.monotonic() + wait, lambda c: c.header.stamp == stamp)
            else:
                msg = self._untimed_command(time.monotonic() + wait, _key(stamp))
        else:
            if self._t0 is None:
                self._t0 = time.monotonic() - t
            while (pause := self._t0 + t - time.monotonic()) > 0:
                time.sleep(min(pause, 0.002))
            stamp = ros_time(time.time())
            self._publish(t, stamp, obs, voluntary, q, v, base_pose)
            if self.trajectory:
                after = -math.inf if self._last is None else seconds(self._last.header.stamp)
                msg = self._wait(self._t0 + t + 0.8 * self.config.period_s,
                                 lambda c: seconds(c.header.stamp) > after)
            else:
                msg = self._wait(self._t0 + t + 0.8 * self.config.period_s, lambda c: True)
            msg = msg or self._fresh_last(stamp)
        self._last_ok = msg is not None
        if msg is None:
            self.missing += 1
            return None
        if msg is not self._last:
            self._last_arrival = time.monotonic()
        self._got_any, self._last = True, msg
        if not self.trajectory:
            self._take_statuses()
            values = self._statuses.get(_key(stamp), {}) if self.sim_time else self._newest_status
            return self._command(msg, values, q, v)
        key = _key(msg.header.stamp)
        end = time.monotonic() + (0.05 if self.sim_time else 0.2 * self.config.period_s)
        while key not in self._statuses and time.monotonic() < end:  # the status follows its command
            self.status.wait(0.002)
            self._take_statuses()
        return self._command(msg, self._statuses.get(key, {}), q, v)

    def _untimed_command(self, end: float, key: str) -> Any:
        """Lockstep, a command without a header: this step's status (stamp ``key``, up to ``end``); the newest
        command received when the status says one went out (up to 0.05 s more), else None."""
        while key not in self._statuses:
            self._take_statuses()
            if key in self._statuses:
                break
            remaining = end - time.monotonic()
            if remaining <= 0:
                return None
            self.status.wait(min(remaining, 0.01))
        values = self._statuses[key]
        if "alpha" not in values and values.get("stop_command") != "1":
            return None
        return self._wait(time.monotonic() + 0.05, lambda c: True)

    def _fresh_last(self, stamp: Time) -> Any:
        """The last command while its point is not yet two periods old (wall clock; by its stamp, or its arrival
        for a command without a header)."""
        last, T = self._last, self.config.period_s
        if last is None:
            return None
        if self.trajectory:
            return None if seconds(stamp) - seconds(last.header.stamp) > 2 * T else last
        return None if time.monotonic() - self._last_arrival > 2 * T else last

    def _wait(self, end: float, wanted: Any) -> Any:
        """The newest command satisfying ``wanted`` received up to ``end`` [s, monotonic]; None: none."""
        found = None
        while True:
            for c in self.commands.take():
                if wanted(c):
                    found = c
            if found is not None:
                return found
            remaining = end - time.monotonic()
            if remaining <= 0:
                return None
            self.commands.wait(min(remaining, 0.01))


def _key(stamp: Time) -> str:
    """A stamp as the status's ``stamp`` value (``sec.nanosec``)."""
    return f"{stamp.sec}.{stamp.nanosec:09d}"
