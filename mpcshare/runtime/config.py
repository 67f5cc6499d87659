"""The arm's configuration of ``mpcshare run``: a TOML file → :class:`RunConfig`, checked.

Tables (every key: docs/design.md, "On a real arm"; examples ``examples/ros2/superlimb.toml``, ``panda.toml``)::

    name = "superlimb"; rate_hz = 100.0   # the status's hardware_id; the control rate (the model's)
    resume_after_s = 1.0                  # after a stop for a silent input: resume once all are fresh this long [s]
    tick = "arm"                          # on each joint state within T/2 of its tick; "schedule": every period
    [network]                             # optional; default loopback 127.0.0.1, no multicast, domain_id 0
    [robot]                               # optional (absent: the SuperLimb): file, tip_frame, mount [m], caps
    [controller]                          # optional: strategy ("gate"), beta (0.5), mpc (false)
    [inputs.arm]                          # required: topic, joints (the model's, in its order)
    [inputs.NAME]                         # topic, type, optional, deadline_s, stop_after_s, frame, reliability, depth
    [obs] / [voluntary]                   # every channel of the model: "INPUT FIELD.PATH"
    [outputs.command] / [outputs.status]  # topic, type, interface, driver_compensates_gravity; the status topic

Field paths as ``mpcshare import``'s (:func:`learning.data.mapping.parse_field_path`): ``a.b[i]``, ``@roll``.
Older than ``deadline_s``: an input's channels are missing (the controller's fault path); older than
``stop_after_s``: protective stop (never for an optional input). Errors: :class:`RunConfigError`, one line
naming the file, the table and the key; :func:`load_run_config` checks the file alone,
:func:`check_against_model` against the model (channels, joint names, rate) before anything is sent.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

from learning.data.mapping import FieldPath, parse_field_path
from mpcshare.runtime.config_reader import RunConfigError, TableReader, check_field_path
from mpcshare.runtime.messages import MESSAGE_TYPES
from mpcshare.runtime.transport import NetworkSettings, QosSettings

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["COMMAND_TYPES", "INPUT_TYPES", "INTERFACES", "STATUS_TYPES", "TICKS", "ChannelSpec", "CommandSpec",
           "ControllerSpec", "InputSpec", "RobotSpec", "RunConfig", "RunConfigError", "check_against_model",
           "load_run_config", "parse_run_config"]

#: Messages an input can carry.
INPUT_TYPES: tuple[str, ...] = ("sensor_msgs/msg/JointState", "geometry_msgs/msg/PoseStamped",
                                "geometry_msgs/msg/WrenchStamped")
#: Messages the joint command can be (ros2_control's joint trajectory and forward command controllers).
COMMAND_TYPES: tuple[str, ...] = ("trajectory_msgs/msg/JointTrajectory", "std_msgs/msg/Float64MultiArray")
#: What a Float64MultiArray command carries.
INTERFACES: tuple[str, ...] = ("position", "velocity", "effort")
#: When the loop ticks: on its schedule, or on the arm's joint states.
TICKS: tuple[str, ...] = ("schedule", "arm")
#: Messages the status can be.
STATUS_TYPES: tuple[str, ...] = ("diagnostic_msgs/msg/DiagnosticArray",)
_TOP = ("name", "rate_hz", "resume_after_s", "tick", "network", "robot", "controller", "inputs", "obs", "voluntary",
        "outputs")
_INPUT_KEYS = ("topic", "type", "optional", "deadline_s", "stop_after_s", "frame", "reliability", "depth",
               "joints")
_ERD = "example-robot-data:"


@dataclass(frozen=True)
class InputSpec:
    """One input topic: name (its table), topic, type (ROS name), deadline_s and stop_after_s [s] after its
    last message, optional, frame (the header's frame_id it must carry; "" any), qos, joints (the arm)."""

    name: str
    topic: str
    type: str
    deadline_s: float
    stop_after_s: float
    optional: bool = False
    frame: str = ""
    qos: QosSettings = field(default_factory=QosSettings)
    joints: tuple[str, ...] = ()


@dataclass(frozen=True)
class ChannelSpec:
    """One channel of the model: kind ("obs" or "voluntary"), name, the input it comes from and its path."""

    kind: str
    name: str
    input: str
    path: FieldPath


@dataclass(frozen=True)
class CommandSpec:
    """The joint command's topic, type (:data:`COMMAND_TYPES`), interface (:data:`INTERFACES`) and QoS;
    ``driver_compensates_gravity`` (effort only): the driver adds g(q) itself, so g(q) is subtracted from every
    effort sent (efforts are otherwise total joint torques, gravity included)."""

    topic: str
    type: str
    interface: str = "position"
    qos: QosSettings = field(default_factory=lambda: QosSettings("reliable", 1))
    driver_compensates_gravity: bool = False


@dataclass(frozen=True)
class RobotSpec:
    """The arm's description (None file: the SuperLimb); mount in the plate frame [m] with the torso at rest,
    rpy [rad]; caps [rad/s, rad/s²] (None: chosen, :mod:`mpcshare.runtime.setup`)."""

    file: str | None = None
    tip_frame: str = ""
    mount: tuple[float, float, float] | None = None
    mount_rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    locked_joints: tuple[str, ...] = ()
    velocity_limit: float | None = None
    acceleration_limit: float | None = None


@dataclass(frozen=True)
class ControllerSpec:
    """The shared controller's strategy, β and whether the MPC runs."""

    strategy: str = "gate"
    beta: float = 0.5
    mpc: bool = False


@dataclass(frozen=True)
class RunConfig:
    """A checked configuration (module docstring); ``inputs`` by name, the arm's first."""

    source: str
    name: str
    rate_hz: float
    network: NetworkSettings
    robot: RobotSpec
    controller: ControllerSpec
    inputs: dict[str, InputSpec]
    channels: tuple[ChannelSpec, ...]
    command: CommandSpec
    status_topic: str
    status_qos: QosSettings
    resume_after_s: float = 1.0
    tick: str = "arm"

    @property
    def arm(self) -> InputSpec:
        """The arm's joint-state input."""
        return self.inputs["arm"]

    @property
    def period_s(self) -> float:
        """The control period [s]."""
        return 1.0 / self.rate_hz

    def names(self, kind: str) -> list[str]:
        """The channels of one kind, in the file's order."""
        return [c.name for c in self.channels if c.kind == kind]


def _inputs(d: TableReader, doc: dict, period_s: float) -> dict[str, InputSpec]:
    table = d.table(doc, "inputs", "[inputs]", required=True)
    if "arm" not in table:
        raise d.fail("[inputs.arm]", "missing: the arm's sensor_msgs/msg/JointState input is required")
    out: dict[str, InputSpec] = {}
    for name in ["arm"] + [k for k in table if k != "arm"]:
        where = f"[inputs.{name}]"
        t = d.table(table, name, where)
        d.keys(t, _INPUT_KEYS, where)
        topic = d.topic(t, where)
        default_type = {"arm": INPUT_TYPES[0], "torso": INPUT_TYPES[1]}.get(name)
        kind = d.text(t, "type", where, default_type)
        if kind not in INPUT_TYPES:
            raise d.fail(f"{where} type", f"unknown message type {kind!r} for an input "
                                          f"(inputs: {', '.join(INPUT_TYPES)})")
        if name in ("arm", "torso") and kind != default_type:
            raise d.fail(f"{where} type", f"the {name} input must be {default_type}, got {kind!r}")
        deadline = d.number(t, "deadline_s", where, 0.05)
        stop = d.number(t, "stop_after_s", where, max(0.25, 5 * deadline))
        if deadline < period_s:
            raise d.fail(f"{where} deadline_s", f"{deadline:g} s is shorter than one control period "
                                                f"({period_s:g} s): it cannot be checked at that rate")
        if not stop > deadline:
            raise d.fail(f"{where} stop_after_s", f"{stop:g} s must be longer than deadline_s ({deadline:g} s)")
        optional = d.flag(t, "optional", where, False)
        if name == "arm" and optional:
            raise d.fail(f"{where} optional", "the arm's joint states cannot be optional")
        joints = d.strings(t, "joints", where)
        if name == "arm" and not joints:
            raise d.fail(f"{where} joints", "missing: the arm's joint names, in the model's order")
        if name != "arm" and joints:
            raise d.fail(f"{where} joints", "only [inputs.arm] takes joint names")
        if len(set(joints)) != len(joints):
            raise d.fail(f"{where} joints", f"joint names repeat: {list(joints)}")
        out[name] = InputSpec(name, topic, kind, deadline, stop, optional, d.text(t, "frame", where, ""),
                              d.qos(t, where, QosSettings()), joints)
    return out


def _channels(d: TableReader, doc: dict, inputs: dict[str, InputSpec]) -> tuple[ChannelSpec, ...]:
    out: list[ChannelSpec] = []
    for kind in ("obs", "voluntary"):
        table = d.table(doc, kind, f"[{kind}]", required=True)
        for name, value in table.items():
            where = f"[{kind}] {name}"
            if not isinstance(value, str) or len(value.split()) != 2:
                raise d.fail(where, f"expected \"INPUT FIELD.PATH\" (two words), got {value!r}")
            source, text = value.split()
            if source not in inputs or source in ("arm", "torso"):
                named = [n for n in inputs if n not in ("arm", "torso")]
                raise d.fail(where, f"no input {source!r} (inputs: {', '.join(named) or 'none'})")
            try:
                path = parse_field_path(text)
                check_field_path(MESSAGE_TYPES[inputs[source].type], path)
            except ValueError as exc:
                raise d.fail(where, f"{exc} ({inputs[source].type})") from None
            out.append(ChannelSpec(kind, str(name), source, path))
    return tuple(out)


def _robot(d: TableReader, doc: dict, folder: Path) -> RobotSpec:
    t = d.table(doc, "robot", "[robot]")
    if not t:
        return RobotSpec()
    d.keys(t, ("file", "tip_frame", "mount", "mount_rpy", "locked_joints", "velocity_limit",
               "acceleration_limit"), "[robot]")
    file = d.text(t, "file", "[robot]")
    if not file.startswith(_ERD) and not Path(file).is_absolute():
        file = str(folder / file)
    mount = d.triple(t, "mount", "[robot]")
    if mount is None:
        raise d.fail("[robot] mount", "missing: the arm's base in the plate frame [m]")
    return RobotSpec(file, d.text(t, "tip_frame", "[robot]"), mount, d.triple(t, "mount_rpy", "[robot]") or
                     (0.0, 0.0, 0.0), d.strings(t, "locked_joints", "[robot]"),
                     d.number(t, "velocity_limit", "[robot]"), d.number(t, "acceleration_limit", "[robot]"))


def _network(d: TableReader, doc: dict) -> NetworkSettings:
    t = d.table(doc, "network", "[network]")
    d.keys(t, ("interface", "peers", "multicast", "domain_id"), "[network]")
    dom = t.get("domain_id", 0)
    if isinstance(dom, bool) or not isinstance(dom, int) or not 0 <= dom <= 232:
        raise d.fail("[network] domain_id", f"must be an integer in [0, 232] (ROS_DOMAIN_ID), got {dom!r}")
    return NetworkSettings(d.text(t, "interface", "[network]", "127.0.0.1"),
                           d.strings(t, "peers", "[network]", ("127.0.0.1",)),
                           d.flag(t, "multicast", "[network]", False), dom)


def parse_run_config(doc: dict[str, Any], source: str, folder: Path | None = None) -> RunConfig:
    """Check a configuration already read from TOML (module docstring); ``folder``: where relative files are."""
    d = TableReader(source)
    d.keys(doc, _TOP, "top level")
    rate = d.number(doc, "rate_hz", "top level", 100.0, high=1000.0)
    inputs = _inputs(d, doc, 1.0 / rate)
    controller = d.table(doc, "controller", "[controller]")
    d.keys(controller, ("strategy", "beta", "mpc"), "[controller]")
    beta = controller.get("beta", 0.5)
    if isinstance(beta, bool) or not isinstance(beta, (int, float)) or not 0.0 <= beta <= 1.0:
        raise d.fail("[controller] beta", f"must be a number in [0, 1], got {beta!r}")
    outputs = d.table(doc, "outputs", "[outputs]", required=True)
    d.keys(outputs, ("command", "status"), "[outputs]")
    cmd = d.table(outputs, "command", "[outputs.command]", required=True)
    d.keys(cmd, ("topic", "type", "interface", "reliability", "depth", "driver_compensates_gravity"),
           "[outputs.command]")
    ctype = d.text(cmd, "type", "[outputs.command]", COMMAND_TYPES[0])
    if ctype not in COMMAND_TYPES:
        raise d.fail("[outputs.command] type", f"unknown message type {ctype!r} for the command "
                                               f"(commands: {', '.join(COMMAND_TYPES)})")
    interface = d.text(cmd, "interface", "[outputs.command]", "position", INTERFACES)
    if ctype == COMMAND_TYPES[0] and interface != "position":
        raise d.fail("[outputs.command] interface", "a JointTrajectory carries positions, velocities and "
                                                    "accelerations: leave interface out")
    compensated = d.flag(cmd, "driver_compensates_gravity", "[outputs.command]", False)
    if compensated and interface != "effort":
        raise d.fail("[outputs.command] driver_compensates_gravity", "applies to an effort command only "
                                                                     f"(interface = \"effort\"), not {interface}")
    status = d.table(outputs, "status", "[outputs.status]")
    d.keys(status, ("topic", "type", "reliability", "depth"), "[outputs.status]")
    d.text(status, "type", "[outputs.status]", STATUS_TYPES[0], STATUS_TYPES)
    return RunConfig(
        source=source, name=d.text(doc, "name", "top level", Path(source).stem), rate_hz=rate,
        network=_network(d, doc), robot=_robot(d, doc, folder or Path(source).parent),
        controller=ControllerSpec(d.text(controller, "strategy", "[controller]", "gate"), float(beta),
                                  d.flag(controller, "mpc", "[controller]", False)),
        inputs=inputs, channels=_channels(d, doc, inputs),
        command=CommandSpec(d.topic(cmd, "[outputs.command]"), ctype, interface,
                            d.qos(cmd, "[outputs.command]", QosSettings("reliable", 1)), compensated),
        status_topic=d.topic(status, "[outputs.status]") if "topic" in status else "/mpcshare/status",
        status_qos=d.qos(status, "[outputs.status]", QosSettings("reliable", 1)),
        resume_after_s=float(d.number(doc, "resume_after_s", "top level", 1.0)),
        tick=d.text(doc, "tick", "top level", "arm", TICKS))


def load_run_config(path: str | Path) -> RunConfig:
    """Read and check a configuration file (module docstring); :class:`RunConfigError` naming what and where."""
    p = str(path)
    try:
        with open(p, "rb") as f:
            doc = tomllib.load(f)
    except FileNotFoundError:
        raise RunConfigError(f"{p}: no such configuration file") from None
    except OSError as exc:
        raise RunConfigError(f"{p}: cannot read the configuration ({exc.strerror or exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise RunConfigError(f"{p}: not valid TOML ({exc})") from None
    return parse_run_config(doc, p, Path(p).resolve().parent)


def check_against_model(config: RunConfig, *, obs_names: Sequence[str], vol_names: Sequence[str],
                        rate_hz: float, joint_names: Sequence[str]) -> None:
    """:class:`RunConfigError` unless ``config`` maps every channel of the model (and no other), names the
    arm's joints in the model's order, and runs at the model's rate."""
    d = TableReader(config.source)
    for kind, wanted in (("obs", list(obs_names)), ("voluntary", list(vol_names))):
        have = config.names(kind)
        missing = [n for n in wanted if n not in have]
        if missing:
            raise d.fail(f"[{kind}] {missing[0]}", f"missing: the model reads this channel (its {kind} channels: "
                                                   f"{', '.join(wanted)})")
        extra = [n for n in have if n not in wanted]
        if extra:
            raise d.fail(f"[{kind}] {extra[0]}", f"the model has no such channel (its {kind} channels: "
                                                 f"{', '.join(wanted)})")
    joints = list(config.arm.joints)
    unknown = [j for j in joints if j not in joint_names]
    if unknown:
        raise d.fail("[inputs.arm] joints", f"the model has no joint {unknown[0]!r} (its joints: "
                                            f"{', '.join(joint_names)})")
    if joints != list(joint_names):
        raise d.fail("[inputs.arm] joints", f"{joints} must be the model's joints in its order: {list(joint_names)}")
    if not math.isclose(config.rate_hz, rate_hz, rel_tol=1e-9):
        raise d.fail("top level rate_hz", f"{config.rate_hz:g} Hz is not the model's rate ({rate_hz:g} Hz): the "
                                          "controller runs at the rate it was trained at")
