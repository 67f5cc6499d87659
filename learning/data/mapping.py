"""The mapping from ROS topics to data-set channels: a TOML file, parsed and checked.

The tables ``[obs]`` and ``[act]`` (required, non-empty) and ``[voluntary]`` (optional) map each
channel, by its physical name, to ``"TOPIC FIELD.PATH"``; ``[map]`` renames a channel
(``NAME = "CHANNEL"``, as ``--map NAME=CHANNEL`` of ``mpcshare train`` and ``sim``)::

    time = "header"                      # or "receive" (the time the recorder got it)
    subject = 3                          # or "s(\\d+)" (a regular expression on the bag's name),
                                         # or a table [subject] of bag name = id
    [obs]
    fork_roll = "/fork/pose pose.orientation@roll"   # @roll, @pitch, @yaw: ZYX angles of a quaternion
    [act]
    knife_x = "/knife/pose pose.position.x"
    [voluntary]
    shoulder_elevation = "/shoulder/joint_states position[0]"   # [i]: an element of an array

A field path is attribute names separated by dots, each optionally followed by ``[i]``; it ends
at a number, or at a quaternion with ``@roll``, ``@pitch`` or ``@yaw`` (tf2's ``getRPY`` of the
normalised quaternion: R = Rz(yaw)·Ry(pitch)·Rx(roll)). Errors are
:class:`~learning.data.DataFormatError` naming the file and entry (``MAP.toml, field '[obs] fork_x': ...``).
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .checks import DataFormatError
from .model import PathLike

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["ANGLES", "KINDS", "BagMapping", "ChannelSource", "FieldPath", "load_mapping", "parse_field_path",
           "parse_mapping", "quaternion_angles"]

#: The channel tables of a mapping file, in the order of the data set's fields.
KINDS: tuple[str, ...] = ("obs", "act", "voluntary")
#: The angles a quaternion field can give.
ANGLES: tuple[str, ...] = ("roll", "pitch", "yaw")
#: Time sources: the message's header stamp, or the time the recorder received it.
TIME_SOURCES: tuple[str, ...] = ("header", "receive")
_TOP_KEYS = KINDS + ("subject", "time", "map")

_IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
_PATH = re.compile(rf"^(?P<body>{_IDENT}(\[\d+\])*(\.{_IDENT}(\[\d+\])*)*)(@(?P<angle>[A-Za-z]+))?$")
_STEP = re.compile(rf"({_IDENT})|\[(\d+)\]")


@dataclass(frozen=True)
class FieldPath:
    """A path into a message: attribute names (str) and array indices (int), and an optional angle.

    Attributes:
        steps: e.g. ``("pose", "orientation")`` or ``("position", 0)``.
        angle: ``"roll"``, ``"pitch"``, ``"yaw"`` (the path ends at a quaternion) or None.
        text: the path as written.
    """

    steps: tuple[str | int, ...]
    angle: str | None
    text: str

    @property
    def is_angle(self) -> bool:
        """True for the angle of a quaternion: unwrapped before it is interpolated."""
        return self.angle is not None


@dataclass(frozen=True)
class ChannelSource:
    """One channel of the data set and where it comes from."""

    kind: str  # "obs", "act" or "voluntary"
    name: str
    topic: str
    path: FieldPath

    @property
    def label(self) -> str:
        """How errors name the entry: ``[obs] fork_x``."""
        return f"[{self.kind}] {self.name}"


@dataclass(frozen=True)
class BagMapping:
    """A parsed mapping file (module docstring).

    Attributes:
        channels: every channel, in the file's order within each table (obs, act, voluntary).
        time: ``"header"`` or ``"receive"``.
        subject: an int (every bag), a compiled regular expression (the first group, or
            the whole match, of the bag's name is the id), a dict {bag name: id}, or None (−1).
        source: the mapping file, for messages.
    """

    channels: tuple[ChannelSource, ...]
    time: str = "header"
    subject: int | re.Pattern[str] | dict[str, int] | None = None
    source: str | None = None

    def names(self, kind: str) -> list[str]:
        """The channel names of one table, in order."""
        return [c.name for c in self.channels if c.kind == kind]

    @property
    def topics(self) -> list[str]:
        """The mapped topics, each once, in order of first use."""
        return list(dict.fromkeys(c.topic for c in self.channels))

    def subject_for(self, bag_name: str) -> int:
        """The subject id of a bag (by its file or folder name); −1 when the mapping gives none."""
        s = self.subject
        if s is None:
            return -1
        if isinstance(s, int):
            return s
        if isinstance(s, dict):
            if bag_name not in s:
                raise DataFormatError(f"bag '{bag_name}' has no entry (entries: {', '.join(sorted(s))})",
                                      path=self.source, field="[subject]")
            return s[bag_name]
        m = s.search(bag_name)
        if m is None:
            raise DataFormatError(f"the pattern {s.pattern!r} does not match the bag name '{bag_name}'",
                                  path=self.source, field="subject")
        text = m.group(1) if m.groups() else m.group(0)
        try:
            return int(text)
        except ValueError:
            raise DataFormatError(f"the pattern {s.pattern!r} gives {text!r} for bag '{bag_name}', "
                                  "not an integer", path=self.source, field="subject") from None


def parse_field_path(text: str) -> FieldPath:
    """Parse ``pose.orientation@roll`` or ``position[0]``; raises ValueError saying what is wrong."""
    m = _PATH.match(text)
    if m is None:
        raise ValueError(f"field path {text!r} is not of the form name.name[i]...(@roll|@pitch|@yaw)")
    angle = m.group("angle")
    if angle is not None and angle not in ANGLES:
        raise ValueError(f"field path {text!r}: unknown angle '@{angle}' (use @roll, @pitch or @yaw)")
    steps: list[str | int] = []
    for name, index in _STEP.findall(m.group("body")):
        steps.append(name if name else int(index))
    return FieldPath(tuple(steps), angle, text)


def _subject(value: Any, source: str | None) -> int | re.Pattern[str] | dict[str, int] | None:
    if value is None:
        return None
    if isinstance(value, bool):
        raise DataFormatError("must be an integer, a regular expression or a table", path=source, field="subject")
    if isinstance(value, int):
        return value
    if isinstance(value, str):
        try:
            return re.compile(value)
        except re.error as exc:
            raise DataFormatError(f"not a regular expression ({exc})", path=source, field="subject") from None
    if isinstance(value, dict):
        out: dict[str, int] = {}
        for bag, sid in value.items():
            if isinstance(sid, bool) or not isinstance(sid, int):
                raise DataFormatError(f"subject of bag '{bag}' must be an integer, got {sid!r}",
                                      path=source, field="[subject]")
            out[str(bag)] = sid
        return out
    raise DataFormatError(f"must be an integer, a regular expression or a table, got {value!r}",
                          path=source, field="subject")


def parse_mapping(doc: dict[str, Any], source: str | None = None) -> BagMapping:
    """Check a mapping already read from TOML (a dict) and return it as a :class:`BagMapping`."""
    unknown = [k for k in doc if k not in _TOP_KEYS]
    if unknown:
        raise DataFormatError(f"unknown key (allowed: {', '.join(_TOP_KEYS)})", path=source, field=unknown[0])
    time = doc.get("time", "header")
    if time not in TIME_SOURCES:
        raise DataFormatError(f"must be \"header\" or \"receive\", got {time!r}", path=source, field="time")
    channels: list[ChannelSource] = []
    for kind in KINDS:
        table = doc.get(kind)
        if table is None:
            if kind == "voluntary":
                continue
            raise DataFormatError(f"the mapping has no [{kind}] table (it needs [obs] and [act])", path=source,
                                  field=f"[{kind}]")
        if not isinstance(table, dict):
            raise DataFormatError(f"must be a table of channel = \"TOPIC FIELD.PATH\", got {table!r}",
                                  path=source, field=f"[{kind}]")
        if not table:
            raise DataFormatError("the table is empty: map at least one channel", path=source, field=f"[{kind}]")
        for name, value in table.items():
            label = f"[{kind}] {name}"
            if not isinstance(value, str):
                raise DataFormatError(f"expected \"TOPIC FIELD.PATH\", got {value!r}", path=source, field=label)
            parts = value.split()
            if len(parts) != 2:
                raise DataFormatError(f"expected \"TOPIC FIELD.PATH\" (two words), got {value!r}",
                                      path=source, field=label)
            try:
                path = parse_field_path(parts[1])
            except ValueError as exc:
                raise DataFormatError(str(exc), path=source, field=label) from None
            channels.append(ChannelSource(kind, str(name), parts[0], path))
    return BagMapping(_renamed(channels, doc.get("map"), source), time, _subject(doc.get("subject"), source), source)


def _renamed(channels: list[ChannelSource], table: Any, source: str | None) -> tuple[ChannelSource, ...]:
    """``channels`` with the ``[map]`` table's renames applied (NAME = "CHANNEL")."""
    if table is None:
        return tuple(channels)
    if not isinstance(table, dict):
        raise DataFormatError(f"must be a table of NAME = \"CHANNEL\", got {table!r}", path=source, field="[map]")
    out = list(channels)
    for name, channel in table.items():
        label = f"[map] {name}"
        if not isinstance(channel, str):
            raise DataFormatError(f"expected the name of a channel above, got {channel!r}", path=source, field=label)
        hits = [i for i, c in enumerate(channels) if c.name == channel]
        if len(hits) != 1:
            raise DataFormatError(f"no channel {channel!r} in [obs], [act] or [voluntary]" if not hits else
                                  f"{channel!r} is a channel of more than one table", path=source, field=label)
        c = out[hits[0]]
        if c.name != channel:
            raise DataFormatError(f"{channel!r} is renamed twice (to {c.name!r} too)", path=source, field=label)
        if any(o.kind == c.kind and o.name == name for o in out):
            raise DataFormatError(f"[{c.kind}] already has a channel {name!r}", path=source, field=label)
        out[hits[0]] = ChannelSource(c.kind, str(name), c.topic, c.path)
    return tuple(out)


def load_mapping(path: PathLike) -> BagMapping:
    """Read and check a mapping file (TOML)."""
    p = str(path)
    try:
        with open(p, "rb") as f:
            doc = tomllib.load(f)
    except FileNotFoundError:
        raise DataFormatError("no such mapping file", path=p) from None
    except OSError as exc:
        raise DataFormatError(f"cannot read the mapping file ({exc.strerror or exc})", path=p) from None
    except tomllib.TOMLDecodeError as exc:
        raise DataFormatError(f"not valid TOML ({exc})", path=p) from None
    return parse_mapping(doc, str(Path(p)))


def quaternion_angles(q: np.ndarray, angle: str) -> np.ndarray:
    """Roll, pitch or yaw [rad] of (n, 4) quaternions ``(x, y, z, w)``, as tf2's ``getRPY``.

    ZYX convention: rotation = Rz(yaw)·Ry(pitch)·Rx(roll); roll, yaw in (−π, π], pitch in
    [−π/2, π/2]. Quaternions are normalised first; a zero quaternion gives NaN.
    """
    q = np.asarray(q, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    if angle == "roll":
        return np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    if angle == "pitch":
        return np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    if angle == "yaw":
        return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    raise ValueError(f"angle must be one of {ANGLES}, got {angle!r}")
