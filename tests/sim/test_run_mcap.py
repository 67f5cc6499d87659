"""A closed-loop run as MCAP: read back with mcap's own reader and checked against the run file."""

import json
from collections import defaultdict

import numpy as np
import pytest
from mcap.reader import make_reader
from scipy.spatial.transform import Rotation

from learning.data.mapping import quaternion_angles
from sim.closed_loop import Episode, run_episode
from sim.demonstrator import OBS_NAMES, generate_demonstrations
from sim.run_mcap import SCHEMAS, TOPICS, fork_poses, write_run_mcap

from .controllers import IdleController, OracleController


@pytest.fixture(scope="module")
def trial():
    return generate_demonstrations(n_subjects=1, minutes=0.1, seed=11).trials[0]


@pytest.fixture(scope="module")
def run_file(trial, tmp_path_factory):
    ep = run_episode(OracleController(trial.act[:, :3]), trial, duration_s=1.5, seed=1)
    return ep.save(tmp_path_factory.mktemp("mcap") / "oracle.npz")


def _read(path):
    """{topic: [(log_time, publish_time, message dict)]}, {topic: (schema name, schema, encoding)}, metadata."""
    messages, schemas = defaultdict(list), {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, msg in reader.iter_messages(log_time_order=True):
            messages[channel.topic].append((msg.log_time, msg.publish_time, json.loads(msg.data)))
            schemas[channel.topic] = (schema.name, json.loads(schema.data), schema.encoding, channel.message_encoding)
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    return messages, schemas, metadata


def _ns(stamp):
    return stamp["sec"] * 1_000_000_000 + stamp["nsec"]


def test_mcap_run_matches_the_run_file(trial, run_file, tmp_path):
    ep = Episode.load(run_file)  # the file written by the loop, read back: what a user converts
    fork = fork_poses(trial, OBS_NAMES)
    path = write_run_mcap(ep, tmp_path / "oracle.mcap", fork=fork, start_ns=5_000_000_000)
    messages, schemas, metadata = _read(path)
    nc, n_phys = len(ep.t), len(ep.t_physics)
    assert nc == 150 and n_phys == 1500

    # schemas: Foxglove's for poses, transforms and logs; JSON messages
    assert set(messages) == set(TOPICS)
    for topic, (name, schema, encoding, msg_encoding) in schemas.items():
        assert name == TOPICS[topic] and schema == SCHEMAS[name]
        assert encoding == "jsonschema" and msg_encoding == "json"
    # counts: every control step on the control topics, every physics step on the joint states
    for topic in ("/knife/tip", "/knife/reference", "/wearer/intent", "/fork/pose", "/tf", "/wearer/shoulder",
                  "/control/arbitration", "/control/status", "/control/timing"):
        assert len(messages[topic]) == nc, topic
    assert len(messages["/arm/joint_states"]) == n_phys
    assert len(messages["/control/log"]) == 1 and messages["/control/log"][0][2]["message"] == "status: ok"

    # times: log = publish = header timestamp = start + the run file's time
    want_c = 5_000_000_000 + np.round(ep.t * 1e9).astype(np.int64)
    for topic, rows in messages.items():
        for log, pub, msg in rows:
            assert log == pub == _ns(msg["timestamp"]), topic
    np.testing.assert_array_equal([r[0] for r in messages["/knife/tip"]], want_c)
    np.testing.assert_array_equal([r[0] for r in messages["/arm/joint_states"]],
                                  5_000_000_000 + np.round(ep.t_physics * 1e9).astype(np.int64))

    # values, exactly as in the run file (JSON keeps every bit of a float64)
    def xyz(topic):
        return np.array([[m["pose"]["position"][a] for a in "xyz"] for _, _, m in messages[topic]])

    np.testing.assert_array_equal(xyz("/knife/tip"), ep.tip)
    np.testing.assert_array_equal(xyz("/knife/reference"), ep.tip_reference)
    np.testing.assert_array_equal(xyz("/wearer/intent"), ep.tip_intent)
    np.testing.assert_array_equal(xyz("/fork/pose"), fork[:nc, :3])
    assert {m["frame_id"] for _, _, m in messages["/knife/tip"]} == {"plate"}
    quat = np.array([[m["pose"]["orientation"][a] for a in "xyzw"] for _, _, m in messages["/fork/pose"]])
    for j, angle in enumerate(("roll", "pitch", "yaw")):
        np.testing.assert_allclose(quaternion_angles(quat, angle), np.angle(np.exp(1j * fork[:nc, 3 + j])),
                                   atol=1e-9)
    joints = [m for _, _, m in messages["/arm/joint_states"]]
    np.testing.assert_array_equal([m["position"] for m in joints], ep.q)
    np.testing.assert_array_equal([m["velocity"] for m in joints], ep.v)
    np.testing.assert_array_equal([m["effort"] for m in joints], ep.tau)
    np.testing.assert_array_equal([m["position"] for _, _, m in messages["/wearer/shoulder"]], ep.voluntary)
    arb = [m for _, _, m in messages["/control/arbitration"]]
    np.testing.assert_array_equal([m["alpha"] for m in arb], ep.alpha)
    np.testing.assert_array_equal([m["beta"] for m in arb], ep.beta)
    np.testing.assert_array_equal([m["mode"] for m in arb], ep.mode)
    assert all(m["novelty"] is None for m in arb)  # NaN in the run file: null in JSON
    assert [m["status"] for _, _, m in messages["/control/status"]] == list(ep.status)
    np.testing.assert_allclose([m["step_time_ms"] for _, _, m in messages["/control/timing"]], ep.step_time * 1e3,
                               rtol=1e-15)
    tf = [m for _, _, m in messages["/tf"]]
    assert {(m["parent_frame_id"], m["child_frame_id"]) for m in tf} == {("plate", "torso")}
    R = Rotation.from_quat([[m["rotation"][a] for a in "xyzw"] for m in tf]).as_matrix()
    np.testing.assert_allclose(R, ep.base_pose[:, :3, :3], atol=1e-12)
    np.testing.assert_array_equal([[m["translation"][a] for a in "xyz"] for m in tf], ep.base_pose[:, :3, 3])
    assert metadata["mpcshare.run"]["limit_violations"] == "0" and metadata["mpcshare.run"]["trial_id"] == "0"


def test_steps_without_a_reference_and_without_fork(trial, tmp_path):
    ep = run_episode(IdleController(), trial, duration_s=0.3, seed=0)
    messages, _, _ = _read(write_run_mcap(ep, tmp_path / "recorded.mcap", joint_stride=10))
    assert len(messages["/fork/pose"]) == 30  # the run file's own fork_pose by default
    ep.fork_pose = None  # an older run file
    messages, _, _ = _read(write_run_mcap(ep, tmp_path / "idle.mcap", joint_stride=10))
    assert "/knife/reference" not in messages and "/fork/pose" not in messages  # NaN reference: left out
    assert len(messages["/knife/tip"]) == 30 and len(messages["/arm/joint_states"]) == 30
    np.testing.assert_array_equal([m["position"] for _, _, m in messages["/arm/joint_states"]], ep.q[::10])


def test_bad_arguments(trial, run_file, tmp_path):
    ep = Episode.load(run_file)
    with pytest.raises(ValueError, match="must end in .mcap"):
        write_run_mcap(ep, tmp_path / "run.npz")
    with pytest.raises(ValueError, match="fork must be"):
        write_run_mcap(ep, tmp_path / "run.mcap", fork=np.zeros((3, 6)))
    assert not (tmp_path / "run.mcap").exists()
    assert fork_poses(trial, ["a", "b"]) is None
