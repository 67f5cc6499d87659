"""The channel mapping of ROS imports (learning.data.mapping): field paths, angles, tables, errors, the example."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from learning.data import DataFormatError
from learning.data.mapping import load_mapping, parse_field_path, parse_mapping, quaternion_angles


def test_quaternion_angles_are_tf2_rpy():
    rng = np.random.default_rng(0)
    rpy = np.column_stack([rng.uniform(-np.pi, np.pi, 200), rng.uniform(-1.5, 1.5, 200),
                           rng.uniform(-np.pi, np.pi, 200)])
    q = Rotation.from_euler("ZYX", rpy[:, ::-1]).as_quat() * 3.0  # not normalised: normalised first
    for j, angle in enumerate(("roll", "pitch", "yaw")):
        np.testing.assert_allclose(quaternion_angles(q, angle), rpy[:, j], atol=1e-9)


def test_field_paths():
    p = parse_field_path("poses[2].orientation@yaw")
    assert p.steps == ("poses", 2, "orientation") and p.angle == "yaw" and p.is_angle
    assert parse_field_path("position[0]").steps == ("position", 0)
    for bad in ("pose..x", "pose.x@spin", "[0]", "pose.x[a]", "1pose"):
        with pytest.raises(ValueError):
            parse_field_path(bad)


@pytest.mark.parametrize("doc, match", [
    ({"act": {"k": "/k x"}}, r"no \[obs\] table"),
    ({"obs": {}, "act": {"k": "/k x"}}, r"\[obs\].*empty"),
    ({"obs": {"f": "/f"}, "act": {"k": "/k x"}}, r"'\[obs\] f'.*two words"),
    ({"obs": {"f": "/f pose.x@spin"}, "act": {"k": "/k x"}}, r"unknown angle '@spin'"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "time": "wall"}, r"'time'.*\"header\" or \"receive\""),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "rate": 100}, r"field 'rate': unknown key"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "subject": "(("}, r"'subject': not a regular expression"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "map": {"knife_x": "nope"}}, r"'\[map\] knife_x': no channel"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x", "knife_x": "/k y"}, "map": {"knife_x": "k"}},
     r"\[act\] already has a channel 'knife_x'"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "map": {"a": "k", "b": "k"}}, r"renamed twice"),
    ({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "map": {"a": 3}}, r"'\[map\] a': expected the name"),
])
def test_mapping_errors(doc, match):
    with pytest.raises(DataFormatError, match=match):
        parse_mapping(doc, "map.toml")


def test_the_map_table_renames_channels_in_place():
    m = parse_mapping({"obs": {"f": "/f x", "g": "/f y"}, "act": {"k": "/k x"}, "voluntary": {"s": "/s position[0]"},
                       "map": {"knife_x": "k", "fork_y": "g", "shoulder_abduction": "s"}})
    assert m.names("obs") == ["f", "fork_y"] and m.names("act") == ["knife_x"]
    assert m.names("voluntary") == ["shoulder_abduction"] and m.channels[1].path.text == "y"


def test_subject_per_bag_table():
    m = parse_mapping({"obs": {"f": "/f x"}, "act": {"k": "/k x"}, "subject": {"monday": 1, "tuesday": 2}})
    assert m.subject_for("tuesday") == 2
    with pytest.raises(DataFormatError, match="bag 'friday' has no entry"):
        m.subject_for("friday")
    assert parse_mapping({"obs": {"f": "/f x"}, "act": {"k": "/k x"}}).subject_for("x") == -1


def test_the_example_mapping_names_the_channels_the_simulator_finds():
    from pathlib import Path

    from sim.demonstrator import ACT_NAMES, OBS_NAMES, VOL_NAMES

    m = load_mapping(Path(__file__).resolve().parents[3] / "examples" / "superlimb_mapping.toml")
    assert m.names("obs") == list(OBS_NAMES) and m.names("act") == list(ACT_NAMES)
    assert m.names("voluntary") == list(VOL_NAMES)
    assert m.subject_for("s2_lunch") == 2 and m.time == "header"
