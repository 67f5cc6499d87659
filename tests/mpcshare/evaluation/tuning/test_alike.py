"""Episodes that decide alike run once (mpcshare.evaluation.tuning.alike): the shared rows equal their own runs."""

from __future__ import annotations

from mpcshare.evaluation.tuning.episodes import TIMING_KEYS, plan_tasks, random_tasks
from mpcshare.evaluation.tuning.runner import run_tune
from sim.task.eating import MODE_NAMES


def _comparable(rows):
    return [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in rows]


def test_episodes_that_decide_alike_share_figures_equal_to_their_own_runs(data, swept, tmp_path):
    from mpcshare.evaluation import frontend_replay
    from mpcshare.evaluation.tuning import episodes
    from mpcshare.training.config import TrainConfig

    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "bundles").symlink_to(swept / "bundles")
    said: list[str] = []
    kwargs = dict(percentiles=[90.0], betas=[0.0, 1.0], strategies=["gate", "paper_gate"], n_trials=1, seeds=[0],
                  duration_s=1.0, wearer="hemiparetic_mild", mode_names=MODE_NAMES)
    run = run_tune(data, tmp_path / "a", progress=False, log=said.append, draws=2, config=TrainConfig(max_epochs=3),
                   workers=1, **kwargs)
    run_n, shared_n = (int(w) for w in said[-1].split(": ")[-1].replace(",", "").split()[0:3:2])
    assert shared_n > 0 and run_n + shared_n == len(run["rows"]) == 2 + 4 + 8
    tasks = plan_tasks(kwargs["percentiles"], kwargs["betas"], kwargs["strategies"], run["trials"], [0],
                       {90.0: str(tmp_path / "a" / "bundles" / "p90")}, str(data.resolve()), 1.0, "hemiparetic_mild",
                       MODE_NAMES)
    settings = [r for r in run["rows"] if r["strategy"] in ("gate", "paper_gate")]
    frontend_replay._CACHE.clear()
    live = [episodes.run_task(t) for t in tasks + random_tasks(settings, tasks, 2)]
    assert _comparable(run["rows"]) == _comparable(live)
    assert len(frontend_replay._CACHE) == 1  # the parties, settings and placebos of a trial share one recording
