"""The DDS transport of `mpcshare run`: loopback configuration, a round trip in one process."""

from __future__ import annotations

import time

import pytest

pytest.importorskip("cyclonedds", reason="mpcshare run needs the cyclonedds package (pip install 'mpcshare[ros]')")

from mpcshare.runtime.messages import Header, JointState, Time  # noqa: E402
from mpcshare.runtime.transport import NetworkSettings, QosSettings, Transport, cyclone_config  # noqa: E402
from tests.mpcshare.runtime.ros_helpers import DOMAIN  # noqa: E402


def test_the_default_network_is_loopback_without_multicast():
    xml = cyclone_config(NetworkSettings())
    assert '<NetworkInterface address="127.0.0.1"/>' in xml
    assert "<AllowMulticast>false</AllowMulticast>" in xml
    assert '<Peers><Peer address="127.0.0.1"/></Peers>' in xml
    other = cyclone_config(NetworkSettings("192.168.1.10", ("192.168.1.2", "192.168.1.3"), True, 5))
    assert 'address="192.168.1.10"' in other and other.count("<Peer ") == 2 and ">true<" in other


def test_a_round_trip_on_loopback(monkeypatch):
    monkeypatch.delenv("CYCLONEDDS_URI", raising=False)
    a, b = Transport(NetworkSettings(domain_id=DOMAIN)), Transport(NetworkSettings(domain_id=DOMAIN))
    assert not a.user_config
    reader = b.reader("/test/round_trip", JointState, QosSettings("reliable", 10))
    writer = a.writer("/test/round_trip", JointState)
    deadline = time.monotonic() + 5.0
    while writer.matched == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert writer.matched == 1
    sent = [JointState(Header(Time(i, 7), "arm"), ["a", "b"], [0.1 * i, -1.0], [0.0, 2.0], []) for i in range(5)]
    got: list[JointState] = []
    for msg in sent:
        writer.write(msg)
        time.sleep(0.002)
    while len(got) < 5 and time.monotonic() < deadline:
        got += reader.take()
        time.sleep(0.005)
    assert [(g.header.stamp.sec, list(g.position), list(g.name)) for g in got] == \
        [(s.header.stamp.sec, list(s.position), list(s.name)) for s in sent]
    assert writer.flush(0.5)


def test_a_users_cyclonedds_uri_is_honoured(monkeypatch):
    monkeypatch.setenv("CYCLONEDDS_URI", "<CycloneDDS/>")
    assert Transport(NetworkSettings(domain_id=DOMAIN)).user_config


def test_a_sample_sent_as_its_bytes_arrives_as_the_sample(monkeypatch):
    monkeypatch.delenv("CYCLONEDDS_URI", raising=False)
    t = Transport(NetworkSettings(domain_id=DOMAIN))
    reader = t.reader("/test/write_cdr", JointState, QosSettings("reliable", 10))
    writer = t.writer("/test/write_cdr", JointState)
    deadline = time.monotonic() + 5.0
    while writer.matched == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    sent = JointState(Header(Time(3, 7), "arm"), ["a"], [0.5], [0.25], [])  # 45 bytes: padded to 48 on the wire
    writer.write_cdr(bytes(sent.serialize()))
    got: list[JointState] = []
    while not got and time.monotonic() < deadline:
        got += reader.take()
        time.sleep(0.005)
    assert got == [sent]
    writer.close()
    with pytest.raises(RuntimeError, match="the writer of /test/write_cdr is closed"):
        writer.write_cdr(bytes(sent.serialize()))
