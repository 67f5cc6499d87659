"""`mpcshare train --modes-from mixture`: the bundle's modes are the time-free Gaussian mixture,
stored as an HMM whose rows of A are the weights, and the online mode filter runs it."""

import numpy as np
import pytest

from learning.data import save
from mpcshare.bundle import load_bundle
from mpcshare.cli import main
from mpcshare.commands.train import TRAIN_COMMAND
from mpcshare.training.config import TrainConfig
from sim.demonstrator import GeneratorConfig, generate_demonstrations


def test_modes_from_is_checked_and_names_the_choices():
    assert TrainConfig().modes_from == "hmm"
    with pytest.raises(ValueError, match=r"modes_from must be one of \('hmm', 'mixture'\), got 'gmm'"):
        TrainConfig(modes_from="gmm")


@pytest.mark.usefixtures("rule_choice_in_process")
def test_cli_trains_a_bundle_with_mixture_modes_and_the_filter_runs_them(tmp_path, capsys):
    demos = generate_demonstrations(2, 1.5, seed=1, config=GeneratorConfig(trial_minutes=0.5))
    path = tmp_path / "d.npz"
    save(demos, path)
    out = tmp_path / "model"
    argv = ["train", str(path), "--out", str(out), "--modes", "3", "--modes-from", "mixture",
            "--epochs", "2", "--hmm-restarts", "1", "--quiet", "--rule-duration", "3"]
    assert main(argv, commands=(TRAIN_COMMAND,)) == 0
    assert "gate: accuracy" in capsys.readouterr().out
    b = load_bundle(out, expect_obs_names=demos.obs_names, expect_act_names=demos.act_names)
    assert b.config["modes_from"] == "mixture" and b.modes.temporal is False
    A = b.modes.transmat_
    np.testing.assert_allclose(A, np.tile(b.modes.startprob_, (3, 1)))  # no temporal model
    # the online filter (as the controller builds it from the bundle) gives the per-sample
    # posterior: the same whatever came before
    f = b.modes.make_filter()
    o = np.zeros(len(demos.obs_names))
    f.step(o + 1.0)
    after_other = f.step(o)
    g = b.modes.make_filter()
    np.testing.assert_allclose(g.step(o), after_other, atol=1e-12)
    with pytest.raises(SystemExit) as exc:  # argparse: a usage error names the choices
        main(["train", str(path), "--out", str(tmp_path / "m2"), "--modes-from", "time"], commands=(TRAIN_COMMAND,))
    assert exc.value.code == 2
    assert "invalid choice: 'time'" in capsys.readouterr().err
