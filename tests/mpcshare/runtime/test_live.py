"""The live view: a Foxglove server on 127.0.0.1 and the run files' MCAP channels recorded (needs foxglove-sdk)."""

from __future__ import annotations

import importlib.util
import socket
import sys
from types import SimpleNamespace

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.well_known import MessageEncoding

from mpcshare.runtime.live import LiveView
from robot.default_arm import as_description
from sim.run_mcap import TOPICS

needs_foxglove = pytest.mark.skipif(importlib.util.find_spec("foxglove") is None,
                                    reason="the live view needs foxglove-sdk (pip install 'mpcshare[live]')")


def test_without_foxglove_the_live_view_says_what_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "foxglove", None)  # as if not installed
    with pytest.raises(RuntimeError, match=r"needs the foxglove-sdk package \(pip install 'mpcshare\[live\]'\)"):
        LiveView(tmp_path / "x.mcap", as_description(None), ["a"])
    assert not (tmp_path / "x.mcap").exists()


@needs_foxglove
def test_the_live_view_serves_on_loopback_and_records_the_run_channels(tmp_path):
    import json

    import mujoco

    from sim.scene import EatingScene, SceneConfig

    robot = as_description(None)
    world = EatingScene(SceneConfig(robot=robot), seed=0)  # the simulator's tip: the independent reference
    q = 0.5 * (robot.limits.q_min + robot.limits.q_max) + 0.1
    world.set_state(q, np.zeros(robot.n), 0.0)
    mujoco.mj_forward(world.model, world.data)
    base, expected = world.base_pose(0.0), world.tip_in_plate().copy()
    live = LiveView(tmp_path / "live.mcap", robot, ["e", "p", "a"], port=0)
    try:
        with socket.create_connection(("127.0.0.1", live.port), timeout=2):
            pass
        cmd = SimpleNamespace(tip_reference=np.array([0.1, 0.0, 0.05]), alpha=0.7, beta=0.5,
                              mode_proba=np.array([0.1, 0.9]), novelty=0.3)
        fork = {"fork_x": 0.1, "fork_y": 0.0, "fork_z": 0.02, "fork_roll": 0.0, "fork_pitch": 0.0, "fork_yaw": 0.5}
        for k in range(3):
            live.step(k * 10_000_000, q=q, v=np.zeros(3), base=base, obs=fork, voluntary=np.array([0.1, 0.2, 0.3]),
                      command=cmd, status="ok", step_time_s=0.001)
        live.step(30_000_000, q=np.full(3, np.nan), v=np.zeros(3), base=None, obs={}, voluntary=np.zeros(3),
                  command=None, status="protective_stop", step_time_s=0.0)
    finally:
        live.close()
    with open(tmp_path / "live.mcap", "rb") as f:
        got = [(ch.topic, ch.message_encoding, json.loads(m.data), m.log_time)
               for _, ch, m in make_reader(f).iter_messages()]
    topics = {t for t, *_ in got}
    assert topics <= set(TOPICS) and topics >= {"/knife/tip", "/knife/reference", "/fork/pose", "/tf",
                                                "/arm/joint_states", "/control/arbitration", "/control/status"}
    assert all(enc == MessageEncoding.JSON for _, enc, _, _ in got)
    tips = [(m, t) for topic, _, m, t in got if topic == "/knife/tip"]
    assert len(tips) == 3  # no tip without measured joints
    p = tips[0][0]["pose"]["position"]
    np.testing.assert_allclose([p["x"], p["y"], p["z"]], expected, atol=1e-6)  # base · FK(q)
    status = [m["status"] for topic, _, m, _ in got if topic == "/control/status"]
    logs = [m["message"] for topic, _, m, _ in got if topic == "/control/log"]
    assert status == ["ok"] * 3 + ["protective_stop"] and logs == ["status: ok", "status: protective_stop"]


@needs_foxglove
def test_a_foxglove_client_on_loopback_receives_the_channels_live(tmp_path):
    """A client of Foxglove's WebSocket protocol (what the Foxglove app speaks) is advertised the run channels,
    subscribes to them and receives each one's messages while the run steps."""
    import asyncio
    import json
    import struct
    import threading
    import time

    websockets = pytest.importorskip("websockets")
    robot = as_description(None)
    live = LiveView(tmp_path / "live.mcap", robot, ["e", "p", "a"], port=0)
    q = 0.5 * (robot.limits.q_min + robot.limits.q_max)
    cmd = SimpleNamespace(tip_reference=np.array([0.1, 0.0, 0.05]), alpha=0.7, beta=0.5,
                          mode_proba=np.array([0.1, 0.9]), novelty=0.3)
    fork = {"fork_x": 0.1, "fork_y": 0.0, "fork_z": 0.02, "fork_roll": 0.0, "fork_pitch": 0.0, "fork_yaw": 0.5}
    stop = threading.Event()

    def run() -> None:
        k = 0
        while not stop.is_set():
            live.step(k * 10_000_000, q=q, v=np.zeros(3), base=np.eye(4), obs=fork,
                      voluntary=np.array([0.1, 0.2, 0.3]), command=cmd, status="ok", step_time_s=0.001)
            k += 1
            time.sleep(0.01)

    async def client() -> tuple[dict, dict]:
        channels, got = {}, {}
        async with websockets.connect(f"ws://127.0.0.1:{live.port}",
                                      subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"]) as ws:
            end = time.monotonic() + 2.0
            while time.monotonic() < end:
                try:
                    msg = await asyncio.wait_for(ws.recv(), 0.5)
                except asyncio.TimeoutError:
                    continue
                if isinstance(msg, str) and json.loads(msg)["op"] == "advertise":
                    new = {c["id"]: c["topic"] for c in json.loads(msg)["channels"]}
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                        {"id": cid, "channelId": cid} for cid in new]}))
                    channels.update(new)
                elif isinstance(msg, bytes) and msg[0] == 1:  # a message: op, subscription id, log time, payload
                    sub, _ = struct.unpack_from("<IQ", msg, 1)
                    got.setdefault(channels[sub], []).append(json.loads(msg[13:]))
        return channels, got

    feeder = threading.Thread(target=run)
    feeder.start()
    try:
        channels, got = asyncio.run(client())
    finally:
        stop.set()
        feeder.join()
        live.close()
    assert set(channels.values()) <= set(TOPICS) and {"/knife/tip", "/control/status", "/fork/pose"} <= set(got)
    assert all(m["status"] == "ok" for m in got["/control/status"]) and len(got["/knife/tip"]) >= 20
