"""The newcomer's example runs end to end: trains a small model, simulates one trial, saves a plot."""

import importlib.util
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "run_eating_sim.py"


def test_run_eating_sim_example(tmp_path):
    spec = importlib.util.spec_from_file_location("run_eating_sim", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    metrics = module.main(["--out", str(tmp_path), "--minutes", "2", "--seconds", "2"])
    assert metrics["limit_violations"] == 0
    assert (tmp_path / "trial.png").stat().st_size > 10_000
    assert (tmp_path / "run.npz").exists() and (tmp_path / "model" / "bundle.json").exists()
