"""``--task NAME`` on the commands that read a task, and the bundle's task for ``mpcshare sim``."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from mpcshare.cli import main
from mpcshare.commands.base import CommandError
from mpcshare.commands.task_option import bundle_task, task_for_bundle
from sim.task import EATING


@pytest.mark.parametrize("argv", [["analyze", "d.npz", "--out", "o"], ["train", "d.npz", "--out", "o"],
                                  ["sim", "--model", "m", "--out", "o"], ["tune", "d.npz", "--out", "o"]])
def test_a_task_no_module_names_is_a_usage_error_naming_the_choices(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        main([*argv, "--task", "juggling"])
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert "argument --task: unknown task 'juggling'; valid choices: eating (or package.module:ATTR)" in err
    assert not (tmp_path / "o").exists()  # refused before any output


def test_sim_runs_the_bundles_task_and_refuses_another(tmp_path, monkeypatch):
    (tmp_path / "pouring_for_option_test.py").write_text("from tests.sim.task.test_protocol import Pouring\n\n"
                                                         "TASK = Pouring()\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert bundle_task(SimpleNamespace(config={})) == "eating"  # a bundle from before tasks were named
    eating = SimpleNamespace(config={"task": "eating"})
    assert task_for_bundle(None, eating) is EATING and task_for_bundle("eating", eating) is EATING
    assert task_for_bundle("sim.task.eating", eating) is EATING  # the same task by its module
    with pytest.raises(CommandError, match="the bundle was trained for task 'gone_x.tasks', which cannot be loaded"):
        task_for_bundle(None, SimpleNamespace(config={"task": "gone_x.tasks"}))
    with pytest.raises(CommandError, match=r"^--task pouring_for_option_test:TASK: the bundle was trained for task "
                                           r"'eating' \(modes cutting, repositioning"):
        task_for_bundle("pouring_for_option_test:TASK", eating)
    pouring = SimpleNamespace(config={"task": "pouring_for_option_test:TASK"})
    assert task_for_bundle(None, pouring).mode_names == ("approach", "pour")
