"""ROS bags into a data set: real bags written with rosbags' writers (rosbag2 MCAP and sqlite3, ROS 1),
imported and compared with the analytic signals they were written from."""

from dataclasses import replace

import numpy as np
import pytest

from learning.data import DataFormatError
from learning.data.mapping import load_mapping
from learning.data.rosbag import import_bags
from tests.learning.bags import MAPPING_TOML, SIGNALS, TOPICS, write_bag

STORAGES = ("mcap", "sqlite3", "ros1")


def _bag_path(folder, name, storage):
    return folder / (f"{name}_{storage}.bag" if storage == "ros1" else f"{name}_{storage}")


N_UNMAPPED = int(np.floor(4.0 * TOPICS["/camera/info"].rate_hz))  # messages of the topic no channel maps
WRITTEN: dict[str, int] = {}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("bags")
    for storage in STORAGES:
        WRITTEN[storage] = write_bag(_bag_path(d, "s3", storage), storage=storage, seed=1)
    write_bag(d / "s5_gap", storage="mcap", seed=2, gap=("/fork/wrench", 2.0, 2.3))
    (d / "map.toml").write_text(MAPPING_TOML)
    return d


@pytest.fixture(scope="module")
def mapping(folder):
    return load_mapping(folder / "map.toml")


def _bound(channel: str) -> float:
    """Linear interpolation error bound h²/8·max|f''| with h the longest interval of the channel's topic."""
    topic = {"fork_f": "/fork/wrench", "fork": "/fork/pose", "knif": "/knife/pose", "shou": "/shoulder"}
    key = "fork_f" if channel.startswith("fork_f") else channel[:4]
    plan = TOPICS[topic[key]]
    h = 1.0 / plan.rate_hz + 2 * plan.jitter_s
    return h * h / 8 * SIGNALS[channel][1] + 1e-8  # + the stamps' rounding to 1 ns


def _errors(demos) -> dict[str, float]:
    out = {}
    for tr in demos:
        x = np.concatenate([tr.obs, tr.act, tr.voluntary], axis=1)
        for j, name in enumerate(demos.obs_names + demos.act_names + demos.vol_names):
            err = float(np.abs(x[:, j] - SIGNALS[name][0](tr.t)).max())
            out[name] = max(out.get(name, 0.0), err)
    return out


@pytest.mark.parametrize("storage", STORAGES)
def test_imported_values_match_the_analytic_signals(folder, mapping, storage):
    res = import_bags([_bag_path(folder, "s3", storage)], mapping, progress=False)
    demos = res.demos
    assert len(demos) == 1 and demos.rate_hz == 100.0
    assert demos.obs_names == ["fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw", "fork_fx",
                               "fork_fz"]
    assert demos.act_names == ["knife_x", "knife_y", "knife_z"]
    assert demos.vol_names == ["shoulder_elevation", "shoulder_protraction"]
    tr = demos[0]
    assert tr.subject == 3  # subject = "s(\d+)" on the bag's name
    # the grid starts where the late topic (the knife, at 0.5 s) starts and ends where the first topic ends
    assert tr.t[0] == pytest.approx(0.5, abs=1e-9)
    np.testing.assert_allclose(np.diff(tr.t), 0.01, atol=1e-9)
    assert 3.95 < tr.t[-1] <= 4.0
    # every mapped message was read; the unmapped topic was not
    assert res.messages == WRITTEN[storage] - N_UNMAPPED
    errors = _errors(demos)
    for name, err in errors.items():
        assert err <= _bound(name), (name, err, _bound(name))
    # the largest errors: the force (the fastest signal, 200 Hz) and positions (below 0.05 mm)
    assert errors["fork_fx"] < 4e-4
    assert max(errors[n] for n in ("fork_x", "fork_y", "fork_z", "knife_x", "knife_y", "knife_z")) < 5e-5
    # yaw turns through ±π several times: unwrapped, it is the continuous analytic angle
    assert np.ptp(tr.obs[:, 5]) > 2 * np.pi and errors["fork_yaw"] < 1e-6
    print(f"{storage}: largest interpolation error per channel: {errors}")


def test_the_storages_give_the_same_data(folder, mapping):
    sets = [import_bags([_bag_path(folder, "s3", s)], mapping, progress=False).demos for s in STORAGES]
    for other in sets[1:]:
        np.testing.assert_array_equal(other[0].obs, sets[0][0].obs)
        np.testing.assert_array_equal(other[0].act, sets[0][0].act)
        np.testing.assert_array_equal(other[0].voluntary, sets[0][0].voluntary)
        np.testing.assert_array_equal(other[0].t, sets[0][0].t)


def test_header_stamps_not_receive_times(folder, mapping):
    """Receive times lag the stamps by 3-8 ms: with time = "receive" the force is visibly off."""
    recv = replace(mapping, time="receive")
    err_recv = _errors(import_bags([_bag_path(folder, "s3", "mcap")], recv, progress=False).demos)
    err_hdr = _errors(import_bags([_bag_path(folder, "s3", "mcap")], mapping, progress=False).demos)
    assert err_recv["fork_fx"] > 0.03 > 20 * err_hdr["fork_fx"]


def test_several_bags_are_several_trials(folder, mapping):
    bags = [_bag_path(folder, "s3", "mcap"), _bag_path(folder, "s3", "ros1")]
    res = import_bags(bags, mapping, progress=False)
    assert res.demos.trial_ids == [0, 1] and res.demos.subjects == [3]
    assert res.messages == WRITTEN["mcap"] + WRITTEN["ros1"] - 2 * N_UNMAPPED
    assert res.trials_per_bag == {str(b): 1 for b in bags}


def test_a_gap_is_refused_naming_topic_and_time(folder, mapping):
    with pytest.raises(DataFormatError, match=r"s5_gap: gap in topic /fork/wrench: no message for 0\.3\d\d s "
                                              r"after t = 1\.99\d s .*--on-gap split"):
        import_bags([folder / "s5_gap"], mapping, progress=False)


def test_a_gap_splits_the_trial(folder, mapping):
    res = import_bags([folder / "s5_gap"], mapping, on_gap="split", progress=False)
    demos = res.demos
    assert len(demos) == 2 and demos.trial_ids == [0, 1] and demos.subjects == [5]
    first, second = demos[0], demos[1]
    assert first.t[0] == pytest.approx(0.5) and 1.99 <= first.t[-1] < 2.0
    assert 2.3 < second.t[0] <= 2.32 and second.t[-1] > 3.9
    for name, err in _errors(demos).items():
        assert err <= _bound(name), name
    assert res.trials_per_bag == {str(folder / "s5_gap"): 2}


def test_gap_with_a_larger_max_gap_is_bridged(folder, mapping):
    demos = import_bags([folder / "s5_gap"], mapping, max_gap=0.5, progress=False).demos
    assert len(demos) == 1
    fx = demos.obs_names.index("fork_fx")
    inside = (demos[0].t > 2.0) & (demos[0].t < 2.3)
    assert inside.sum() > 20 and np.all(np.isfinite(demos[0].obs[inside, fx]))  # interpolated across
