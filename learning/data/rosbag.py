"""ROS recordings into a data set: rosbag2 folders (MCAP or sqlite3 storage) and ROS 1 ``.bag`` files.

:func:`import_bags` reads each bag with the ``rosbags`` package (pure Python), takes
the mapped fields of the mapped topics (:mod:`learning.data.mapping`), puts them on
one grid (:mod:`learning.data.regrid`) and returns a validated
:class:`~learning.data.Demonstrations`: one bag is one trial (or several, when
gaps split it). Before any message is read, every mapped topic is looked up in the
bag and every field path is checked against the message type's definition, so
that a typo costs no reading time.

Time: with ``time = "header"`` (the default) a sample's time is its header stamp
where the message type has a header, else the time the recorder received it; with
``"receive"`` always the latter. Per topic the samples are sorted by time and a
repeated time keeps its first sample. Times in the data set are seconds from the
first mapped message of the bag; the first trial of a bag starts where every
topic has data.

Every problem is one :class:`~learning.data.DataFormatError` naming the bag (or
the mapping file) and what is wrong.
"""

from __future__ import annotations

import operator
import time as _time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .checks import DataFormatError
from .mapping import BagMapping, ChannelSource, FieldPath, quaternion_angles
from .model import Demonstrations, PathLike, Trial
from .regrid import TopicSeries, regrid

__all__ = ["BagImport", "bag_name", "import_bags", "read_bag"]

# rosbags' parse-tree node types (rosbags.interfaces.Nodetype): BASE, NAME (a message), ARRAY, SEQUENCE
_BASE, _NAME, _ARRAY, _SEQUENCE = 1, 2, 3, 4
_NUMERIC = {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
            "float32", "float64", "octet"}
_PROGRESS_EVERY = 1000  # messages between progress-bar updates


@dataclass
class BagImport:
    """The result of :func:`import_bags`: the data set and what reading it took.

    Attributes:
        demos: the validated data set.
        messages: messages read (the mapped topics, every bag).
        seconds: wall time of reading and resampling [s].
        trials_per_bag: {bag path: number of trials it gave}.
    """

    demos: Demonstrations
    messages: int
    seconds: float
    trials_per_bag: dict[str, int] = field(default_factory=dict)

    @property
    def messages_per_second(self) -> float:
        return self.messages / self.seconds if self.seconds > 0 else float("nan")


def bag_name(path: PathLike) -> str:
    """The name of a bag for the mapping's ``subject``: the folder name, or the file name without ``.bag``."""
    p = Path(path)
    return p.stem if p.suffix == ".bag" else p.name


def _bag_path(path: PathLike) -> Path:
    """A rosbag2 storage file (``.mcap``, ``.db3``) beside its ``metadata.yaml`` means its folder."""
    p = Path(path)
    if p.is_file() and p.suffix in (".mcap", ".db3") and (p.parent / "metadata.yaml").is_file():
        return p.parent
    return p


def _type_name(node: tuple[int, Any]) -> str:
    kind, arg = node
    if kind == _BASE:
        return str(arg[0])
    if kind == _NAME:
        return str(arg)
    inner = _type_name(arg[0])
    return f"{inner}[{arg[1]}]" if kind == _ARRAY else f"{inner}[]"


def check_field(fielddefs: dict[str, Any], msgtype: str, path: FieldPath) -> None:
    """Check that ``path`` leads to a number (or, with an angle, to a quaternion) on ``msgtype``.

    Raises ValueError with the reason (the field that does not exist and the fields
    that do; a non-numeric field and its type; a missing index; an angle not on a quaternion).
    """
    node: tuple[int, Any] = (_NAME, msgtype)
    walked = ""
    for step in path.steps:
        kind, arg = node
        if isinstance(step, str):
            if kind != _NAME:
                raise ValueError(f"'{walked}' is {_type_name(node)}, it has no field '{step}'")
            fields = dict(fielddefs[arg][1])
            if step not in fields:
                raise ValueError(f"{arg} has no field '{step}'" + (f" at '{walked}'" if walked else "")
                                 + f" (its fields: {', '.join(fields) or 'none'})")
            node = fields[step]
            walked = f"{walked}.{step}" if walked else step
        else:
            if kind not in (_ARRAY, _SEQUENCE):
                raise ValueError(f"'{walked}' is {_type_name(node)}, not an array: it has no element [{step}]")
            if kind == _ARRAY and step >= arg[1]:
                raise ValueError(f"'{walked}' has {arg[1]} elements, no element [{step}]")
            node = arg[0]
            walked = f"{walked}[{step}]"
    kind, arg = node
    if path.angle is not None:
        if kind != _NAME or [n for n, _ in fielddefs[arg][1]] != ["x", "y", "z", "w"]:
            raise ValueError(f"@{path.angle} needs a quaternion (x, y, z, w); '{walked}' is {_type_name(node)}")
        return
    if kind == _BASE and arg[0] not in _NUMERIC:
        raise ValueError(f"'{walked}' is not numeric (it is a {arg[0]})")
    if kind == _NAME:
        names = ", ".join(n for n, _ in fielddefs[arg][1])
        raise ValueError(f"'{walked}' is a message ({arg}), not a number; pick one of its fields: {names}")
    if kind in (_ARRAY, _SEQUENCE):
        raise ValueError(f"'{walked}' is an array ({_type_name(node)}); pick an element, e.g. {walked}[0]")


def _getter(path: FieldPath) -> Callable[[Any], Any]:
    """A function message → the field's value (a quaternion → its (x, y, z, w))."""
    getters: list[Callable[[Any], Any]] = []
    attrs: list[str] = []
    for step in path.steps:
        if isinstance(step, str):
            attrs.append(step)
            continue
        if attrs:
            getters.append(operator.attrgetter(".".join(attrs)))
            attrs = []
        getters.append(operator.itemgetter(step))
    if attrs:
        getters.append(operator.attrgetter(".".join(attrs)))
    if path.angle is not None:
        getters.append(operator.attrgetter("x", "y", "z", "w"))
    if len(getters) == 1:
        return getters[0]

    def get(msg: Any) -> Any:
        for g in getters:
            msg = g(msg)
        return msg

    return get


def _has_header(fielddefs: dict[str, Any], msgtype: str) -> bool:
    fields = dict(fielddefs[msgtype][1])
    node = fields.get("header")
    if node is None or node[0] != _NAME:
        return False
    stamp = dict(fielddefs[node[1]][1]).get("stamp")
    return stamp is not None and stamp[0] == _NAME


class _TopicReader:
    """The channels of one topic: checks, per-message extraction, the series."""

    def __init__(self, topic: str, channels: list[ChannelSource], msgtype: str, fielddefs: dict[str, Any],
                 use_header: bool, bag: str) -> None:
        self.topic, self.channels, self.bag, self.msgtype = topic, channels, bag, msgtype
        for c in channels:
            try:
                check_field(fielddefs, msgtype, c.path)
            except ValueError as exc:
                raise DataFormatError(f"topic {topic} ({msgtype}): {exc}", path=bag, field=c.label) from None
        self.use_header = use_header and _has_header(fielddefs, msgtype)
        self.getters = [_getter(c.path) for c in channels]
        self.times: list[int] = []
        self.rows: list[list[Any]] = []

    def add(self, msg: Any, receive_ns: int) -> None:
        if self.use_header:
            stamp = msg.header.stamp
            self.times.append(int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec))
        else:
            self.times.append(receive_ns)
        try:
            self.rows.append([g(msg) for g in self.getters])
        except IndexError:
            for c, g in zip(self.channels, self.getters):
                try:
                    g(msg)
                except IndexError:
                    ns = self.times[-1]
                    raise DataFormatError(f"topic {self.topic}: the message stamped {ns // 10**9}.{ns % 10**9:09d} s "
                                          f"has no element for '{c.path.text}'", path=self.bag, field=c.label) from None
            raise

    def series(self, t0_ns: int) -> TopicSeries:
        ns = np.asarray(self.times, dtype=np.int64)
        if self.use_header and ns.size and (ns <= 0).any():
            raise DataFormatError(f"topic {self.topic}: header stamps are zero (not set by the publisher); "
                                  "map it with time = \"receive\"", path=self.bag)
        cols: list[np.ndarray] = []
        angle: list[bool] = []
        for j, c in enumerate(self.channels):
            if c.path.angle is not None:
                q = np.array([r[j] for r in self.rows], dtype=float).reshape(-1, 4)
                cols.append(quaternion_angles(q, c.path.angle))
                angle.append(True)
            else:
                cols.append(np.array([r[j] for r in self.rows], dtype=float).reshape(-1))
                angle.append(False)
        values = np.stack(cols, axis=1) if cols else np.zeros((len(ns), 0))
        order = np.argsort(ns, kind="stable")
        ns, values = ns[order], values[order]
        first = np.concatenate([[True], np.diff(ns) > 0]) if ns.size else np.zeros(0, dtype=bool)
        return TopicSeries(self.topic, (ns[first] - t0_ns) * 1e-9, values[first], np.array(angle, dtype=bool))


def read_bag(path: PathLike, mapping: BagMapping, *, progress: bool = True) -> tuple[list[TopicSeries], int]:
    """Read the mapped channels of one bag: (one series per mapped topic, messages read).

    Times are seconds from the earliest mapped sample. Raises :class:`DataFormatError`
    for a bag that cannot be read, a missing topic, a field path that is not on the
    message type or not numeric.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    bag = str(path)
    p = _bag_path(path)
    if not p.exists():
        raise DataFormatError("no such bag (a rosbag2 folder or a ROS 1 .bag file)", path=bag)
    by_topic: dict[str, list[ChannelSource]] = {}
    for c in mapping.channels:
        by_topic.setdefault(c.topic, []).append(c)
    try:
        with AnyReader([p], default_typestore=get_typestore(Stores.LATEST)) as reader:
            topics = reader.topics
            missing = [t for t in by_topic if t not in topics]
            if missing:
                c = by_topic[missing[0]][0]
                raise DataFormatError(f"topic {missing[0]} is not in the bag (it has: "
                                      f"{', '.join(sorted(topics)) or 'no topics'})", path=bag, field=c.label)
            fielddefs = reader.typestore.fielddefs
            readers: dict[int, _TopicReader] = {}
            per_topic: dict[str, _TopicReader] = {}
            for conn in reader.connections:
                if conn.topic not in by_topic:
                    continue
                tr = per_topic.get(conn.topic)
                if tr is not None and tr.msgtype != conn.msgtype:
                    raise DataFormatError(f"topic {conn.topic} has messages of two types ({tr.msgtype}, "
                                          f"{conn.msgtype})", path=bag, field=tr.channels[0].label)
                if tr is None:
                    tr = _TopicReader(conn.topic, by_topic[conn.topic], conn.msgtype, fielddefs,
                                      mapping.time == "header", bag)
                    per_topic[conn.topic] = tr
                readers[conn.id] = tr
            conns = [c for c in reader.connections if c.id in readers]
            total = sum(c.msgcount for c in conns)
            from learning.progress import progress_bar

            count = 0
            with progress_bar(total=total, enabled=progress, desc=bag_name(p), unit="msg", unit_scale=True,
                              leave=False) as bar:
                deserialize = reader.deserialize
                for conn, ns, raw in reader.messages(connections=conns):
                    readers[conn.id].add(deserialize(raw, conn.msgtype), ns)
                    count += 1
                    if count % _PROGRESS_EVERY == 0:
                        bar.update(_PROGRESS_EVERY)
                bar.update(count % _PROGRESS_EVERY)
    except DataFormatError:
        raise
    except Exception as exc:  # noqa: BLE001  (rosbags, sqlite, mcap, zstd: any failure means unreadable)
        reason = " ".join(str(exc).split())  # one line, whatever the library's message looks like
        raise DataFormatError(f"cannot read the bag ({type(exc).__name__}: {reason})", path=bag) from None
    for topic, tr in per_topic.items():
        if not tr.times:
            raise DataFormatError(f"topic {topic} has no messages", path=bag, field=tr.channels[0].label)
    t0 = min(min(tr.times) for tr in per_topic.values())
    try:
        return [per_topic[t].series(t0) for t in mapping.topics], count
    except DataFormatError:
        raise
    except (TypeError, ValueError) as exc:  # a value that is not a number, whatever its declared type
        raise DataFormatError(f"a mapped field is not numeric ({exc})", path=bag) from None


def import_bags(bags: Sequence[PathLike], mapping: BagMapping, *, rate_hz: float = 100.0, max_gap: float = 0.1,
                on_gap: str = "error", progress: bool = True) -> BagImport:
    """Read every bag, put it on the grid and return the validated data set (module docstring).

    One bag gives one trial, or one per stretch between gaps with ``on_gap="split"``;
    trial ids count from 0 in the order of ``bags``; subjects come from the mapping.
    """
    if not bags:
        raise ValueError("no bags given")
    t_start = _time.perf_counter()
    trials: list[Trial] = []
    per_bag: dict[str, int] = {}
    messages = 0
    kinds = {kind: [i for i, c in enumerate(mapping.channels) if c.kind == kind]
             for kind in ("obs", "act", "voluntary")}
    for path in bags:
        bag = str(path)
        series, n = read_bag(path, mapping, progress=progress)
        subject = mapping.subject_for(bag_name(_bag_path(path)))
        messages += n
        segments = regrid(series, rate_hz, max_gap=max_gap, on_gap=on_gap, path=bag,
                          time_origin="from the bag's first mapped message")
        per_bag[bag] = len(segments)
        first = len(trials)
        for seg in segments:
            # the channels in the mapping's order: topic by topic, column by column
            cursor = {t: 0 for t in seg.columns}
            cols: list[np.ndarray] = []
            for c in mapping.channels:
                cols.append(seg.columns[c.topic][:, cursor[c.topic]])
                cursor[c.topic] += 1
            x = np.stack(cols, axis=1)
            trials.append(Trial(obs=x[:, kinds["obs"]], act=x[:, kinds["act"]], t=seg.t, trial_id=len(trials),
                                subject=subject,
                                voluntary=x[:, kinds["voluntary"]] if kinds["voluntary"] else None))
        # checked bag by bag, so that a message (a NaN in a field, say) names the bag
        Demonstrations(trials[first:], float(rate_hz), mapping.names("obs"), mapping.names("act"),
                       mapping.names("voluntary")).validate(bag)
    demos = Demonstrations(trials, float(rate_hz), mapping.names("obs"), mapping.names("act"),
                           mapping.names("voluntary"))
    demos.validate()
    return BagImport(demos, messages, _time.perf_counter() - t_start, per_bag)
