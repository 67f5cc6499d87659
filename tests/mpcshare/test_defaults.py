"""Each default is written once: the objects that share a setting read it from one place, and the
command line's defaults are the values users have always had."""

from __future__ import annotations

import inspect

import pytest

from mpcshare.cli import build_parser
from mpcshare.control.arbitration import Arbiter
from mpcshare.control.controller import SharedController
from mpcshare.control.strategies.gate import GateSettings
from mpcshare.control.strategies.paper_gate import PaperGateSettings
from mpcshare.control.types import DEFAULT_BETA, ControllerConfig
from mpcshare.training.config import DEFAULT_PERCENTILES, TrainConfig
from sim.demonstrator import DEFAULT_MINUTES, DEFAULT_SUBJECTS, generate_demonstrations


def _defaults(f) -> dict:
    return {k: p.default for k, p in inspect.signature(f).parameters.items() if p.default is not p.empty}


def test_the_arbiter_takes_the_controller_configs_defaults():
    arb, cfg = _defaults(Arbiter), ControllerConfig()
    for name in ("min_dwell_s", "handover_s", "novelty_persist_s"):
        assert arb[name] == getattr(cfg, name), name
    paper, gate = PaperGateSettings(), GateSettings()  # the gate falls back to the paper's gate, its thresholds
    assert (gate.on_threshold, gate.off_threshold) == (paper.on_threshold, paper.off_threshold)
    for f in (Arbiter, SharedController, SharedController.from_bundle):
        assert _defaults(f)["beta"] == DEFAULT_BETA


def test_the_lstm_and_train_config_share_their_defaults():
    from learning.predictor import ReactivePredictor

    lstm, cfg = _defaults(ReactivePredictor), TrainConfig()
    same = {n: n for n in ("hidden_size", "batch_size", "chunk_len", "burn_in", "learning_rate", "max_epochs",
                           "patience", "val_fraction")} | {"num_threads": "torch_threads"}
    for mine, theirs in same.items():
        assert lstm[mine] == getattr(cfg, theirs), mine


@pytest.mark.parametrize("argv,expected", [
    (["generate", "--out", "x.npz"], {"subjects": 3, "minutes": 10.0}),
    (["demo"], {"subjects": 3, "minutes": 10.0}),
    (["sim", "--model", "m", "--out", "o"], {"beta": 0.5}),
    # tune sweeps fewer percentiles than train --sweep, so that its default has >= 10 pairs (issue 28)
    (["tune", "data.npz", "--out", "o"], {"percentiles": [100.0, 70.0], "epochs": 80}),
])
def test_the_command_lines_defaults_are_unchanged_and_read_from_one_place(argv, expected):
    args = build_parser().parse_args(argv)
    for k, v in expected.items():
        assert getattr(args, k) == v, k
    assert (DEFAULT_SUBJECTS, DEFAULT_MINUTES) == (_defaults(generate_demonstrations)["n_subjects"],
                                                   _defaults(generate_demonstrations)["minutes"])
    assert list(DEFAULT_PERCENTILES) == [100.0, 90.0, 80.0, 70.0, 60.0, 50.0]
    assert TrainConfig().chunk_len == 25 and TrainConfig().max_epochs == 80 and TrainConfig().patience == 10
