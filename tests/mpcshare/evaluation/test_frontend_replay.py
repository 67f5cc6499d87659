"""The front end recorded in one episode and replayed in others: the same episodes, to the last bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from learning.data import Demonstrations
from mpcshare.calibration import rule_choice
from mpcshare.control.controller import SharedController
from mpcshare.control.keepout import KeepOut
from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation import compare_strategies, frontend_replay, runs
from mpcshare.evaluation.distinct import decision_trace
from mpcshare.evaluation.episode import simulate_episode
from mpcshare.evaluation.frontend_replay import (
    FrontEndRecording,
    decisions,
    record_front_end,
    replay_front_end,
    simulate_cached,
)
from mpcshare.run_table import StrategyRun
from mpcshare.training import train_bundle
from mpcshare.training.config import TrainConfig
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES

TIMING = ("step_p50_ms", "step_p99_ms", "realtime_factor")
SETTINGS = {"beta": 0.5, "duration_s": 1.0, "seed": 1, "wearer": None, "mode_names": MODE_NAMES}
ZONES = {"beta": 0.5, "duration_s": 1.0, "wearer": None, "mode_names": MODE_NAMES}


@pytest.fixture(scope="module")
def trained() -> tuple[Demonstrations, object]:
    demos = generate_demonstrations(2, 3.0, seed=4)
    return demos, train_bundle(demos, TrainConfig(max_epochs=2), progress=False)


def _trial(demos, tid):
    return next(t for t in demos.trials if t.trial_id == tid)


def _record(bundle, demos, trial) -> tuple[tuple[object, dict], FrontEndRecording]:
    """The voluntary episode on ``trial``, its front end recorded."""
    out = []

    def make(b, **o):
        c = SharedController.from_bundle(b, **o)
        out.append(record_front_end(c))
        return c
    done = simulate_episode(bundle, demos, trial, StrategyRun("voluntary", "voluntary"), {}, make_controller=make,
                            **SETTINGS)
    return done, out[0]


def _same(a, b) -> None:
    (ea, ma), (eb, mb) = a, b
    assert {k: v for k, v in ma.items() if k not in TIMING} == {k: v for k, v in mb.items() if k not in TIMING}
    for field in ("tip", "alpha", "beta", "q", "tau", "voluntary", "tip_reference", "novelty"):
        assert np.array_equal(getattr(ea, field), getattr(eb, field), equal_nan=True), field
    assert list(ea.status) == list(eb.status)


def test_a_replayed_episode_is_the_live_one(trained):
    demos, bundle = trained
    trial = _trial(demos, bundle.heldout_trials[0])
    recorded, recording = _record(bundle, demos, trial)
    assert recording.steps == 100
    _same(recorded, simulate_episode(bundle, demos, trial, StrategyRun("voluntary", "voluntary"), {}, **SETTINGS))
    frontend_replay._CACHE.clear()
    gate = {"config": ControllerConfig(strategy_settings={"wearer_modes": [1], "share_on": 0.2, "share_off": 0.1})}
    for name, strategy, options in [("reactive", "reactive", {}), ("paper_gate", "paper_gate", {}),
                                    ("blend", "blend", {}), ("gate", "gate", gate)]:
        run = StrategyRun(name, strategy)
        live = simulate_episode(bundle, demos, trial, run, options, **SETTINGS)
        checks = []

        def make(b, **o):
            c = SharedController.from_bundle(b, **o)
            checks.append(replay_front_end(c, recording))
            return c
        replayed = simulate_episode(bundle, demos, trial, run, options, make_controller=make, **SETTINGS)
        assert checks[0]() is None, name  # replayed, not run live
        _same(live, replayed)
        *cached, seen = simulate_cached(bundle, demos, trial, run, options, **SETTINGS)  # recorded, then replayed
        _same(live, tuple(cached))
        assert np.array_equal(seen, decisions(recording), equal_nan=True)
    assert len(frontend_replay._CACHE) == 1


def test_a_recording_of_another_trial_diverges_and_the_episode_runs_live(trained):
    demos, bundle = trained
    a, b = _trial(demos, bundle.heldout_trials[0]), _trial(demos, bundle.train_trials[0])
    _, recording = _record(bundle, demos, a)
    checks = []

    def make(bd, **o):
        c = SharedController.from_bundle(bd, **o)
        checks.append(replay_front_end(c, recording))
        return c
    simulate_episode(bundle, demos, b, StrategyRun("gate", "gate"), {}, make_controller=make, **SETTINGS)
    assert "differs from the recording" in checks[0]()
    run = StrategyRun("gate", "gate")
    frontend_replay._CACHE.clear()
    simulate_cached(bundle, demos, a, run, {}, **SETTINGS)
    (key, (_, rec)), = frontend_replay._CACHE.items()
    frontend_replay._CACHE[key[:2] + (b.trial_id,) + key[3:]] = (bundle, rec)  # a's recording filed under b
    *cached, seen = simulate_cached(bundle, demos, b, run, {}, **SETTINGS)
    assert seen is None  # diverged: run live
    _same(simulate_episode(bundle, demos, b, run, {}, **SETTINGS), tuple(cached))


def test_a_strategy_that_reads_the_wearers_command_has_no_predicted_decisions(trained):
    demos, bundle = trained
    trial = _trial(demos, bundle.heldout_trials[0])
    _, recording = _record(bundle, demos, trial)

    def trace(**options):
        c = SharedController.from_bundle(bundle, strategy="gate", config=ControllerConfig(strategy_settings=options))
        return decision_trace(c.arbiter, decisions(recording))
    assert trace(push_mps=0.05) is None
    assert trace(push_mps=math.inf) == trace() and trace() is not None
    assert trace(wearer_modes=[0, 1, 2, 3]) != trace(wearer_modes=[])


def _live(monkeypatch) -> None:
    """The comparison and the rule choice without replaying or deduplicating (the code before)."""
    def live(bundle, demos, trial, run, options, **settings):
        return (*simulate_episode(bundle, demos, trial, run, options, **settings), None)
    monkeypatch.setattr(runs, "simulate_cached", live)
    pooled = rule_choice.pooled_runs
    monkeypatch.setattr(rule_choice, "pooled_runs",
                        lambda *a, seen=None, ran=None, **kw: pooled(*a, seen=None, ran=ran, **kw))


def test_the_comparison_and_the_rule_choice_are_the_same_replayed_and_deduplicated(trained, tmp_path, monkeypatch):
    demos, bundle = trained
    trials = [bundle.heldout_trials[0], bundle.train_trials[0]]
    run_list = (StrategyRun("voluntary", "voluntary"), StrategyRun("reactive", "reactive"),
                StrategyRun("gate", "gate"), StrategyRun("random_handover", "schedule", schedule="random", draws=2))
    results, counts = [], []
    for live in (False, True):
        if live:
            _live(monkeypatch)
        comp = compare_strategies(bundle, demos, trials, runs=run_list, duration_s=0.6, out=tmp_path / str(live),
                                  mode_names=MODE_NAMES, log=None)
        choice = rule_choice.choose_rule(bundle, demos, trials, duration_s=0.6, mode_names=MODE_NAMES)
        choice.pop("seconds")
        counts.append(choice.pop("episodes_run"))
        results.append(({n: {k: v for k, v in m.items() if k not in TIMING} for n, m in comp.strategies.items()},
                        choice))
    assert results[0] == results[1]
    assert counts[0] < counts[1]  # some candidates decide as another at every step: run once


def test_a_candidate_that_decides_as_an_earlier_batchs_episode_is_that_episode(trained):
    """A gate whose wearer leads every mode at share 0 decides as ``voluntary`` at every step: with the first
    batch's episodes ``known``, it runs no episode and has the figures of simulating it live."""
    demos, bundle = trained
    trials = [bundle.heldout_trials[0]]
    everything = {"wearer_modes": list(range(bundle.n_modes)), "wearer_alpha": 0.0, "share_on": 0.0,
                  "share_off": 0.0}
    seen, known, ran = {}, {}, []
    args = (bundle, demos, trials)
    common = {"duration_s": 0.6, "wearer": None, "seed": 0, "mode_names": MODE_NAMES, "seen": seen, "ran": ran,
              "known": known}
    (vol, _), = rule_choice.pooled_runs(*args, [("voluntary", None)], **common)
    assert known and seen
    (gate, _), = rule_choice.pooled_runs(*args, [("gate", everything)], **common)
    assert ran == [1, 0]
    (live, _), = rule_choice.pooled_runs(*args, [("gate", everything)], 0.6, None, 0, MODE_NAMES)
    assert gate == vol
    assert {k: v for k, v in live.items() if k not in TIMING} == {k: v for k, v in gate.items() if k not in TIMING}


def test_a_replayed_episode_with_its_zones_is_the_live_one(trained, monkeypatch):
    """The keep-out's zones given back (the recording's seed) or run live (another seed's sway): every array
    and metric of the episode is the live one's."""
    demos, bundle = trained
    trial = next(t for t in demos.trials if t.trial_id == bundle.heldout_trials[0])
    frontend_replay._CACHE.clear()
    simulate_cached(bundle, demos, trial, StrategyRun("voluntary", "voluntary"), {}, seed=1, **ZONES)
    real, live_calls = KeepOut.update, []
    monkeypatch.setattr(KeepOut, "update", lambda self, *a: (live_calls.append(1), real(self, *a))[1])
    for seed, given_back in ((1, True), (2, False)):
        run = StrategyRun("gate", "gate")
        live = simulate_episode(bundle, demos, trial, run, {}, seed=seed, **ZONES)
        n_live = len(live_calls)
        episode, metrics, known = simulate_cached(bundle, demos, trial, run, {}, seed=seed, **ZONES)
        assert known is not None  # replayed, not run again live
        assert (len(live_calls) == n_live) is given_back and len(live_calls) - n_live in (0, len(episode.t))
        for name, value in vars(live[0]).items():
            if isinstance(value, np.ndarray) and name != "step_time":
                assert np.array_equal(value, getattr(episode, name), equal_nan=value.dtype.kind == "f"), name
        assert {k: v for k, v in live[1].items() if k not in TIMING} == \
            {k: v for k, v in metrics.items() if k not in TIMING}
