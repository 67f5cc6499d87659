"""Stage-level progress of training (mpcshare.training.stages): each stage's time, the bar on a terminal only."""

from __future__ import annotations

import sys
import time

from mpcshare.training.stages import Stages


def test_each_stage_gets_its_time_and_a_repeated_stage_adds_up():
    stages = Stages(["data", "gates"], enabled=False)
    time.sleep(0.02)
    stages.done("data")
    stages.done("gates")
    time.sleep(0.01)
    stages.done("gates")
    stages.close()
    assert stages.bar is None and list(stages.timings) == ["data", "gates"]
    assert stages.timings["data"] >= 0.02 and stages.timings["gates"] >= 0.01


def test_the_bar_counts_the_stages_and_names_the_next_on_a_terminal(capsys, monkeypatch):
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    stages = Stages(["data", "gates", "predictor"], enabled=True, desc="train")
    stages.done("data")
    assert stages.bar.n == 1 and "gates" in str(stages.bar.postfix)
    stages.done("extra")  # a stage outside the list counts, names nothing
    stages.done("predictor")
    assert stages.bar.n == 3
    stages.close()
    assert "train" in capsys.readouterr().err


def test_no_bar_draws_on_a_pipe(capsys):
    stages = Stages(["data"], enabled=True)
    stages.done("data")
    stages.close()
    assert capsys.readouterr().err == ""
