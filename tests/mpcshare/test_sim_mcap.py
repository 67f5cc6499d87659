"""Runs as MCAP from ``mpcshare sim --mcap`` and ``compare_strategies(..., mcap=True)``.

The controller is a test double (tests/sim/controllers.py) and the bundle a stand-in
with what ``sim`` reads of it, so that these tests take seconds, not a training run.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest
from mcap.reader import make_reader

import mpcshare.bundle
import mpcshare.evaluation.runs
from learning.data import save
from mpcshare.cli import main
from mpcshare.evaluation import StrategyRun, compare_strategies
from sim.closed_loop import Episode
from sim.demonstrator import generate_demonstrations
from tests.sim.controllers import IdleController


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(n_subjects=1, minutes=0.1, seed=5)


def _idle(bundle, **options):
    return IdleController()


def _counts(path):
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    return {ch.topic: summary.statistics.channel_message_counts[i] for i, ch in summary.channels.items()}


def test_compare_strategies_writes_mcap_beside_the_run_files(demos, tmp_path):
    comp = compare_strategies(None, demos, [0], runs=[StrategyRun("voluntary", "voluntary")], duration_s=0.4,
                              out=tmp_path, make_controller=_idle, log=None, mcap=True)
    npz = tmp_path / comp.run_files["voluntary"][0]
    mcap = npz.with_suffix(".mcap")
    assert npz.exists() and mcap.exists()
    counts = _counts(mcap)
    assert counts["/knife/tip"] == len(Episode.load(npz).t) == 40 and counts["/fork/pose"] == 40
    assert counts["/arm/joint_states"] == 400


def test_no_mcap_by_default(demos, tmp_path):
    compare_strategies(None, demos, [0], runs=[StrategyRun("voluntary", "voluntary")], duration_s=0.2,
                       out=tmp_path, make_controller=_idle, log=None)
    assert sorted(p.suffix for p in (tmp_path / "runs").iterdir()) == [".npz"]


def test_mcap_rate_thins_the_joint_states(demos, tmp_path):
    comp = compare_strategies(None, demos, [0], runs=[StrategyRun("voluntary", "voluntary")], duration_s=0.4,
                              out=tmp_path, make_controller=_idle, log=None, mcap=True, mcap_rate_hz=100.0)
    counts = _counts((tmp_path / comp.run_files["voluntary"][0]).with_suffix(".mcap"))
    assert counts["/arm/joint_states"] == 40 and counts["/knife/tip"] == 40  # 1 kHz → 100 Hz; control rate kept


def _stand_in_bundle(demos, tmp_path, monkeypatch) -> None:
    """`mpcshare sim --model stand-in` loads a stand-in bundle over ``demos`` whose controllers idle."""
    data = tmp_path / "demos.npz"
    save(demos, data)
    bundle = SimpleNamespace(obs_names=list(demos.obs_names), act_names=list(demos.act_names),
                             vol_names=list(demos.vol_names), rate_hz=demos.rate_hz, heldout_trials=[0],
                             config={"data_path": str(data)})
    monkeypatch.setattr(mpcshare.bundle, "load_bundle", lambda path: bundle)
    monkeypatch.setattr(mpcshare.evaluation.runs, "_from_bundle", _idle)


def test_the_size_is_announced_before_writing_and_near_what_is_written(demos, tmp_path, monkeypatch, capsys):
    _stand_in_bundle(demos, tmp_path, monkeypatch)
    from mpcshare.evaluation import DEFAULT_RUNS, output_size

    out = tmp_path / "sim"
    assert main(["sim", "--model", "stand-in", "--out", str(out), "--duration", "3", "--runs", "voluntary",
                 "--mcap", "--mcap-rate", "200"]) == 0
    said = capsys.readouterr().out
    assert " of run files (NPZ) and " in said and " of MCAP" in said and "--mcap-rate HZ" in said
    npz, mcap = output_size(DEFAULT_RUNS[:1], demos, [0], 3.0, True, 200.0)
    written = {p.suffix: p.stat().st_size for p in (out / "runs").iterdir()}
    assert 0.9 < written[".npz"] / npz < 1.1 and 0.5 < written[".mcap"] / mcap < 2.0, (written, npz, mcap)


def test_sim_command_mcap_option(demos, tmp_path, monkeypatch):
    _stand_in_bundle(demos, tmp_path, monkeypatch)
    out = tmp_path / "sim"
    assert main(["sim", "--model", "stand-in", "--out", str(out), "--duration", "0.3", "--runs", "voluntary",
                 "--mcap"]) == 0
    assert _counts(out / "runs" / "voluntary_trial0.mcap")["/control/status"] == 30
