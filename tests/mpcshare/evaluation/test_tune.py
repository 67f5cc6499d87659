"""`mpcshare tune`: the closed-loop sweep, its files, its statistics and its backends."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from scipy import stats as st

from learning.data import save
from mpcshare.cli import main
from mpcshare.evaluation.tuning.episodes import TIMING_KEYS, plan_tasks, random_tasks, task_key
from mpcshare.evaluation.tuning.runner import run_tune
from mpcshare.evaluation.tuning.stats import gate_vs_random, pareto, recommend, summarise
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES
from tests.mpcshare.evaluation.tune_rows import tune_row as _row

SWEEP = ["--percentiles", "90", "70", "--betas", "0", "1", "--strategies", "gate", "--trials", "1",
         "--duration", "2", "--seeds", "2", "--draws", "2", "--epochs", "3", "--quiet", "--workers", "1"]


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    path = tmp_path_factory.mktemp("tune") / "demos.npz"
    save(generate_demonstrations(3, 4.0, seed=5), path)
    return path


@pytest.fixture(scope="module")
def swept(data, tmp_path_factory):
    out = tmp_path_factory.mktemp("tune_out")
    assert main(["tune", str(data), "--out", str(out), *SWEEP]) == 0
    return out


def _comparable(rows):
    return [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in rows]


def test_tiny_sweep_writes_the_three_files_with_the_documented_keys(swept):
    result = json.loads((swept / "tune.json").read_text())
    assert {"rows", "summary", "tests", "recommended", "pareto"} <= set(result)
    # 2 seeds x 1 trial x (voluntary + 2 reactive + 2x2 gate + 2x2x2 random_handover draws): what the tests need
    assert len(result["rows"]) == 2 * (1 + 2 + 4 + 8)
    assert result["multiple_testing"]["method"] == "Holm" and result["multiple_testing"]["m"] >= 1
    assert result["summary"]["voluntary"]["line_ratio"] == pytest.approx(1.0)
    assert all(result["summary"][n]["line_ratio"] is not None for n in result["tests"])
    for r in result["rows"]:
        assert {"percentile", "beta", "strategy", "trial", "seed", "tracking_rmse_m", "voluntary_effort",
                "saw_amplitude_ratio", "lag_s"} <= set(r)
    assert {r["strategy"] for r in result["rows"]} == {"voluntary", "reactive", "gate", "random_handover"}
    assert set(result["tests"]) == {"gate p90 b0", "gate p90 b1", "gate p70 b0", "gate p70 b1"}
    for t in result["tests"].values():
        (key,) = t
        assert "random" in key and {"p_value", "effect_m", "effect_ci95_m"} <= set(t[key])
        assert t[key]["n_pairs"] == 2 and t[key]["draws_per_pair"] == [2] and "p_holm" in t[key]
    assert "criterion" in result["recommended"] and result["recommended"]["setting"] in result["tests"]
    assert result["summary"]["voluntary"]["tracking_rmse_m"]["ci95"] is not None
    md = (swept / "tune.md").read_text()
    assert "Pareto set" in md and "Recommendation" in md and ("beats" in md or "does not beat chance" in md)
    assert "line ratio" in md and "Holm" in md
    assert (swept / "pareto.png").stat().st_size > 1000
    bundle = json.loads((swept / "bundles" / "p90" / "bundle.json").read_text())
    assert result["trials"] == bundle["heldout_trials"][:1]  # held-out trials of the bundles


def test_random_handover_keeps_the_matched_settings_share(swept):
    rows = json.loads((swept / "tune.json").read_text())["rows"]
    gates = {(r["percentile"], r["beta"], r["seed"]): r for r in rows if r["strategy"] == "gate"}
    for r in (r for r in rows if r["strategy"] == "random_handover"):
        g = gates[(r["percentile"], r["beta"], r["seed"])]
        assert r["matched_to"] == "gate"
        assert abs(r["reactive_share"] - g["reactive_share"]) <= 0.03
        assert r["handovers"] == g["handovers"]


def test_one_and_two_workers_give_the_same_rows_and_a_rerun_resumes(data, swept, tmp_path):
    kwargs = dict(percentiles=[90.0], betas=[0.5], strategies=["gate"], n_trials=1, seeds=[0, 1],
                  duration_s=1.5, wearer="hemiparetic_mild", progress=False, log=None, mode_names=MODE_NAMES)
    from mpcshare.training.config import TrainConfig

    cfg = TrainConfig(max_epochs=3)
    one = run_tune(data, tmp_path / "a", workers=1, config=cfg, **kwargs)
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "bundles").symlink_to(tmp_path / "a" / "bundles")  # the same bundles
    two = run_tune(data, tmp_path / "b", workers=2, config=cfg, **kwargs)
    assert _comparable(one["rows"]) == _comparable(two["rows"])
    lines = (tmp_path / "a" / "episodes.jsonl").read_text().splitlines()
    (tmp_path / "a" / "episodes.jsonl").write_text("\n".join(lines[:-2]) + "\n")  # interrupted: 2 lost
    again = run_tune(data, tmp_path / "a", workers=1, config=cfg, **kwargs)
    assert _comparable(again["rows"]) == _comparable(one["rows"])
    assert len((tmp_path / "a" / "episodes.jsonl").read_text().splitlines()) == len(lines)  # only 2 re-run


def test_the_plan_and_its_time_are_said_before_the_episodes_run(data, swept, tmp_path):
    from mpcshare.training.config import TrainConfig

    (tmp_path / "t").mkdir()
    (tmp_path / "t" / "bundles").symlink_to(swept / "bundles")  # trained: only the episodes run
    said: list[str] = []
    run = run_tune(data, tmp_path / "t", percentiles=[90.0], betas=[0.5], strategies=["gate"], n_trials=1,
                   seeds=[0], duration_s=0.5, wearer="hemiparetic_mild", progress=False, log=said.append,
                   mode_names=MODE_NAMES, draws=2, config=TrainConfig(max_epochs=3), workers=1)
    # voluntary, reactive p90, gate p90 b0.5 and its 2 placebo draws
    assert said[0] == ("tune plans 5 closed-loop episodes of 0.5 s: 3 of the settings and the parties, 2 placebo "
                       "draws (2 per setting episode), on 1 local worker(s)")
    assert re.fullmatch(r"about [0-9.]+ min for the [23] episodes left on 1 worker\(s\) \(measured: a bundle and "
                        r"trial's first episode in a worker [0-9.]+ s, the others [0-9.]+ s\)", said[1])
    assert len(run["rows"]) == 5 and said[2].endswith(" given the figures of an episode that decided alike")


def test_the_estimate_counts_recordings_and_replays():
    from mpcshare.evaluation.tuning.dispatch import Costs

    costs = Costs()
    task = plan_tasks([90.0], [0.5], ["gate"], [3], [0], {90.0: "b"}, "d", 1.0, "w")[0]
    costs.add(task, 6.0, pid=1)  # the first of bundle b, trial 3 in process 1: a recording
    assert not costs.ready(workers=2)
    costs.add(task, 4.0, pid=1)
    costs.add(task, 2.0, pid=1)
    assert costs.recorded == [6.0] and costs.replayed == [4.0, 2.0] and costs.ready(workers=2)
    # 2 processes x 2 bundles and trials = 4 recordings, 1 done: 3 more at 6 s, the other 7 at 3 s, on 2 processes
    assert costs.estimate(10, wheres=2, workers=2) == pytest.approx((3 * 6.0 + 7 * 3.0) / 2)


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


def test_gate_against_random_is_a_paired_one_sided_test():
    rng = np.random.default_rng(1)
    base = rng.uniform(0.01, 0.03, 8)  # per (trial, seed): a hard trial is hard for both
    gate_err = base
    rand_err = base + np.array([2, 1, 3, 0.5, 2, 1.5, -0.2, 1]) * 1e-3
    rows = []
    for i, (g, r) in enumerate(zip(gate_err, rand_err)):
        rows += [_row("gate", i % 2, i // 2, g), _row("random_handover", i % 2, i // 2, r, "gate")]
    rows = [rows[i] for i in rng.permutation(len(rows))]  # the order of rows must not matter
    test = gate_vs_random(rows)["gate p90 b0.5"]["vs_random_handover"]
    expected = st.wilcoxon(rand_err - gate_err, alternative="greater")
    assert test["p_value"] == pytest.approx(expected.pvalue) and test["n_pairs"] == 8
    assert test["n_forced"] == 4  # the seed-0 episodes handed over once: their placebo is forced
    assert test["p_value"] < 0.05 and test["beats_random"]
    assert test["effect_m"] == pytest.approx(np.mean(rand_err - gate_err))
    lo, hi = test["effect_ci95_m"]
    assert lo < test["effect_m"] < hi
    # unpaired, the spread between trials would hide the effect: the pairing is what is tested
    assert st.mannwhitneyu(rand_err, gate_err, alternative="greater").pvalue > 0.05
    worse = [dict(r, tracking_rmse_m=r["tracking_rmse_m"] + (3e-3 if r["strategy"] == "gate" else 0))
             for r in rows]
    t2 = gate_vs_random(worse)["gate p90 b0.5"]["vs_random_handover"]
    assert t2["p_value"] > 0.5 and not t2["beats_random"]
    rec = recommend(summarise(worse), gate_vs_random(worse))
    assert rec["setting"] == "gate p90 b0.5" and rec["beats_random"] is False and "criterion" in rec


def test_holm_and_the_placebo_as_the_mean_of_its_draws():
    from mpcshare.evaluation.tuning.stats import holm

    assert holm([0.01, 0.04, 0.03, None]) == pytest.approx([0.03, 0.06, 0.06, None], nan_ok=True)
    rng = np.random.default_rng(2)
    gate_err = rng.uniform(0.01, 0.03, 10)
    rows = []
    for i, g in enumerate(gate_err):  # two draws per pair: one 1 mm worse than the gate, one 3 mm
        rows += [_row("gate", i % 2, i // 2, g)]
        rows += [dict(_row("random_handover", i % 2, i // 2, g + d, "gate"), draw=j)
                 for j, d in enumerate((1e-3, 3e-3))]
    rows += [_row("blend", i % 2, i // 2, g + 1e-3) for i, g in enumerate(gate_err)]
    rows += [_row("random_handover", i % 2, i // 2, g, "blend") for i, g in enumerate(gate_err)]
    tests = gate_vs_random(rows)
    t = tests["gate p90 b0.5"]["vs_random_handover"]
    assert t["effect_m"] == pytest.approx(2e-3) and t["draws_per_pair"] == [1, 2]
    assert t["p_value"] == pytest.approx(0.5 ** 10) and t["p_holm"] == pytest.approx(2 * 0.5 ** 10)
    assert t["p_holm"] < 0.01 and t["beats_random"]
    assert not tests["blend p90 b0.5"]["vs_random_handover"]["beats_random"]


def test_pareto_keeps_the_settings_nothing_beats_on_both():
    rows = [_row("voluntary", 0, 0, 0.030, effort=0.5), _row("reactive", 0, 0, 0.010, effort=0.05),
            _row("gate", 0, 0, 0.020, effort=0.2), _row("blend", 0, 0, 0.012, effort=0.04)]
    rows[0]["percentile"] = rows[0]["beta"] = None
    assert pareto(summarise(rows)) == ["reactive p90 b0.5", "blend p90 b0.5"]


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


@pytest.mark.parametrize("args, needle", [
    (["--percentiles", "0"], "above 0 and at most 100"), (["--percentiles", "101"], "above 0 and at most 100"),
    (["--betas", "1.5"], "a number from 0 to 1"), (["--strategies", "wild"], "gate"),
])
def test_bad_input_gets_one_line_and_status_2(data, tmp_path, capsys, args, needle):
    with pytest.raises(SystemExit) as exc:
        main(["tune", str(data), "--out", str(tmp_path / "x"), *args])
    assert exc.value.code == 2 and needle in capsys.readouterr().err


def test_too_many_trials_and_missing_ray_are_usage_errors(data, swept, tmp_path, capsys):
    code = main(["tune", str(data), "--out", str(swept), *SWEEP, "--trials", "9"])
    assert code == 2 and "held-out trials" in capsys.readouterr().err
    try:
        import ray  # noqa: F401
    except ImportError:
        code = main(["tune", str(data), "--out", str(tmp_path / "r"), *SWEEP, "--backend", "ray"])
        assert code == 2 and "pip install -e .[ray]" in capsys.readouterr().err


def test_ray_gives_the_same_rows_as_the_local_pool(data, swept, tmp_path):
    pytest.importorskip("ray", reason="Ray is an optional extra (pip install -e .[ray]); not installed here")
    (tmp_path / "ray").mkdir()
    (tmp_path / "ray" / "bundles").symlink_to(swept / "bundles")
    assert main(["tune", str(data), "--out", str(tmp_path / "ray"), *SWEEP, "--backend", "ray"]) == 0
    local = json.loads((swept / "tune.json").read_text())["rows"]
    remote = json.loads((tmp_path / "ray" / "tune.json").read_text())["rows"]
    assert _comparable(local) == _comparable(remote)


def test_default_sweep_has_at_least_ten_pairs():
    from mpcshare.commands.tune import default_trials_and_seeds

    for n_heldout in (1, 2, 3, 4, 5, 8):
        t, s = default_trials_and_seeds(n_heldout, None, None)
        assert t == min(5, n_heldout) and t * s >= 10 and 0.5 ** (t * s) * 6 < 0.01  # Holm over 6 settings
    assert default_trials_and_seeds(4, None, None) == (4, 3)  # the default data: 4 held-out trials
    assert default_trials_and_seeds(4, 2, None) == (2, 5) and default_trials_and_seeds(4, 2, 1) == (2, 1)


def test_replaying_the_front_end_gives_the_rows_of_live_episodes(data, swept, monkeypatch):
    from mpcshare.evaluation import frontend_replay
    from mpcshare.evaluation.tuning import episodes

    bundles = {p: str(swept / "bundles" / f"p{p:g}") for p in (90.0, 70.0)}
    trial = json.loads((swept / "episodes.jsonl").read_text().splitlines()[0])["trial"]
    tasks = plan_tasks([90.0, 70.0], [0.0, 1.0], ["gate"], [trial], [1], bundles, str(data), 1.0, "hemiparetic_mild",
                       MODE_NAMES)
    frontend_replay._CACHE.clear()
    replayed = [episodes.run_task(t) for t in tasks]  # the first of each bundle records, the rest replay
    assert len(frontend_replay._CACHE) == 2
    monkeypatch.setattr(frontend_replay, "_MAX_CACHED", 0)  # nothing kept: every episode live
    frontend_replay._CACHE.clear()
    live = [episodes.run_task(t) for t in tasks]
    assert not frontend_replay._CACHE
    assert _comparable(replayed) == _comparable(live)
