"""The console script's simulator subcommands: generate and demo."""

import json

import numpy as np

from learning.data import load
from sim.cli import main


def test_generate_npz_then_inspect(tmp_path, capsys):
    out = tmp_path / "d.npz"
    assert main(["generate", "--subjects", "2", "--minutes", "1", "--seed", "4", "--out", str(out)]) == 0
    d = load(out)
    assert d.subjects == [0, 1] and d.n_samples == 2 * 60 * 100 and d.has_modes
    assert main(["inspect", str(out)]) == 0
    assert "modes:" in capsys.readouterr().out


def test_generate_csv_folder_same_data_as_npz(tmp_path):
    main(["generate", "--subjects", "1", "--minutes", "0.5", "--seed", "1", "--out", str(tmp_path / "a.npz")])
    main(["generate", "--subjects", "1", "--minutes", "0.5", "--seed", "1", "--out", str(tmp_path / "csv")])
    a, b = load(tmp_path / "a.npz"), load(tmp_path / "csv")
    for x, y in zip(a, b):
        np.testing.assert_allclose(x.obs, y.obs, rtol=1e-12, atol=1e-12)
        np.testing.assert_array_equal(x.mode, y.mode)


def test_generate_rejects_bad_arguments(tmp_path, capsys):
    assert main(["generate", "--subjects", "0", "--out", str(tmp_path / "x.npz")]) == 1
    assert "--subjects" in capsys.readouterr().err


def test_demo_writes_summary_plots_and_report(tmp_path):
    out = tmp_path / "demo"
    code = main(["demo", "--out", str(out), "--subjects", "2", "--minutes", "2", "--n-random", "2",
                 "--no-search"])
    assert code == 0
    summary = json.loads((out / "data_summary.json").read_text())
    assert summary["mode_names"] == ["cutting", "repositioning", "collecting", "removing"]
    assert (out / "data_trial.png").stat().st_size > 10_000
    assert (out / "demos.npz").exists()
    report = json.loads((out / "report.json").read_text())
    assert report["candidates"] == []
    assert (out / "report.md").exists()
