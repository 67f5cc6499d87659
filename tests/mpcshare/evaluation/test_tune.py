"""`mpcshare tune`: the closed-loop sweep, its files, its rows in one or two workers or Ray, its usage errors."""

from __future__ import annotations

import json
import re

import pytest

from mpcshare.cli import main
from mpcshare.evaluation.tuning.episodes import TIMING_KEYS, plan_tasks
from mpcshare.evaluation.tuning.runner import run_tune
from sim.task.eating import MODE_NAMES
from tests.mpcshare.evaluation.tune_rows import SWEEP


def _comparable(rows):
    return [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in rows]


def test_tiny_sweep_writes_the_three_files_with_the_documented_keys(swept):
    result = json.loads((swept / "tune.json").read_text())
    assert {"rows", "summary", "tests", "recommended", "pareto"} <= set(result)
    # 2 seeds x 1 trial x (voluntary + 2 reactive + 2x2 gate + 2x2x2 random_handover draws): what the tests need
    assert len(result["rows"]) == 2 * (1 + 2 + 4 + 8)
    assert result["multiple_testing"]["method"] == "Holm"
    # the settings tested: those with a pair where they handed over more than once (else its placebo is its own)
    assert result["multiple_testing"]["m"] == sum(t["vs_random_handover"]["p_value"] is not None
                                                  for t in result["tests"].values())
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
        assert t[key]["n_pairs"] + t[key]["n_forced"] == 2 and t[key]["draws_per_pair"] == [2] and "p_holm" in t[key]
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
    for run in ("a", "b"):  # the sweep's bundles: only the episodes run
        (tmp_path / run).mkdir()
        (tmp_path / run / "bundles").symlink_to(swept / "bundles")
    one = run_tune(data, tmp_path / "a", workers=1, config=cfg, **kwargs)
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
