"""Closed-loop episodes over worker processes: the same figures with one worker and with two."""

from __future__ import annotations

import pytest

from learning.data import Demonstrations
from mpcshare.calibration.rule_choice import choose_rule
from mpcshare.evaluation import compare_strategies
from mpcshare.evaluation.episode_pool import MAX_DEFAULT_WORKERS, EpisodeJob, EpisodePool, default_workers
from mpcshare.run_table import StrategyRun
from mpcshare.training import train_bundle
from mpcshare.training.config import TrainConfig
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES

TIMING = ("step_p50_ms", "step_p99_ms", "realtime_factor")
RUNS = (StrategyRun("voluntary", "voluntary"), StrategyRun("reactive", "reactive"), StrategyRun("gate", "gate"),
        StrategyRun("random_handover", "schedule", schedule="random", draws=2),
        StrategyRun("oracle_handover", "schedule", schedule="oracle"))


@pytest.fixture(scope="module")
def trained() -> tuple[Demonstrations, object]:
    demos = generate_demonstrations(2, 3.0, seed=4)
    return demos, train_bundle(demos, TrainConfig(max_epochs=2), progress=False)


def _figures(strategies: dict) -> dict:
    return {name: {k: v for k, v in m.items() if k not in TIMING} for name, m in strategies.items()}


def test_the_comparison_and_the_rule_choice_are_the_same_on_one_and_two_workers(trained, tmp_path):
    demos, bundle = trained
    trials = bundle.heldout_trials[:1]
    results = {}
    for workers in (1, 2):
        with EpisodePool(demos, workers) as pool:
            comp = compare_strategies(bundle, demos, trials, runs=RUNS, duration_s=0.5, out=tmp_path / f"w{workers}",
                                      mode_names=MODE_NAMES, log=None, pool=pool)
            choice = choose_rule(bundle, demos, trials, duration_s=0.5, mode_names=MODE_NAMES, pool=pool)
        results[workers] = (_figures(comp.strategies), comp.run_files, choice["wearer_modes"],
                            [(r["wearer_modes"], r["timing"], r["tracking_rmse_m"]) for r in choice["candidates"]])
    assert results[1] == results[2]
    assert results[2][1]["random_handover"] == [f"runs/random_handover_trial{trials[0]}_draw{j}.npz" for j in (0, 1)]
    assert (tmp_path / "w2" / results[2][1]["oracle_handover"][0]).exists()


def test_workers_need_what_pickles_and_at_least_one_worker(trained):
    demos, bundle = trained
    with pytest.raises(ValueError, match="workers must be >= 1"):
        EpisodePool(demos, 0)
    job = EpisodeJob(bundle.heldout_trials[0], StrategyRun("voluntary", "voluntary"))
    with EpisodePool(demos, 2) as pool, pytest.raises(ValueError, match="defined at module level"):
        pool.map(lambda *a, **k: None, bundle, [job], beta=0.5)
    assert 1 <= default_workers() <= MAX_DEFAULT_WORKERS


def test_seconds_per_trial_reach_each_episode_live_and_replayed(trained):
    """``duration_s`` as {trial: seconds}: each trial's episode runs its own seconds (a trial missing from the
    mapping runs whole), the same whether the front end runs live or is replayed from a recording."""
    from mpcshare.evaluation.episode import simulate_episode, trial_seconds
    from mpcshare.evaluation.frontend_replay import simulate_cached

    demos, bundle = trained
    held = list(bundle.heldout_trials)
    seconds = {held[0]: 0.6, **({held[1]: 1.2} if len(held) > 1 else {})}
    job = StrategyRun("voluntary", "voluntary")
    jobs = [EpisodeJob(t, job) for t in held[:2]]
    settings = dict(beta=0.5, duration_s=seconds, seed=0, wearer=None, mode_names=MODE_NAMES)
    with EpisodePool(demos, 1) as pool:
        live = pool.map(simulate_episode, bundle, jobs, **settings)
        replayed = [r[:2] for r in pool.map(simulate_cached, bundle, jobs * 2, **settings)][len(jobs):]
    for j, (episode, _), (again, _) in zip(jobs, live, replayed):
        want = trial_seconds(seconds, j.trial)
        assert episode.t[-1] - episode.t[0] == pytest.approx(want, abs=0.02)
        assert again.t.shape == episode.t.shape and (again.tip == episode.tip).all()
    assert trial_seconds(seconds, -1) is None and trial_seconds(2.0, held[0]) == 2.0
