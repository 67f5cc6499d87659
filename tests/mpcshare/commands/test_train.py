"""`mpcshare train`: what it writes to a pipe, and where its rule choice runs."""

from mpcshare.cli import main


def test_train_output_captured_to_a_pipe_holds_lines_not_progress_bars(data_file, tmp_path, capsys):
    """Progress bars draw on a terminal only (learning.progress): a redirected log gets no carriage return."""
    assert main(["train", str(data_file), "--out", str(tmp_path / "model"), "--epochs", "2",
                 "--no-rule-choice"]) == 0
    said = capsys.readouterr()
    assert said.out.strip() and "\r" not in said.out + said.err and "\x1b" not in said.out + said.err


def test_train_workers_1_chooses_the_rule_in_this_process(data_file, tmp_path, monkeypatch):
    """`--workers 1`: the closed-loop choice runs its episodes here, starting no process."""
    import json

    from mpcshare.evaluation import episode_pool

    def no_pool(*args, **kwargs):
        raise AssertionError("a worker process was started")

    monkeypatch.setattr(episode_pool, "ProcessPoolExecutor", no_pool)
    out = tmp_path / "model"
    assert main(["train", str(data_file), "--out", str(out), "--epochs", "2", "--rule-duration", "2",
                 "--workers", "1", "--quiet"]) == 0
    rule = json.loads((out / "rule.json").read_text())["rule"]
    # the seconds given, or up to twice them where a choice trial shows too little of the stroke (choice_seconds)
    assert rule["choice"]["episodes_run"] > 0 and 2.0 <= rule["choice"]["duration_s"] <= 4.0
