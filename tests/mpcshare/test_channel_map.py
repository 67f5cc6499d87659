"""The channel map: parsing ``--map``, the map ``sim`` applies, and what keeps channels from the simulator."""

import pytest

from learning.data import Demonstrations
from mpcshare.channel_map import bundle_map, parse_map, simulator_gaps, simulator_line
from sim.demonstrator import ACT_NAMES, OBS_NAMES, VOL_NAMES

OBS, ACT, VOL = list(OBS_NAMES), list(ACT_NAMES), list(VOL_NAMES)


def test_parse_map():
    assert parse_map(["knife_x=u0", "fork_x=obs:o1"]) == {"knife_x": "u0", "fork_x": "obs:o1"}
    for bad, match in ((["knife_x"], "expected NAME=CHANNEL"), (["=u0"], "expected"), (["a=b", "a=c"], "twice")):
        with pytest.raises(ValueError, match=match):
            parse_map(bad)


def test_the_project_channels_drive_the_simulator_with_any_shoulder():
    for vol in (VOL, VOL[:2], ["imu"], [], ["temperature", "shoulder_abduction", "x", "y"]):
        assert simulator_gaps(OBS, ACT, vol, 100.0) == []
    assert simulator_line(OBS, ACT, VOL[:2]) == ("yes (knife tip knife_x, knife_y, knife_z; fork pose; shoulder "
                                                 "shoulder_elevation, shoulder_protraction)")
    assert "fork position (a level fork); no shoulder" in simulator_line(OBS[:3], ACT, [])


@pytest.mark.parametrize("obs, act, vol, rate, expected", [
    ([f"o{i}" for i in range(9)], [f"u{i}" for i in range(9)], [], 100.0,
     ["knife_x=CHANNEL knife_y=CHANNEL knife_z=CHANNEL", "fork_x=CHANNEL fork_y=CHANNEL fork_z=CHANNEL"]),
    (OBS, ["tip_x", "tip_y", "tip_z"], VOL, 100.0, ["--map knife_x=tip_x knife_y=tip_y knife_z=tip_z"]),
    (OBS[:4], ACT, VOL, 100.0, ["the fork's angles lack fork_pitch, fork_yaw"]),
    (OBS, ACT, ["a", "b", "c", "d"], 100.0, ["4 shoulder channels"]),
    (OBS, ACT, VOL, 50.0, ["sampled at 50 Hz, the simulator runs at 100 Hz"]),
])
def test_each_gap_says_why_and_how(obs, act, vol, rate, expected):
    gaps = simulator_gaps(obs, act, vol, rate)
    assert len(gaps) == len(expected)
    for gap, text in zip(gaps, expected):
        assert text in gap
    assert simulator_line(obs, act, vol, rate).startswith("no: ")


def test_sim_applies_the_recorded_map_to_data_named_as_the_training_data():
    demos = Demonstrations([], 100.0, ["fk_x", "o1"], ["blade_x"], [])
    recorded = {"knife_x": "blade_x", "fork_x": "obs:fk_x", "fork_y": "gone"}
    assert bundle_map(recorded, demos, {}) == {"knife_x": "blade_x", "fork_x": "obs:fk_x"}
    assert bundle_map(recorded, demos, {"fork_x": "o1"}) == {"knife_x": "blade_x", "fork_x": "o1"}
    assert bundle_map(recorded, Demonstrations([], 100.0, ["fork_x"], ["blade_x"], []), {}) == {"knife_x": "blade_x"}
