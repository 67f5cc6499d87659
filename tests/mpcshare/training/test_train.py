"""Training a bundle: any channels, refusals of unusable data, the `train` command end to end."""

import json

import numpy as np
import pytest

from learning.data import Demonstrations, Trial, save
from mpcshare.bundle import RULE_VERSION, load_bundle
from mpcshare.calibration.trials import choice_trials
from mpcshare.cli import main
from mpcshare.commands.train import TRAIN_COMMAND
from mpcshare.training import TrainingError, train_bundle
from tests.mpcshare.training.small import SMALL


def _anonymous(demos: Demonstrations, d_obs: int = 5, d_act: int = 4) -> Demonstrations:
    """The same trials with fewer, unnamed-style channels and no voluntary channel."""
    trials = [Trial(obs=tr.obs[:, :d_obs] * 7.0, act=tr.act[:, 2:2 + d_act] + 3.0, t=tr.t,
                    trial_id=tr.trial_id + 100, subject=tr.subject) for tr in demos.trials]
    return Demonstrations(trials, demos.rate_hz, [f"sensor{j}" for j in range(d_obs)],
                          [f"motor{j}" for j in range(d_act)]).validate()


def test_trains_on_channels_without_physical_names(demos):
    anon = _anonymous(demos)
    b = train_bundle(anon, SMALL, progress=False)
    assert b.obs_names == tuple(f"sensor{j}" for j in range(5)) and b.vol_names == ()
    assert set(b.train_trials) | set(b.heldout_trials) == set(anon.trial_ids)
    m = b.metrics
    assert m["effort_source"] == "action_proxy" and "knife speed" in m["effort_units"]
    assert 0 <= m["voluntary_share"] <= 1 and m["voluntary_effort"] >= 0
    assert m["predictor"]["rmse_all"] > 0 and "ridge" in m["baselines"]
    json.dumps(m, allow_nan=False)
    seq = np.zeros((20, 5 + b.n_modes))
    assert b.predictor.predict(seq).shape == (20, 4)


def test_voluntary_channel_gives_the_effort_in_rad(demos):
    b = train_bundle(demos, SMALL, progress=False)
    m = b.metrics
    assert m["effort_source"] == "voluntary" and m["effort_units"].startswith("rad ")
    assert 0 <= m["voluntary_effort"] <= m["effort_if_all_voluntary"]
    assert set(m["gate"]["per_mode"]) == {"0", "1", "2"}


@pytest.mark.parametrize("case, match", [
    ("two_trials", "at least 3"),
    ("short", "too short"),
    ("rate", "integer factor"),
    ("no_act", "act channels"),
])
def test_unusable_data_is_refused(demos, case, match):
    if case == "two_trials":
        bad = demos.select(demos.trial_ids[:2])
    elif case == "short":
        trials = list(demos.trials)
        tr = trials[1]
        trials[1] = Trial(obs=tr.obs[:50], act=tr.act[:50], t=tr.t[:50], trial_id=tr.trial_id)
        bad = demos.with_trials(trials)
    elif case == "rate":
        bad = demos.with_trials(demos.trials)
        bad.rate_hz = 25.0
    else:
        bad = Demonstrations([Trial(obs=tr.obs, act=np.zeros((len(tr), 0)), t=tr.t, trial_id=tr.trial_id)
                              for tr in demos.trials], demos.rate_hz, demos.obs_names, [])
    with pytest.raises(TrainingError, match=match):
        train_bundle(bad, SMALL, progress=False)


@pytest.fixture(scope="module")
def data_file(demos, tmp_path_factory):
    path = tmp_path_factory.mktemp("d") / "demos.npz"
    save(demos, path)
    return path


@pytest.mark.usefixtures("rule_choice_in_process")
def test_cli_trains_a_bundle_and_prints_the_metrics(data_file, demos, tmp_path, capsys):
    out = tmp_path / "model"
    argv = ["train", str(data_file), "--percentile", "70", "--out", str(out), "--modes", "3",
            "--epochs", "2", "--hmm-restarts", "1", "--quiet", "--rule-duration", "2"]
    assert main(argv, commands=(TRAIN_COMMAND,)) == 0
    text = capsys.readouterr().out
    assert "K = " in text and "percentile 70" in text and "gate: accuracy" in text and str(out) in text
    b = load_bundle(out, expect_obs_names=demos.obs_names, expect_act_names=demos.act_names)
    assert b.percentile == 70 and b.n_modes == 3 and b.config["max_epochs"] == 2
    # the hand-over rule chosen in the closed loop on a held-out trial (dealt round the subjects), recorded with why
    choice = b.rule.choice
    assert b.rule.strategy == "gate" and b.rule.version == RULE_VERSION
    assert dict(b.rule.settings) == {k: tuple(v) if isinstance(v, list) else v for k, v in choice["settings"].items()}
    subjects = {tr.trial_id: tr.subject for tr in demos.trials}
    assert choice["trials"] == choice_trials(b.heldout_trials, subjects=subjects) and "rule_settings" not in b.metrics
    assert "hand-over rule: the wearer leads modes" in text and choice["why"] in text
    assert choice["why"] in (out / "training.md").read_text()


def test_cli_refuses_unusable_data_and_outputs_with_one_message(demos, data_file, tmp_path, capsys):
    two = tmp_path / "two.npz"
    save(demos.select(demos.trial_ids[:2]), two)
    assert main(["train", str(two), "--out", str(tmp_path / "m")], commands=(TRAIN_COMMAND,)) == 1
    err = capsys.readouterr().err
    assert "mpcshare train:" in err and "at least 3" in err and "Traceback" not in err
    assert not (tmp_path / "m").exists()
    other = tmp_path / "notes"
    other.mkdir()
    (other / "a.txt").write_text("x")
    assert main(["train", str(data_file), "--out", str(other)], commands=(TRAIN_COMMAND,)) == 1
    assert "not a model bundle" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        main(["train", str(data_file), "--out", str(tmp_path / "m"), "--percentile", "120"],
             commands=(TRAIN_COMMAND,))
    assert e.value.code == 2
