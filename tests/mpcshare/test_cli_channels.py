"""Any channels, no traceback: ``import`` → ``inspect`` → ``train`` → ``sim`` on data whose channels are
named otherwise, with two shoulder channels, generic names or none of the roles."""

import json

import pytest

from learning.data import Demonstrations, Trial, load, save
from mpcshare.cli import main
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from sim.episode import Episode
from tests.learning.bags import MAPPING_TOML, write_bag

RENAMED = (MAPPING_TOML.replace("knife_", "blade_").replace("fork_", "fk_")
           .replace("shoulder_elevation", "imu_a").replace("shoulder_protraction", "imu_b"))
ROLES = ["knife_x=blade_x", "knife_y=blade_y", "knife_z=blade_z", "fork_x=fk_x", "fork_y=fk_y", "fork_z=fk_z",
         "fork_roll=fk_roll", "fork_pitch=fk_pitch", "fork_yaw=fk_yaw"]
FAST = ["--epochs", "2", "--quiet"]


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp("channel_bags")
    for i in range(4):
        write_bag(d / f"s{i % 2 + 1}_t{i}", storage="mcap", seed=i, duration_s=6.0)
    (d / "renamed.toml").write_text(RENAMED)
    (d / "roles.toml").write_text(RENAMED + "[map]\n" + "".join(f'{r.split("=")[0]} = "{r.split("=")[1]}"\n'
                                                                for r in ROLES))
    return d


def _one_line(err: str, command: str) -> str:
    assert err.startswith(f"mpcshare {command}: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    return err


@pytest.mark.usefixtures("rule_choice_in_process")
def test_renamed_channels_and_a_two_angle_shoulder_from_import_to_sim(bags, tmp_path, capsys):
    data = tmp_path / "renamed.npz"
    bag_paths = [str(p) for p in sorted(bags.glob("s*"))]
    assert main(["import", *bag_paths, "--mapping", str(bags / "renamed.toml"), "--out", str(data),
                 "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "simulator: no: no knife tip channel(s) knife_x, knife_y, knife_z" in out
    assert "--map knife_x=blade_x knife_y=blade_y knife_z=blade_z" in out  # the fix, proposed
    assert main(["inspect", str(data)]) == 0
    assert "simulator: no:" in capsys.readouterr().out
    assert main(["inspect", str(data), "--map", *ROLES]) == 0
    assert "simulator: yes (knife tip knife_x, knife_y, knife_z; fork pose; shoulder imu_a as shoulder_elevation, " \
        "imu_b as shoulder_protraction)" in \
        capsys.readouterr().out

    # unmapped: the bundle is written, the rule choice skipped in one line; sim refuses in one line
    plain = tmp_path / "plain"
    assert main(["train", str(data), "--out", str(plain), *FAST]) == 0
    lines = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("hand-over rule:")]
    assert len(lines) == 1 and "closed-loop choice was skipped" in lines[0] and "--map knife_x=blade_x" in lines[0]
    assert (plain / "bundle.json").exists() and "was skipped" in (plain / "training.md").read_text()
    rule = json.loads((plain / "rule.json").read_text())["rule"]  # the typed record says why, not the metrics
    assert rule["skipped"] == lines[0].removeprefix("hand-over rule: the ") and rule["settings"] == {}
    assert "rule_choice_skipped" not in json.loads((plain / "metrics.json").read_text())
    assert main(["sim", "--model", str(plain), "--out", str(tmp_path / "no_sim")]) == 1
    err = _one_line(capsys.readouterr().err, "sim")
    assert "the bundle's channels cannot drive the simulator" in err and "fork_x=fk_x" in err

    # mapped once, at training: the rule is chosen in the closed loop and sim applies the recorded map
    model = tmp_path / "model"
    assert main(["train", str(data), "--out", str(model), *FAST, "--rule-duration", "1", "--rule-trials", "1",
                 "--map", *ROLES]) == 0
    assert "hand-over rule: the wearer leads modes" in capsys.readouterr().out
    info = json.loads((model / "bundle.json").read_text())
    assert info["config"]["channel_map"]["knife_x"] == "blade_x" and info["vol_names"] == ["imu_a", "imu_b"]
    out = tmp_path / "sim"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "1",
                 "--runs", "voluntary", "gate"]) == 0
    comp = json.loads((out / "comparison.json").read_text())
    assert set(comp["strategies"]) == {"voluntary", "gate"} and (out / "comparison.md").exists()
    run = Episode.load(out / comp["run_files"]["gate"][0])
    assert run.voluntary.shape == (100, 2)  # the wearer commands through the two measured angles
    assert run.shoulder_names == ["shoulder_elevation", "shoulder_protraction"]  # imu_a, imu_b by position
    assert comp["strategies"]["gate"]["limit_violations"] == 0


def test_the_import_mapping_carries_the_roles(bags, tmp_path, capsys):
    data = tmp_path / "roles.npz"
    assert main(["import", str(bags / "s1_t0"), "--mapping", str(bags / "roles.toml"), "--out", str(data),
                 "--no-progress"]) == 0
    assert "simulator: yes" in capsys.readouterr().out
    demos = load(data)
    assert demos.act_names == ["knife_x", "knife_y", "knife_z"] and demos.vol_names == ["imu_a", "imu_b"]
    bad = bags / "bad_map.toml"
    bad.write_text(RENAMED + '[map]\nknife_x = "nope"\n')
    assert main(["import", str(bags / "s1_t0"), "--mapping", str(bad), "--out", str(tmp_path / "x.npz"),
                 "--no-progress"]) == 1
    assert "[map] knife_x" in _one_line(capsys.readouterr().err, "import")


@pytest.fixture(scope="module")
def generic(tmp_path_factory):
    """10 trials of 6 s, channels o0..o8 (fork), u0..u8 (knife) and a 4-channel shoulder v0..v3."""
    d = generate_demonstrations(2, 0.5, seed=4, config=GeneratorConfig(trial_minutes=0.1))
    trials = [Trial(tr.obs, tr.act, tr.t, tr.trial_id, tr.subject, tr.mode, tr.voluntary[:, [0, 1, 2, 0]])
              for tr in d.trials]
    path = tmp_path_factory.mktemp("generic") / "generic.npz"
    save(Demonstrations(trials, d.rate_hz, [f"o{i}" for i in range(9)], [f"u{i}" for i in range(9)],
                        [f"v{i}" for i in range(4)]), path)
    return path


def test_generic_channels_train_and_say_what_the_simulator_needs(generic, tmp_path, capsys):
    assert main(["inspect", str(generic), "--json"]) == 0
    sim = json.loads(capsys.readouterr().out)["simulator"]
    assert not sim["can_drive"] and len(sim["gaps"]) == 3  # knife, fork, four unnamed shoulder channels
    model = tmp_path / "model"
    assert main(["train", str(generic), "--out", str(model), *FAST]) == 0
    out = capsys.readouterr().out
    assert "knife_x=CHANNEL" in out and "4 shoulder channels" in out and (model / "bundle.json").exists()
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "s")]) == 1
    _one_line(capsys.readouterr().err, "sim")
    # the roles given at sim time do not fix a bundle trained without them: one line, how
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "s2"), "--map", "knife_x=u0"]) == 1
    assert "train it again" in _one_line(capsys.readouterr().err, "sim")


@pytest.mark.parametrize("words, message", [
    (["knife_x"], "expected NAME=CHANNEL"),
    (["knife_x=nope"], "no channel 'nope'"),
    (["knife_x=u0", "knife_y=u0"], "renamed twice"),
    (["o1=o0"], "name ['o1'] twice"),
])
def test_a_bad_map_is_one_line(generic, tmp_path, capsys, words, message):
    for command in (["inspect", str(generic)], ["train", str(generic), "--out", str(tmp_path / "m")]):
        assert main([*command, "--map", *words]) == 1
        assert message in _one_line(capsys.readouterr().err, command[0])


def test_tune_on_data_that_cannot_drive_the_simulator_is_one_line(generic, tmp_path, capsys):
    assert main(["tune", str(generic), "--out", str(tmp_path / "t")]) == 1
    assert "knife_x" in _one_line(capsys.readouterr().err, "tune")
