"""`mpcshare demo`: every stage into one report, and an output path that is a file refused."""

import json

from mpcshare.cli import main


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
    from mpcshare.run_table import DEFAULT_RUNS

    assert set(comparison["strategies"]) == {r.name for r in DEFAULT_RUNS} >= {
        "voluntary", "reactive", "mix25", "mix50", "mix75", "gate", "paper_gate", "random_handover", "oracle_handover"}
    # the demo's choice leaves its mixture comparators to the closed loop, and says so in its log and report
    choice = json.loads((out / "model" / "rule.json").read_text())["rule"]["choice"]
    assert choice["mixes"] == [] and "leaves out the constant mixtures" in said
    # and its second stage (the robot's share 0.5 while it leads), said in both too
    assert choice["robot_alphas"] == [1.0] and {c["robot_alpha"] for c in choice["candidates"]} == {1.0}
    assert "and its second stage" in said
    assert ("ran without the constant mixtures beside its candidates and without its second stage"
            in (out / "report.md").read_text())
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
