"""The K trade-off sweep: through the CLI, its files, and the expected trend."""

import json

import pytest

from learning.data import save
from mpcshare.cli import main
from mpcshare.commands.train import TRAIN_COMMAND
from sim.demonstrator import GeneratorConfig, generate_demonstrations

KEYS = {"percentile", "K", "rmse_reactive", "rmse_all", "voluntary_share", "voluntary_effort", "gate_accuracy"}


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep")
    demos = generate_demonstrations(2, 2, seed=0, config=GeneratorConfig(trial_minutes=0.5))
    save(demos, root / "demos.npz")
    argv = ["train", str(root / "demos.npz"), "--sweep", "--percentiles", "100", "50", "--out",
            str(root / "out"), "--modes", "4", "--epochs", "8", "--hmm-restarts", "1", "--quiet"]
    assert main(argv, commands=(TRAIN_COMMAND,)) == 0
    return root / "out"


def test_sweep_writes_rows_table_and_plot(sweep_dir):
    rows = json.loads((sweep_dir / "sweep.json").read_text())
    assert isinstance(rows, list)
    for r in rows:
        assert KEYS <= set(r) and r["rmse_units"].startswith("standardised")
    kinds = [r["kind"] for r in rows]
    assert kinds == ["gate+predictor", "gate+predictor", "lstm_all", "ridge"]
    assert [r["percentile"] for r in rows] == [100.0, 50.0, None, None]
    assert rows[0]["K"] > rows[1]["K"] > 0
    # at the 100th percentile R is every point: the all-points LSTM, nothing handed over
    assert rows[0]["predictor_is_lstm_all"] and rows[0]["voluntary_share"] == 0.0
    assert rows[0]["rmse_all"] == pytest.approx(rows[2]["rmse_all"])
    assert rows[0]["rmse_reactive"] == pytest.approx(rows[0]["rmse_reactive_lstm_all"])
    assert rows[1]["rmse_all"] > 0 and rows[3]["rmse_all"] > 0
    md = (sweep_dir / "sweep.md").read_text()
    assert "| percentile |" in md and "As K is lowered" in md and "effort E = (1/N)" in md
    assert "The LSTM trained on all points, measured on the same subsets R" in md
    assert (sweep_dir / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_reactive_rmse_falls_and_effort_rises_as_K_is_lowered(sweep_dir):
    rows = json.loads((sweep_dir / "sweep.json").read_text())
    at = {r["percentile"]: r for r in rows if r["kind"] == "gate+predictor"}
    assert at[50.0]["rmse_reactive"] < at[100.0]["rmse_reactive"]
    assert at[50.0]["voluntary_effort"] > at[100.0]["voluntary_effort"] == 0.0
    assert at[50.0]["voluntary_share"] > 0.2
    assert at[50.0]["gate_accuracy"] > 0.6
