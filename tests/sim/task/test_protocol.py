"""A second task, defined here only, runs through what reads a task: its figures of a closed-loop episode, the
report's mode colours, the data summary's mode names, the shoulder map; and a task module beside ``eating`` is
found by name."""

from __future__ import annotations

import importlib
import re
import sys
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Mapping, Sequence

import numpy as np
import pytest

import sim.task
from robot.shoulder import ShoulderMap
from sim.demonstrator import generate_demonstrations
from sim.task import EATING, Task, task_named, task_names
from sim.task.metrics import rms_by_mode, time_lag
from tests.sim.controllers import VoluntaryController


class Pouring:
    """A task of two modes, no strokes, judged by its lag; the wearer's shoulder elevation lifts the tip."""

    name = "pouring"
    mode_names = ("approach", "pour")
    mode_colours = {"approach": "#112233", "pour": "#445566"}
    stroke_mode = None
    stroke_band_hz = None
    criterion = "the tip within 0.2 s of the intent"
    metric_keys = ("lag_s", "rms_by_mode_m")
    body = replace(EATING.body, head_speed_cap=0.03)
    shoulder_channels = ("shoulder_elevation",)
    shoulder_to_plate = np.array([[0.0], [0.0], [1.0]])

    def episode_metrics(self, tip: np.ndarray, intent: np.ndarray, dt: float, true_mode: np.ndarray | None,
                        mode_names: Sequence[str] | None = None, alpha: np.ndarray | None = None) -> dict[str, Any]:
        lag, _ = time_lag(tip, intent, dt)
        by_mode = {} if true_mode is None else rms_by_mode(tip, intent, true_mode, tuple(mode_names or ()))
        return {"lag_s": None if not np.isfinite(lag) else lag, "rms_by_mode_m": by_mode}

    def done(self, metrics: Mapping[str, Any]) -> bool:
        return metrics.get("lag_s") is not None and abs(metrics["lag_s"]) <= 0.2

    def shoulder_map(self, names: Sequence[str] = (), gain: float = 0.5, deadband_rad: float = 0.01) -> ShoulderMap:
        return ShoulderMap.for_channels(names, self.shoulder_channels, self.shoulder_to_plate, gain, deadband_rad)


def test_both_tasks_are_tasks_and_a_partial_one_is_not():
    assert isinstance(EATING, Task) and isinstance(Pouring(), Task)
    assert not isinstance(SimpleNamespace(name="half", mode_names=("a",)), Task)


def test_a_closed_loop_comparison_is_scored_by_the_task_it_is_given():
    from mpcshare.evaluation import compare_strategies, simulate_episode
    from mpcshare.run_table import StrategyRun

    demos = generate_demonstrations(n_subjects=1, minutes=0.5, seed=11)
    two = demos.__class__([replace(t, mode=(t.mode > 0).astype(int)) for t in demos.trials], demos.rate_hz,
                          list(demos.obs_names), list(demos.act_names), list(demos.vol_names))  # cutting → approach
    task, run = Pouring(), StrategyRun("voluntary", "voluntary")
    bundle = SimpleNamespace(vol_names=list(demos.vol_names))
    comp = compare_strategies(bundle, two, [two.trials[0].trial_id], runs=(run,), duration_s=4.0, seed=1, beta=1.0,
                              make_controller=lambda bundle, **_: VoluntaryController(), log=None,
                              mode_names=task.mode_names, task=task)
    row = comp.per_trial["voluntary"][str(two.trials[0].trial_id)]
    assert set(task.metric_keys) <= set(row) and "saw_correlation" not in row  # its figures, not eating's
    assert set(row["rms_by_mode_m"]) == {"approach", "pour"} and task.done(row)
    assert set(comp.strategies["voluntary"]["rms_by_mode_m"]) == {"approach", "pour"}  # pooled by its mode names
    _, eating = simulate_episode(bundle, demos, demos.trials[0], run, {}, beta=1.0, duration_s=4.0, seed=1,
                                 wearer=None, mode_names=EATING.mode_names,
                                 make_controller=lambda bundle, **_: VoluntaryController())
    assert set(EATING.metric_keys) <= set(eating) and eating["lag_s"] == row["lag_s"]  # the same loop, eating's figures


def test_the_report_colours_and_the_data_summary_name_the_tasks_modes():
    from mpcshare.commands.data import format_summary
    from mpcshare.reports.style import mode_colour

    task = Pouring()
    assert [mode_colour(k, task.mode_names, task) for k in (0, 1)] == ["#112233", "#445566"]
    assert mode_colour(0, task.mode_names) != "#112233"  # eating's colours know no "approach": a grey
    assert mode_colour(0, EATING.mode_names) == EATING.mode_colours["cutting"]
    demos = generate_demonstrations(n_subjects=1, minutes=0.5, seed=11)
    demos = demos.__class__([replace(t, mode=(t.mode > 0).astype(int)) for t in demos.trials], demos.rate_hz,
                            list(demos.obs_names), list(demos.act_names), list(demos.vol_names))
    line = format_summary(demos, task.mode_names).splitlines()[-1]
    assert line.startswith("modes:") and "approach" in line and "pour" in line and "cutting" not in line


def test_the_tasks_shoulder_layout_drives_the_map():
    m = Pouring().shoulder_map()
    np.testing.assert_allclose(m.tip_velocity(np.array([0.11])), [0.0, 0.0, 0.05])  # elevation lifts the tip
    with pytest.raises(ValueError, match="none named by its role"):
        Pouring().shoulder_map(["a", "b"])


def test_a_task_module_beside_eating_is_found_by_name():
    assert task_named("eating") is EATING and "eating" in task_names()
    with pytest.raises(ValueError, match="unknown task 'pouring'; valid choices: eating"):
        task_named("pouring")
    planted = Path(sim.task.__file__).parent / "pouring_for_test.py"
    assert not planted.exists()
    planted.write_text(f"from {__name__} import Pouring\n\nTASK = Pouring()\n")
    importlib.invalidate_caches()
    try:
        assert "pouring_for_test" in task_names()
        assert task_named("pouring_for_test").mode_names == ("approach", "pour")
    finally:
        planted.unlink()
        sys.modules.pop("sim.task.pouring_for_test", None)
        importlib.invalidate_caches()
    assert task_names() == ["eating"]


def test_a_task_outside_the_package_is_found_by_its_module_and_attribute(tmp_path, monkeypatch):
    (tmp_path / "my_tasks_for_test").mkdir()
    (tmp_path / "my_tasks_for_test" / "__init__.py").write_text("")
    (tmp_path / "my_tasks_for_test" / "pouring.py").write_text(
        f"from {__name__} import Pouring\n\nTASK = Pouring()\nOTHER = Pouring()\nNOT_A_TASK = 3\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    for name in ("my_tasks_for_test", "my_tasks_for_test.pouring"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    assert task_named("my_tasks_for_test.pouring").mode_names == ("approach", "pour")  # its TASK
    assert isinstance(task_named("my_tasks_for_test.pouring:OTHER"), Pouring)
    assert task_named("my_tasks_for_test.pouring:TASK") is task_named("my_tasks_for_test.pouring")
    assert task_names() == ["eating"]  # lists the package's tasks only
    with pytest.raises(ValueError, match="unknown task 'my_tasks_for_test'; valid choices: eating"):
        task_named("my_tasks_for_test")  # a bare name is a module of sim.task
    m = "my_tasks_for_test.pouring"
    for spec, words in ((f"{m}:NOPE", f"module {m} has no NOPE"),
                        (f"{m}:NOT_A_TASK", f"{m}.NOT_A_TASK is a int, not a sim.task.Task"),
                        ("no_such_package_x.tasks", "cannot import no_such_package_x.tasks (ModuleNotFoundError"),
                        (f"{m}:1x", "expected package.module or package.module:ATTR"),
                        (f"{m}:Pouring", f"{m}.Pouring is a class; name an instance of it (TASK = Pouring())")):
        with pytest.raises(ValueError, match=re.escape(f"task {spec!r}: {words}")):
            task_named(spec)
