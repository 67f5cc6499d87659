"""``mpcshare import``: bags in, a data set out; bad input is one line on stderr, exit status 1 and no file."""

import re

import numpy as np
import pytest

from learning.data import load
from mpcshare.cli import main
from tests.learning.bags import MAPPING_TOML, TOPICS, TopicPlan, write_bag


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli_bags")
    write_bag(d / "s1_mcap", storage="mcap", seed=3)
    write_bag(d / "s2_sqlite", storage="sqlite3", seed=4)
    write_bag(d / "s1_gap", storage="mcap", seed=5, gap=("/shoulder", 1.5, 1.8))
    write_bag(d / "s7_zero", storage="mcap", seed=6, zero_stamps=True)
    apart = dict(TOPICS)
    apart["/fork/pose"] = TopicPlan("geometry_msgs/msg/PoseStamped", 120.0, 0.0, 0.002, stop_s=1.0)
    apart["/knife/pose"] = TopicPlan("geometry_msgs/msg/PoseStamped", 90.0, 2.0, 0.002)
    write_bag(d / "s8_apart", storage="sqlite3", seed=7, topics=apart)
    (d / "s9_broken.bag").write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 4)
    (d / "s6_garbage").mkdir()
    (d / "s6_garbage" / "metadata.yaml").write_text("rosbag2_bagfile_information: [not, a, bag\n")
    (d / "map.toml").write_text(MAPPING_TOML)
    return d


def _map(folder, old: str, new: str):
    text = MAPPING_TOML.replace(old, new)
    assert text != MAPPING_TOML
    path = folder / f"map_{abs(hash(new))}.toml"
    path.write_text(text)
    return path


def test_import_writes_a_usable_data_set(bags, tmp_path, capsys):
    out = tmp_path / "demos.npz"
    rc = main(["import", str(bags / "s1_mcap"), str(bags / "s2_sqlite"), "--mapping", str(bags / "map.toml"),
               "--out", str(out), "--no-progress"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "2 trial(s) from 2 bag(s)" in printed and "msg/s" in printed and "knife_x" in printed
    demos = load(out)
    assert demos.trial_ids == [0, 1] and demos.subjects == [1, 2] and demos.rate_hz == 100.0
    assert demos.has_voluntary and demos.vol_names == ["shoulder_elevation", "shoulder_protraction"]
    assert main(["inspect", str(out)]) == 0
    assert list(tmp_path.iterdir()) == [out]  # no temporary files left


def test_rate_and_split_options(bags, tmp_path, capsys):
    out = tmp_path / "demos.npz"
    rc = main(["import", str(bags / "s1_gap"), "--mapping", str(bags / "map.toml"), "--out", str(out),
               "--rate", "50", "--on-gap", "split", "--no-progress"])
    assert rc == 0
    assert "split at gaps" in capsys.readouterr().out
    demos = load(out)
    assert len(demos) == 2 and demos.rate_hz == 50.0
    np.testing.assert_allclose(np.diff(demos[0].t), 0.02, atol=1e-9)


def test_csv_output(bags, tmp_path):
    out = tmp_path / "csv"
    assert main(["import", str(bags / "s1_mcap"), "--mapping", str(bags / "map.toml"), "--out", str(out),
                 "--no-progress"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["trial_000.csv"]


CASES = {
    "topic not in the bag": (
        "s1_mcap", ("/fork/wrench wrench.force.x", "/fork/wrenc wrench.force.x"),
        r"field '\[obs\] fork_fx': topic /fork/wrenc is not in the bag \(it has: /camera/info, /fork/pose, "
        r"/fork/wrench, /knife/pose, /shoulder\)"),
    "field not on the message type": (
        "s1_mcap", ("pose.position.y", "pose.positon.y"),
        r"'\[obs\] fork_y': topic /fork/pose \(geometry_msgs/msg/PoseStamped\): geometry_msgs/msg/Pose has no "
        r"field 'positon' at 'pose' \(its fields: position, orientation\)"),
    "non-numeric field": (
        "s1_mcap", ("/knife/pose pose.position.x", "/knife/pose header.frame_id"),
        r"'\[act\] knife_x': .*'header.frame_id' is not numeric \(it is a string\)"),
    "a message, not a number": (
        "s1_mcap", ("pose.position.z", "pose.position"),
        r"'pose.position' is a message \(geometry_msgs/msg/Point\), not a number; pick one of its fields: x, y, z"),
    "an array without an index": (
        "s1_mcap", ("position[1]", "position"), r"'position' is an array \(float64\[\]\); pick an element"),
    "an angle of something else": (
        "s1_mcap", ("orientation@pitch", "position@pitch"), r"@pitch needs a quaternion"),
    "an element past the end": (
        "s1_mcap", ("position[1]", "position[7]"),
        r"'\[voluntary\] shoulder_protraction': topic /shoulder: the message stamped 1700000000\.000000000 s "
        r"has no element for 'position\[7\]'"),
    "empty overlap": (
        "s8_apart", None, r"s8_apart: empty overlap: no time at which every mapped topic has data \(/fork/pose ends at "
                       r"t = 0\.99\d s, /knife/pose starts at t = 2\.000 s\)"),
    "a gap": ("s1_gap", None, r"s1_gap: gap in topic /shoulder: no message for 0\.3\d\d s after t = 1\.4\d\d s"),
    "zero header stamps": ("s7_zero", None, r"s7_zero: topic /fork/pose: header stamps are zero .*time = \"receive\""),
    "unreadable ROS 1 bag": ("s9_broken.bag", None, r"s9_broken.bag: cannot read the bag \("),
    "unreadable rosbag2 folder": ("s6_garbage", None, r"s6_garbage: cannot read the bag \("),
    "no such bag": ("nothing_here", None, r"nothing_here: no such bag"),
    "mapping not TOML": ("s1_mcap", ("[obs]", "[obs"), r"map_\d+\.toml: not valid TOML"),
    "mapping without [act]": ("s1_mcap", ("[act]", "[action]"), r"field 'action': unknown key"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_bad_input_is_one_line_and_no_file(bags, tmp_path, capsys, case):
    bag, edit, message = CASES[case]
    mapping = bags / "map.toml" if edit is None else _map(tmp_path, *edit)
    out = tmp_path / "out" / "demos.npz"
    rc = main(["import", str(bags / bag), "--mapping", str(mapping), "--out", str(out), "--no-progress"])
    err = capsys.readouterr().err
    assert rc == 1
    assert err.startswith("mpcshare import: ") and err.count("\n") == 1, err
    assert re.search(message, err), err
    assert not out.exists() and not out.parent.exists()
