"""The loop of ``mpcshare run``: the shared controller at the control rate over ROS 2 topics.

Per tick k (t_k = k·T on the monotonic clock from the start, T = 1/rate_hz; ``sim_time``: each new ``/clock``
message's time, a clock that jumps back resets the controller, the watchdog and the latest inputs):
1. take every new message (arrivals feed the :class:`~mpcshare.runtime.watchdog.Watchdog`; a wrong frame_id is
   dropped, counted); stale inputs withheld (NaN: the controller's fault path), named in the status;
2. ``SharedController.step(t_k, obs, voluntary, q, v, base_pose)``; publish the command (stamped with ROS time,
   or the clock's with ``sim_time``) and the status;
3. collect the garbage due if the slack allows (:mod:`~mpcshare.runtime.gc_policy`), sleep to t_{k+1} (the last
   0.2 ms spun); a tick already past is skipped (``late_ticks``). ``tick = "arm"``: tick k+1 runs on the first
   arm joint state after t_{k+1} − T/2 (at t_{k+1} + T/2 at the latest) and the schedule moves to it.
Phases and collections go to ``RunLoop.profile`` (:class:`~mpcshare.runtime.tick_profile.TickProfile`).
**Protective stop** (a required input older than ``stop_after_s``, a non-finite command, the end of the run):
no controller call; each tick publishes ``protective_stop`` and the hold at q_stop (measured at the first stop):
a trajectory point at rest; a Float64MultiArray of q_stop, zero velocities, or efforts braking to rest at q_stop,
gravity included (:mod:`robot.holding_torque`, the controller's ``robot``; g(q) alone while the arm's state is
stale, zeros without a model: status ``stop_torque``). Efforts are total joint torques; with
``driver_compensates_gravity`` g(q) is subtracted from each. A silent-input stop ends once every required input
was fresh for ``resume_after_s`` (controller reset); a non-finite command latches. Before the arm's first joint
state only the status goes out. :meth:`RunLoop.shutdown` publishes the stop again, ≤ 0.2 s for acknowledgement.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from mpcshare.runtime.config import RunConfig
from mpcshare.runtime.convert import (
    ERROR,
    OK,
    STALE,
    WARN,
    command_message,
    controller_values,
    joint_state,
    pose_matrix,
    read_path,
    status_cdr,
)
from mpcshare.runtime.effort_command import EffortCommand
from mpcshare.runtime.gc_policy import CollectorPolicy
from mpcshare.runtime.messages import MESSAGE_TYPES, Clock, DiagnosticArray, ros_time, seconds
from mpcshare.runtime.tick_profile import TickProfile
from mpcshare.runtime.transport import QosSettings, Transport
from mpcshare.runtime.watchdog import Deadline, Watchdog

__all__ = ["CLOCK_TOPIC", "WARN_STATUSES", "RunLoop", "RunSummary"]

#: The simulated clock's topic (ROS 2's ``/clock``).
CLOCK_TOPIC = "/clock"

#: Controller statuses reported as WARN (the step still tracks); any other non-ok status is ERROR.
WARN_STATUSES: frozenset[str] = frozenset({"reference_unreachable", "invalid_base_pose", "keepout_stale_zone",
                                           "missing_observation", "invalid_observation_shape", "mpc_failed",
                                           "mpc_timeout", "keepout_person"})


@dataclass
class RunSummary:
    """What a run did: ticks, commands and stops published, late ticks, resumes after a stop, clock jumps
    back (``sim_time``), step times [s], the (last) stop's reason."""

    ticks: int = 0
    commands: int = 0
    stops: int = 0
    late_ticks: int = 0
    resumes: int = 0
    clock_resets: int = 0
    step_times: list[float] = field(default_factory=list)
    stop_reason: str | None = None
    statuses: dict[str, int] = field(default_factory=dict)


class RunLoop:
    """The loop (module docstring) of ``controller`` (``SharedController.step``'s interface) over ``transport``;
    ``obs_names``, ``vol_names``: the controller's channel order; ``clock`` monotonic [s], ``wall`` ROS time [s];
    ``sim_time``: both are the ``/clock`` topic's time instead (module docstring); ``rest_base_pose``: the
    base pose (T_plate_torso) given to the controller while no torso pose is configured or has arrived
    (None: none, the controller's own mount, given at its construction); ``live``: a
    :class:`mpcshare.runtime.live.LiveView` given every tick (its failure ends it, named in ``live_error``);
    ``gc_policy``: :data:`mpcshare.runtime.gc_policy.GC_POLICIES` (ValueError naming them otherwise). An effort
    command takes the arm's model from ``controller.robot`` (a :class:`robot.description.RobotDescription`);
    ValueError when ``driver_compensates_gravity`` is set and the controller has none."""

    def __init__(self, config: RunConfig, controller: Any, transport: Transport, *, obs_names: list[str],
                 vol_names: list[str], clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time, sim_time: bool = False, live: Any = None,
                 rest_base_pose: np.ndarray | None = None, gc_policy: str = "managed") -> None:
        self.sim_time, self.live = sim_time, live
        self.collector = CollectorPolicy(gc_policy)
        self.profile = TickProfile(config.period_s)
        self._t_poll = self._t_step = self._t_live = 0.0
        self._sent = math.nan
        self.rest_base_pose = None if rest_base_pose is None else np.array(rest_base_pose, dtype=float)
        self.live_error: str | None = None
        self._live_in: tuple | None = None
        self._sim_now = 0.0
        self._sim_stamp = ros_time(0.0)
        if sim_time:
            clock = wall = self._sim_clock
            self.clock_reader = transport.reader(CLOCK_TOPIC, Clock, QosSettings("reliable", 64))
        self.config, self.controller, self.clock, self.wall = config, controller, clock, wall
        self.joints = list(config.arm.joints)
        self.readers = {n: transport.reader(s.topic, MESSAGE_TYPES[s.type], s.qos) for n, s in config.inputs.items()}
        self.command_writer = transport.writer(config.command.topic, MESSAGE_TYPES[config.command.type],
                                               config.command.qos)
        self.status_writer = transport.writer(config.status_topic, DiagnosticArray, config.status_qos)
        by_name = {(c.kind, c.name): c for c in config.channels}
        self._obs = [by_name[("obs", n)] for n in obs_names]
        self._vol = [by_name[("voluntary", n)] for n in vol_names]
        self.latest: dict[str, Any] = {}
        self.wrong_frame: dict[str, int] = {n: 0 for n in config.inputs}
        self.summary = RunSummary()
        status_cdr(ros_time(0.0), "", "", OK, "", {})  # rosbags' serialiser made now (~0.2 s), not in a tick
        cmd = config.command
        self._efforts = cmd.type.endswith("Float64MultiArray") and cmd.interface == "effort"
        self.effort = EffortCommand(getattr(controller, "robot", None) if self._efforts else None, config.period_s,
                                    len(self.joints), compensated=cmd.driver_compensates_gravity,
                                    where=f"{config.source}, [outputs.command]")
        self._restart(clock())

    def _sim_clock(self) -> float:
        return self._sim_now

    def _stamp(self) -> Any:
        """Now as ROS time: the wall clock, or with ``sim_time`` the last clock message's stamp itself."""
        self._sent = time.perf_counter()  # the profile's time of the command
        return self._sim_stamp if self.sim_time else ros_time(self.wall())

    def _restart(self, start: float) -> None:
        """Start afresh at ``start``: the watchdog, no input seen, no stop (the constructor; a clock jump back)."""
        self.start = start
        self.watchdog = Watchdog([Deadline(n, s.deadline_s, s.stop_after_s, s.optional)
                                  for n, s in self.config.inputs.items()], start)
        self.latest.clear()
        self._q_last: np.ndarray | None = None  # last finite measured joint positions
        self._v_last: np.ndarray | None = None  # and velocities
        self._arm_stale = True  # the arm's joint state older than its deadline at the last check
        self._q_stop: np.ndarray | None = None  # the positions the stop holds, latched at the stop
        self._stop_reason: str | None = None
        self._stop_latched = False  # a stop that no input's return ends (a non-finite command)
        self._fresh_since: float | None = None  # since when every required input is fresh

    # ------------------------------------------------------------------ inputs
    def poll(self) -> None:
        """Take every new message of every input (module docstring, 1)."""
        now = self.clock()
        for name, reader in self.readers.items():
            frame = self.config.inputs[name].frame
            for msg in reader.take():
                if frame and msg.header.frame_id != frame:
                    self.wrong_frame[name] += 1
                    continue
                self.latest[name] = msg
                self.watchdog.seen(name, now)
        if "arm" in self.latest:
            q, v = joint_state(self.latest["arm"], self.joints)
            if np.isfinite(q).all():
                self._q_last = q
                self._v_last = v if np.isfinite(v).all() else None

    def _values(self, channels, stale: tuple[str, ...]) -> np.ndarray:
        return np.array([read_path(self.latest[c.input], c.path) if c.input in self.latest and c.input not in stale
                         else math.nan for c in channels])

    # ------------------------------------------------------------------ one tick
    def stop_command(self, stamp: Any = None) -> Any | None:
        """The stop command stamped ``stamp`` (default now; module docstring); None when no joint position was
        ever measured and the command carries positions."""
        n = len(self.joints)
        zeros = np.zeros(n)
        if self._q_last is None and not (self.config.command.type.endswith("Float64MultiArray")
                                         and self.config.command.interface != "position"):
            return None
        if self._q_stop is None and self._q_last is not None:
            self._q_stop = self._q_last.copy()
        q = self._q_stop if self._q_stop is not None else zeros
        v = None if self._arm_stale else self._v_last
        tau = self.effort.stop(self._q_last, v, self._q_stop) if self._efforts else zeros
        return command_message(self.config.command.type, self.config.command.interface, self.joints,
                               self._stamp() if stamp is None else stamp, self.config.period_s, q, zeros, zeros, tau)

    def _publish_stop(self, stamp: Any = None) -> bool:
        msg = self.stop_command(stamp)
        if msg is not None:
            self.command_writer.write(msg)
            self.summary.stops += 1
        return msg is not None

    def _resume_due(self, watch: Any, now: float) -> bool:
        """Track since when every required input is fresh; True when a stop for a silent input may end."""
        required = [n for n, s in self.config.inputs.items() if not s.optional]
        if any(n in watch.stale for n in required):
            self._fresh_since = None
        elif self._fresh_since is None:
            self._fresh_since = now
        return (self._stop_reason is not None and not self._stop_latched and self._fresh_since is not None
                and now - self._fresh_since >= self.config.resume_after_s)

    def tick(self, k: int, t: float | None = None) -> str:
        """Control tick k at time ``t`` (default k·T; module docstring, 1–2); returns the published status."""
        t_k = k * self.config.period_s if t is None else t
        self._live_in = None
        self._t_step = self._t_live = 0.0
        p0 = time.perf_counter()
        self.poll()
        self._t_poll = time.perf_counter() - p0
        now = self.clock()
        watch = self.watchdog.check(now)
        self._arm_stale = "arm" in watch.stale
        values: dict[str, object] = {"tick": k, "t": t_k}
        values.update({f"age_{n}": a for n, a in watch.ages.items()})
        values["stale_inputs"] = ",".join(watch.stale)
        values.update({f"wrong_frame_{n}": c for n, c in self.wrong_frame.items() if c})
        if watch.stopped and self._stop_reason is None:
            self._stop_reason = watch.stop_reason
        if self._resume_due(watch, now):
            values["resumed_after"] = self._stop_reason
            self.watchdog.resume()
            self._stop_reason, self._q_stop = None, None
            self.summary.resumes += 1
            if callable(getattr(self.controller, "reset", None)):
                self.controller.reset()
        if self._stop_reason is not None:
            stamp = self._stamp()  # the stop command's and its status's
            sent = self._publish_stop(stamp)
            values.update(protective_stop=self._stop_reason, stop_command=int(sent))
            return self._status(stamp, ERROR, "protective_stop", f"protective stop: {self._stop_reason}"
                                f"{self.effort.note(values)}", values)
        if "arm" not in self.latest:
            stamp = self._stamp()
            return self._status(stamp, STALE, "waiting", f"waiting for the arm's joint states on "
                                                         f"{self.config.arm.topic}", values)
        arm_stamp = self.latest["arm"].header.stamp
        values["input_stamp"] = f"{arm_stamp.sec}.{arm_stamp.nanosec:09d}"
        q, v = joint_state(self.latest["arm"], self.joints)
        if "arm" in watch.stale:
            q, v = np.full_like(q, np.nan), np.full_like(v, np.nan)
        base = self.rest_base_pose
        if "torso" in self.config.inputs and "torso" in self.latest:
            base = pose_matrix(self.latest["torso"].pose) if "torso" not in watch.stale else np.full((4, 4), np.nan)
        obs, vol = self._values(self._obs, watch.stale), self._values(self._vol, watch.stale)
        t0 = time.perf_counter()
        cmd = self.controller.step(t_k, obs, vol, q, v, base)
        self._t_step = time.perf_counter() - t0
        self.summary.step_times.append(self._t_step)
        self._live_in = (q, v, base, dict(zip((c.name for c in self._obs), obs)), vol, cmd,
                         self.summary.step_times[-1])
        arrays = [np.asarray(getattr(cmd, a, np.nan), dtype=float) for a in ("q_cmd", "v_cmd", "a_cmd", "tau")]
        stamp = self._stamp()
        finite = all(x.shape == (len(self.joints),) and np.isfinite(x).all() for x in arrays)
        if finite and self.config.command.driver_compensates_gravity:
            arrays[3] = self.effort.command(arrays[3], q, self._q_last)
            if not np.isfinite(arrays[3]).all():
                self._stop_reason, finite = "g(q) for the driver's gravity compensation could not be computed", False
        if not finite:
            self._stop_reason = self._stop_reason or \
                f"the controller gave a non-finite command (status {getattr(cmd, 'status', '?')})"
            self._stop_latched = True
            self._publish_stop(stamp)
            values["protective_stop"] = self._stop_reason
            return self._status(stamp, ERROR, "protective_stop", f"protective stop: {self._stop_reason}"
                                f"{self.effort.note(values)}", values)
        self.command_writer.write(command_message(self.config.command.type, self.config.command.interface,
                                                  self.joints, stamp, self.config.period_s, *arrays))
        self.summary.commands += 1
        status = str(cmd.status)
        values.update(controller_values(cmd, getattr(self.controller, "keepout", None)))
        stale_note = "; stale: " + ", ".join(f"{n} ({self.config.inputs[n].topic}, {watch.ages[n]:.3f} s)"
                                             for n in watch.stale) if watch.stale else ""
        level = OK if status == "ok" and not watch.stale else WARN if status in WARN_STATUSES or status == "ok" \
            else ERROR
        return self._status(stamp, level, status, f"{status}{stale_note}", values)

    def _status(self, stamp, level: int, status: str, message: str, values: dict[str, object]) -> str:
        values = {"status": status, "stamp": f"{stamp.sec}.{stamp.nanosec:09d}", **values}
        self.status_writer.write_cdr(status_cdr(stamp, "mpcshare: shared controller", self.config.name, level,
                                                message, values))
        self.summary.statuses[status] = self.summary.statuses.get(status, 0) + 1
        if self.live is not None:
            t0 = time.perf_counter()
            self._live_step(stamp, status)
            self._t_live = time.perf_counter() - t0
        return status

    def _live_step(self, stamp: Any, status: str) -> None:
        n = len(self.joints)
        q_last = self._q_last if self._q_last is not None else np.full(n, np.nan)
        q, v, base, obs, vol, cmd, step_s = self._live_in or (q_last, np.full(n, np.nan), None, {},
                                                               np.full(len(self._vol), np.nan), None, 0.0)
        try:
            self.live.step(stamp.sec * 1_000_000_000 + stamp.nanosec, q=q, v=v, base=base, obs=obs, voluntary=vol,
                           command=cmd, status=status, step_time_s=step_s)
        except Exception as exc:  # noqa: BLE001  (the view must never stop the loop: it ends, and says why)
            self.live_error, self.live = f"{type(exc).__name__}: {exc}", None

    # ------------------------------------------------------------------ the schedule
    def run(self, duration_s: float | None = None, should_stop: Callable[[], bool] = lambda: False) -> RunSummary:
        """Tick on the monotonic schedule (``sim_time``: on each new clock message) until ``duration_s`` [s]
        (None: no end; ``sim_time``: seconds of the wall clock) or ``should_stop()``; then :meth:`shutdown`.
        Returns the summary."""
        if self.sim_time:
            return self._run_sim_time(duration_s, should_stop)
        self.collector.start()  # a full collection first: the schedule starts after it
        self.profile.install()
        self._restart(self.clock())
        T, k, origin, triggered, skipped = self.config.period_s, 0, self.start, False, False
        slack = T / 2 if self.config.tick == "arm" else 0.0  # how far from its time a tick may run
        try:
            while not should_stop():
                if duration_s is not None and k * T >= duration_s:
                    break
                t_tick, wall = self.clock(), self.wall()
                self.tick(k)
                self._profile_tick(wall, skipped)
                self.summary.ticks += 1
                if triggered:  # phase-locked to the arm: the next window is centred one period after this tick
                    origin = t_tick - k * T
                now = self.clock() - origin
                nxt = k + 1
                skipped = now >= nxt * T + slack
                if skipped:  # overran: skip to the next tick still ahead
                    late = int((now - slack) // T) + 1
                    self.summary.late_ticks += late - nxt
                    nxt = late
                opens = origin + nxt * T - slack
                self.collector.idle(opens - self.clock())
                self._sleep_until(opens, should_stop)
                triggered = False
                if slack:  # then on the arm's next joint state, or at the window's end
                    arm = self.readers["arm"]
                    while (left := opens + 2 * slack - self.clock()) > 0 and not should_stop():
                        if arm.wait(min(left, 0.005)):
                            triggered = True
                            break
                k = nxt
        finally:
            self.collector.stop()
            self.profile.uninstall()
            self.shutdown()
        self.summary.stop_reason = self._stop_reason
        return self.summary

    def _sleep_until(self, end: float, should_stop: Callable[[], bool]) -> None:
        """Sleep until ``end`` on the loop's clock: in steps of ≤ 5 ms, the last 0.2 ms spun."""
        while (wait := end - self.clock()) > 0 and not should_stop():
            if wait > 2e-4:
                time.sleep(min(wait - 2e-4, 0.005))

    def _profile_tick(self, wall: float, skipped: bool) -> None:
        arm = self.latest.get("arm")
        arm_stamp = seconds(arm.header.stamp) if arm is not None else math.nan
        publish = time.perf_counter() - self._sent - self._t_live
        self.profile.tick(wall, arm_stamp, self._sent, (self._t_poll, self._t_step, publish, self._t_live), skipped)

    def _run_sim_time(self, duration_s: float | None, should_stop: Callable[[], bool]) -> RunSummary:
        end = math.inf if duration_s is None else time.monotonic() + duration_s
        last, k = -math.inf, 0
        try:
            while not should_stop() and time.monotonic() < end:
                if not self.clock_reader.wait(0.05):
                    continue
                for msg in self.clock_reader.take():
                    t = seconds(msg.clock)
                    if t < last:  # a new episode: start afresh
                        self._sim_now = t
                        self._restart(t)
                        self.summary.clock_resets += 1
                        if callable(getattr(self.controller, "reset", None)):
                            self.controller.reset()
                    elif t == last:
                        continue
                    elif last == -math.inf:
                        self._sim_now = t
                        self._restart(t)
                    self._sim_now, self._sim_stamp, last = t, msg.clock, t
                    k = int(round((t - self.start) / self.config.period_s))
                    self.tick(k, t)
                    self.summary.ticks += 1
        finally:
            self.shutdown()
        self.summary.stop_reason = self._stop_reason
        return self.summary

    def shutdown(self) -> None:
        """Publish the stop command and wait up to 0.2 s for reliable readers to acknowledge it."""
        stamp = self._stamp()
        sent = self._publish_stop(stamp)
        values: dict[str, object] = {"stop_command": int(sent)}
        note = self.effort.note(values)
        self._status(stamp, ERROR if self._stop_reason else OK, "stopped",
                     "stopped: " + (self._stop_reason or "end of the run") + note, values)
        if sent:
            self.command_writer.flush(0.2)
        self.status_writer.flush(0.05)
