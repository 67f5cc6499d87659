"""The sweep's plan (mpcshare.evaluation.tuning.episodes): every setting on the same trials and seeds."""

from __future__ import annotations

from mpcshare.evaluation.tuning.episodes import plan_tasks, random_tasks, task_key


def test_plan_pairs_every_setting_with_the_same_trials_and_seeds():
    bundles = {90.0: "b90", 70.0: "b70"}
    tasks = plan_tasks([90.0, 70.0], [0.0, 1.0], ["gate", "blend"], [3, 4], [0, 1], bundles, "d.npz", 2.0,
                       "hemiparetic_mild")
    assert len({task_key(t) for t in tasks}) == len(tasks) == 2 * 2 * (1 + 2 * (1 + 4))
    with_bound = plan_tasks([90.0], [0.5], ["gate"], [3], [0], bundles, "d.npz", 2.0, "hemiparetic_mild", oracle=True)
    assert [t.strategy for t in with_bound] == ["voluntary", "oracle_preview", "reactive", "gate"]
    settings = [t for t in tasks if t.strategy in ("gate", "blend")]
    rows = [{"strategy": t.strategy, "matched_to": None, "percentile": t.percentile, "beta": t.beta,
             "trial": t.trial, "seed": t.seed, "schedule": {"steps": 10}} for t in settings]
    rand = random_tasks(rows, tasks, 1)
    assert [(t.matched_to, t.percentile, t.beta, t.trial, t.seed) for t in rand] == \
        [(t.strategy, t.percentile, t.beta, t.trial, t.seed) for t in settings]
    five = random_tasks(rows, tasks)  # the default: 5 draws per setting episode, each its own task
    assert len(five) == 5 * len(settings) and len({task_key(t) for t in five}) == len(five)
