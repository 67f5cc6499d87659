"""DDS transport for ``mpcshare run``: one participant, ROS 2-named topics, readers and writers (Cyclone DDS).

The participant's network is :class:`NetworkSettings` (default: loopback only, multicast off,
discovery by unicast to 127.0.0.1), turned into Cyclone DDS's XML by :func:`cyclone_config`. A
``CYCLONEDDS_URI`` in the environment replaces it (the user's own Cyclone configuration, as for
any ROS 2 node with ``rmw_cyclonedds_cpp``). Cyclone binds its unicast receive sockets to the
wildcard address whatever the interface (``ddsi_udp.c``); it advertises, sends to and accepts
discovery from the configured interface and peers only.

QoS: readers default to best effort (they match both reliable and best-effort ROS 2 publishers,
e.g. the sensor-data profile), writers to reliable (matched by ROS 2's default subscribers);
history keep-last ``depth``; volatile durability. :meth:`Writer.write_cdr` sends a sample already serialised
(XCDR1 with its encapsulation header, e.g. by rosbags' ROS 2 CDR serialiser, faster than Cyclone's Python one).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Generic, TypeVar
from xml.sax.saxutils import quoteattr

from cyclonedds.core import InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.internal import InvalidSample
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from mpcshare.runtime.messages import dds_topic

try:  # what DataWriter.write itself sends its serialised sample with
    from cyclonedds._clayer import ddspy_write as _write_serialized
except ImportError:  # pragma: no cover - another cyclonedds layout: Writer.write_cdr deserialises, then writes
    _write_serialized = None

__all__ = ["RELIABILITIES", "NetworkSettings", "QosSettings", "Reader", "Transport", "Writer", "cyclone_config"]

#: The reliability a reader or writer can ask for.
RELIABILITIES: tuple[str, ...] = ("best_effort", "reliable")

M = TypeVar("M", bound=IdlStruct)


@dataclass(frozen=True)
class NetworkSettings:
    """Where the participant talks: ``interface`` (this computer's address on that network), unicast
    ``peers`` (addresses of the other computers; 127.0.0.1 for this one), ``multicast`` (False: discovery
    by unicast to the peers only), ``domain_id`` (ROS_DOMAIN_ID, 0–232)."""

    interface: str = "127.0.0.1"
    peers: tuple[str, ...] = ("127.0.0.1",)
    multicast: bool = False
    domain_id: int = 0


@dataclass(frozen=True)
class QosSettings:
    """A reader's or writer's QoS: reliability (:data:`RELIABILITIES`), keep-last depth (≥ 1)."""

    reliability: str = "best_effort"
    depth: int = 1

    def qos(self) -> Qos:
        """The Cyclone DDS QoS."""
        rel = Policy.Reliability.Reliable(0) if self.reliability == "reliable" else Policy.Reliability.BestEffort
        return Qos(rel, Policy.History.KeepLast(self.depth), Policy.Durability.Volatile)


def cyclone_config(net: NetworkSettings) -> str:
    """Cyclone DDS's XML configuration of ``net`` (module docstring)."""
    peers = "".join(f"<Peer address={quoteattr(p)}/>" for p in net.peers)
    return ('<CycloneDDS xmlns="https://cdds.io/config"><Domain id="any"><General><Interfaces>'
            f'<NetworkInterface address={quoteattr(net.interface)}/></Interfaces>'
            f'<AllowMulticast>{"true" if net.multicast else "false"}</AllowMulticast></General>'
            f'<Discovery><Peers>{peers}</Peers><ParticipantIndex>auto</ParticipantIndex>'
            '<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex></Discovery></Domain></CycloneDDS>')


class Reader(Generic[M]):
    """The samples of one topic: :meth:`take` returns the valid samples received since the last call."""

    def __init__(self, reader: DataReader, topic: str) -> None:
        self._reader, self.topic = reader, topic
        self._waitset: WaitSet | None = None

    def take(self, limit: int = 64) -> list[M]:
        """Up to ``limit`` new samples, oldest first (disposals and other non-data samples skipped)."""
        return [s for s in self._reader.take(N=limit) if not isinstance(s, InvalidSample)]

    def wait(self, timeout_s: float) -> bool:
        """Block up to ``timeout_s`` until a sample is ready to take; True when one is."""
        if self._waitset is None:
            self._waitset = WaitSet(self._reader.participant)
            self._waitset.attach(ReadCondition(self._reader, SampleState.Any | ViewState.Any | InstanceState.Any))
        return self._waitset.wait(max(0, int(timeout_s * 1e9))) > 0

    @property
    def matched(self) -> int:
        """How many writers are matched now."""
        return len(self._reader.get_matched_publications())


class Writer(Generic[M]):
    """Publishes one topic."""

    def __init__(self, writer: DataWriter, topic: str) -> None:
        self._writer: DataWriter | None = writer
        self.topic = topic

    def write_cdr(self, data: bytes) -> None:
        """Send a sample of the topic's type given as its XCDR1 bytes (encapsulation header included), as
        :meth:`write` would send it; RuntimeError after :meth:`close` or for a DDS error."""
        if self._writer is None:
            raise RuntimeError(f"the writer of {self.topic} is closed")
        if _write_serialized is None:  # pragma: no cover
            self._writer.write(self._writer.data_type.deserialize(data))
            return
        if _write_serialized(self._writer._ref, data.ljust((len(data) + 3) & ~3, b"\0")) < 0:
            raise RuntimeError(f"the writer of {self.topic} failed to send a serialised sample")

    def write(self, message: M) -> None:
        """Send ``message``; RuntimeError after :meth:`close`."""
        if self._writer is None:
            raise RuntimeError(f"the writer of {self.topic} is closed")
        self._writer.write(message)

    def close(self) -> None:
        """Delete the DDS writer (its readers see it leave; as a publisher whose process ended)."""
        self._writer = None  # the only reference: Cyclone deletes the entity when it is freed

    def flush(self, timeout_s: float = 0.1) -> bool:
        """Wait up to ``timeout_s`` for the reliable readers to acknowledge; True when they all did."""
        return self._writer is not None and bool(self._writer.wait_for_acks(int(timeout_s * 1e9)))

    @property
    def matched(self) -> int:
        """How many readers are matched now."""
        return 0 if self._writer is None else len(self._writer.get_matched_subscriptions())


class Transport:
    """One DDS participant (module docstring); ``net`` None: :class:`NetworkSettings` defaults.

    Cyclone DDS configures a domain once per process: the first :class:`Transport` of a domain id
    sets its network, later ones in the same process share it.
    """

    _domains: dict[int, Domain] = {}

    def __init__(self, net: NetworkSettings | None = None) -> None:
        self.net = net = net or NetworkSettings()
        self.user_config = bool(os.environ.get("CYCLONEDDS_URI"))
        if not self.user_config and net.domain_id not in Transport._domains:
            Transport._domains[net.domain_id] = Domain(net.domain_id, cyclone_config(net))
        self.participant = DomainParticipant(net.domain_id)
        self._topics: dict[str, Topic] = {}

    def _topic(self, ros_topic: str, message: type[M]) -> Topic:
        name = dds_topic(ros_topic)
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, message)
        return self._topics[name]

    def reader(self, ros_topic: str, message: type[M], qos: QosSettings | None = None) -> Reader[M]:
        """A reader of ``ros_topic`` (``/name``) carrying ``message``."""
        qos = qos or QosSettings()
        return Reader(DataReader(self.participant, self._topic(ros_topic, message), qos=qos.qos()), ros_topic)

    def writer(self, ros_topic: str, message: type[M], qos: QosSettings | None = None) -> Writer[M]:
        """A writer of ``ros_topic`` carrying ``message`` (reliable by default)."""
        qos = qos or QosSettings("reliable", 1)
        return Writer(DataWriter(self.participant, self._topic(ros_topic, message), qos=qos.qos()), ros_topic)
