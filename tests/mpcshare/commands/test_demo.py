"""The data-producing subcommands: generate and demo."""

import json

import numpy as np
import pytest

from learning.data import load
from mpcshare.cli import main


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


@pytest.mark.parametrize("args", [["--subjects", "0"], ["--minutes", "-1"], ["--rate", "nan"],
                                  ["--minutes", "ten"]])
def test_generate_rejects_bad_arguments_as_usage_errors(tmp_path, capsys, args):
    with pytest.raises(SystemExit) as e:
        main(["generate", *args, "--out", str(tmp_path / "x.npz")])
    assert e.value.code == 2
    assert f"argument {args[0]}" in capsys.readouterr().err
    assert not (tmp_path / "x.npz").exists()


def test_generate_will_not_replace_a_folder_of_other_files(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    assert main(["generate", "--minutes", "0.1", "--out", str(tmp_path)]) == 1
    assert "cannot write" in capsys.readouterr().err
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_demo_refuses_an_output_path_that_is_a_file(tmp_path, capsys):
    (tmp_path / "f").write_text("x")
    assert main(["demo", "--out", str(tmp_path / "f")]) == 1
    assert "exists and is not a folder" in capsys.readouterr().err


def test_demo_runs_every_stage_into_one_report(tmp_path, capsys):
    out = tmp_path / "demo"
    code = main(["demo", "--out", str(out), "--subjects", "2", "--minutes", "4", "--n-random", "2",
                 "--no-search", "--no-sweep", "--sim-trials", "1", "--sim-duration", "3", "--no-video",
                 "--modes", "3", "--window", "0.8", "--wearer", "unimpaired"])
    assert code == 0
    # the analysis options reach the training too (they were once read by the analysis only)
    bundle = json.loads((out / "model" / "bundle.json").read_text())
    assert bundle["n_modes"] == 3 and bundle["window_s"] == 0.8
    summary = json.loads((out / "data_summary.json").read_text())
    assert summary["mode_names"] == ["cutting", "repositioning", "collecting", "removing"]
    assert (out / "data_trial.png").stat().st_size > 10_000
    assert (out / "demos.npz").exists()
    analysis = json.loads((out / "analysis" / "report.json").read_text())
    assert analysis["candidates"] == []
    assert analysis["modes"]["n_modes"] == 3 and analysis["window_s"] == 0.8
    assert (out / "model" / "bundle.json").exists()
    comparison = json.loads((out / "sim" / "comparison.json").read_text())
    said = capsys.readouterr().out  # the progress names what it runs, and the closing lines answer first
    assert f"[6/6] closed loop in MuJoCo: {len(comparison['strategies'])} strategies x 1 held-out trial(s)" in said
    assert "MB of run files" in said.split("[6/6]")[1]
    closing = said.split("What the robot did:")[1]
    assert [ln.strip().split(":")[0] for ln in closing.splitlines()[1:5]] == ["The task", "Sharing", "Effort",
                                                                             "Keep-out"]
    from mpcshare.run_table import RUN_NAMES

    assert set(comparison["strategies"]) == set(RUN_NAMES) >= {"voluntary", "reactive", "mix25", "mix50", "mix75",
                                                                "gate", "paper_gate", "random_handover",
                                                                "oracle_handover"}
    assert all(m["limit_violations"] == 0 for m in comparison["strategies"].values())
    assert comparison["wearer"]["preset"] == "unimpaired"  # --wearer reaches the closed loop
    gate = comparison["strategies"]["gate"]  # the task figures: lag, sawing while cutting, RMS per mode
    assert -1.0 <= gate["lag_s"] <= 1.0 and gate["rms_at_lag_m"] <= gate["tracking_rmse_m"] + 1e-12
    assert set(gate["rms_by_mode_m"]) <= {"cutting", "repositioning", "collecting", "removing"}
    report = json.loads((out / "report.json").read_text())
    assert report["analysis"]["n_samples"] == analysis["n_samples"]
    assert report["comparison"]["trials"] == comparison["trials"]
    md = (out / "report.md").read_text()
    assert md.startswith("# mpcshare demo") and "## Statistics" in md and "## 4. Closed loop in MuJoCo" in md
    # the summary states both claims, each in its own sentence (issue 22)
    summary_md = md.split("## Statistics", 1)[1].split("\n## ", 1)[0]
    assert "Modes help: " in summary_md and "The temporal model adds information: " in summary_md
    assert "Line: tracking RMS over the straight line" in summary_md  # the line ratio as a headline (issue 28)
    page = (out / "report.html").read_text()
    # the four answers come first, each with its verdict, before any statistic (issue 32)
    heads = [page.index(f"<strong>{topic}: ") for topic in ("The task", "Sharing", "Effort", "Keep-out")]
    first_statistic = min(page.index(w) for w in ("Lipschitz quotient", "Wilcoxon", "p = ") if w in page)
    assert heads == sorted(heads) and heads[-1] < first_statistic
    assert page.index("effort against error") < first_statistic  # then the plot with the line
    assert "{'" not in page and "min_class_count" not in page and "(rad (" not in page  # words, not internals
    assert "<img" in page and 'src="data:image/png;base64,' in page
    assert 'src="analysis/' not in page and 'src="sim/' not in page  # every plot embedded


def test_generate_a_world_of_the_family(tmp_path, capsys) -> None:
    from sim.world_family import world_demonstrations

    out = tmp_path / "w.npz"
    assert main(["generate", "--world", "5", "--trials", "2", "--trial-seconds", "5", "--out", str(out)]) == 0
    assert "world 5: modes cutting (stroke)" in capsys.readouterr().out
    expected, _ = world_demonstrations(5, 2, 5.0)
    np.testing.assert_allclose(load(out).trials[1].act, expected.trials[1].act)
