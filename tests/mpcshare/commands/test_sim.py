"""`mpcshare sim`, the strategy comparison and the self-contained HTML report."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from learning.data import Demonstrations, load, save
from mpcshare.cli import main
from mpcshare.evaluation import METRIC_KEYS, pool_metrics
from mpcshare.reports.html import markdown_to_html
from sim.demonstrator import generate_demonstrations
from sim.episode import Episode
from tests.mpcshare.in_process import choose_rules_in_process


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("simcmd")
    data = root / "demos.npz"
    save(generate_demonstrations(2, 4.0, seed=2), data)
    model = root / "model"
    with pytest.MonkeyPatch.context() as patch:
        choose_rules_in_process(patch)
        assert main(["train", str(data), "--out", str(model), "--epochs", "5", "--quiet",
                     "--rule-duration", "3"]) == 0
    assert "skill vs hold" in (model / "training.md").read_text()  # the forecast's skill table
    return data, model


def test_sim_runs_held_out_trials_and_writes_the_comparison(trained, tmp_path):
    data, model = trained
    out = tmp_path / "sim"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "2",
                 "--runs", "voluntary", "gate"]) == 0
    comp = json.loads((out / "comparison.json").read_text())
    bundle_info = json.loads((model / "bundle.json").read_text())
    assert set(comp["strategies"]) == {"voluntary", "gate"}
    assert comp["trials"] == bundle_info["heldout_trials"][:1]  # held-out trials by default
    for metrics in comp["strategies"].values():
        assert set(METRIC_KEYS) <= set(metrics)
        assert metrics["limit_violations"] == 0
        assert metrics["reactive_share"] is not None
    assert comp["strategies"]["voluntary"]["reactive_share"] == 0.0
    run = Episode.load(out / comp["run_files"]["gate"][0])
    assert run.t.size == 200 and run.q.shape[1] == 3
    assert (out / "comparison.md").read_text().count("|") > 20 and (out / "trial.png").exists()
    assert comp["wearer"]["preset"] == "hemiparetic_mild"  # the default wearer, recorded
    assert comp["wearer"]["settings"]["reaction_delay_s"] == 0.3
    predicted = json.loads((model / "rule.json").read_text())["rule"]["choice"]["predicted"]  # the choice's record
    check = comp["rule_check"]  # beside the gate's realised figures (no reactive run: no line ratio to compare)
    assert check["run"] == "gate" and check["predicted"]["effort_vs_voluntary"] == predicted["effort_vs_voluntary"]
    assert check["realised"]["effort_vs_voluntary"] is not None and check["line_ratio_gap"] is None
    assert "**The choice: not comparable.**" in (out / "comparison.md").read_text()


def test_sim_wearer_preset_reaches_the_episodes(trained, tmp_path, capsys):
    data, model = trained
    out = tmp_path / "severe"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "1",
                 "--runs", "voluntary", "--wearer", "hemiparetic_severe"]) == 0
    comp = json.loads((out / "comparison.json").read_text())
    assert comp["wearer"]["preset"] == "hemiparetic_severe"
    assert comp["wearer"]["settings"]["rhythmic_bandwidth_hz"] == 1.5
    assert "Simulated wearer: hemiparetic_severe." in (out / "comparison.md").read_text()
    run = Episode.load(out / comp["run_files"]["voluntary"][0])
    assert run.info["wearer_preset"] == "hemiparetic_severe"
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--model", str(model), "--out", str(tmp_path / "x"), "--wearer", "nobody"])
    assert exc.value.code == 2 and "hemiparetic_mild" in capsys.readouterr().err


def test_sim_maps_renamed_channels_and_names_what_is_missing(trained, tmp_path, capsys):
    data, model = trained
    demos = load(data)
    renamed = Demonstrations(demos.trials, demos.rate_hz, [f"sensor{i}" for i in range(demos.obs_dim)],
                             list(demos.act_names), list(demos.vol_names))
    other = tmp_path / "renamed.npz"
    save(renamed, other)
    code = main(["sim", "--model", str(model), "--data", str(other), "--out", str(tmp_path / "a"),
                 "--trials", "1", "--duration", "1", "--runs", "gate"])
    assert code == 1
    assert "fork_x" in capsys.readouterr().err
    mapping = [f"{name}=sensor{i}" for i, name in enumerate(demos.obs_names)]
    code = main(["sim", "--model", str(model), "--data", str(other), "--out", str(tmp_path / "b"),
                 "--trials", "1", "--duration", "1", "--runs", "gate", "--map", *mapping])
    assert code == 0
    assert json.loads((tmp_path / "b" / "comparison.json").read_text())["strategies"]["gate"]


def test_sim_refuses_a_missing_bundle(tmp_path, capsys):
    assert main(["sim", "--model", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 1
    assert "nope" in capsys.readouterr().err


def test_pooled_metrics_equal_the_metrics_of_the_pooled_steps():
    rng = np.random.default_rng(0)
    errors = [rng.normal(0, 0.01, n) for n in (300, 100)]
    steps = [rng.uniform(0.0005, 0.002, e.size) for e in errors]
    alphas = [rng.uniform(size=e.size) > 0.3 for e in errors]
    per = [{"tracking_rmse_m": math.sqrt(np.mean(e**2)), "tracking_p95_m": 0.0, "voluntary_effort": 0.1,
            "reactive_share": float(a.mean()), "handovers": 2, "conflict_share": 0.0, "limit_violations": 0,
            "step_p50_ms": 0.0, "step_p99_ms": 0.0, "realtime_factor": 5.0} for e, a in zip(errors, alphas)]
    pooled = pool_metrics(per, steps, [3.0, 1.0])
    all_e, all_a, all_s = np.concatenate(errors), np.concatenate(alphas), np.concatenate(steps)
    assert pooled["tracking_rmse_m"] == pytest.approx(math.sqrt(np.mean(all_e**2)), rel=1e-12)
    assert pooled["reactive_share"] == pytest.approx(all_a.mean(), rel=1e-12)
    assert pooled["step_p99_ms"] == pytest.approx(np.percentile(all_s, 99) * 1e3, rel=1e-12)
    assert pooled["handovers"] == 4 and pooled["realtime_factor"] == pytest.approx(5.0)
    with pytest.raises(ValueError, match="no episodes"):
        pool_metrics([], [], [])


def test_html_report_embeds_local_images_and_lists_missing_ones(tmp_path):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2, 2))
    fig.subplots().plot([0, 1], [1, 0])
    fig.savefig(tmp_path / "p.png")
    page, missing = markdown_to_html("# T\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n![plot](p.png)\n\n![gone](q.png)\n",
                                     tmp_path)
    assert "<table>" in page and 'src="data:image/png;base64,' in page
    assert missing == ["q.png"] and "file not found" in page


def test_sim_runs_the_placebo_and_the_oracle_hand_overs_beside_the_gate(trained, tmp_path):
    data, model = trained
    out = tmp_path / "handover"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "3",
                 "--runs", "voluntary", "reactive", "gate", "random_handover", "oracle_handover"]) == 0
    comp = json.loads((out / "comparison.json").read_text())
    assert set(comp["strategies"]) == {"voluntary", "reactive", "gate", "random_handover", "oracle_handover"}
    assert len(comp["run_files"]["random_handover"]) == 5  # five seeded draws
    s, per = comp["strategies"], comp["per_trial"]
    # the upper bound is never worse than the better party, per trial and pooled
    better = min(s["voluntary"]["tracking_rmse_m"], s["reactive"]["tracking_rmse_m"])
    assert s["oracle_handover"]["tracking_rmse_m"] <= better + 1e-12
    for tid, m in per["oracle_handover"].items():
        assert m["tracking_rmse_m"] <= min(per[k][tid]["tracking_rmse_m"] for k in ("voluntary", "reactive")) + 1e-12
    assert s["voluntary"]["line_ratio"] == pytest.approx(1.0) and s["reactive"]["line_ratio"] == pytest.approx(1.0)
    assert s["gate"]["line_ratio"] is not None
    gate = Episode.load(out / comp["run_files"]["gate"][0])
    draws = [Episode.load(out / f) for f in comp["run_files"]["random_handover"]]
    for run in draws:  # the gate's share of robot control and hand-overs, at other times
        assert abs(np.mean(run.alpha > 0.5) - np.mean(gate.alpha > 0.5)) <= 0.02
        assert np.count_nonzero(np.diff(run.alpha > 0.5)) == np.count_nonzero(np.diff(gate.alpha > 0.5))
    assert comp["strategies"]["oracle_handover"]["limit_violations"] == 0
    md = (out / "comparison.md").read_text()
    assert "at random times" in md and "minimise the error" in md and "line ratio" in md


def test_sim_on_another_arm_from_its_file(trained, tmp_path, capsys):
    """``--robot FILE --tip-frame NAME --mount X Y Z``: the Panda of example-robot-data beside the plate."""
    from tests.sim.second_arm import PANDA_FINGERS, PANDA_TIP, panda_path

    data, model = trained
    arm = ["--robot", str(panda_path()), "--tip-frame", PANDA_TIP, "--mount", "0", "-0.45", "0",
           "--mount-rpy", "0", "0", "1.5708", "--lock-joints", *PANDA_FINGERS, "--velocity-limit", "1.5",
           "--acceleration-limit", "8"]
    out = tmp_path / "panda"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "1",
                 "--runs", "reactive", *arm]) == 0
    comp = json.loads((out / "comparison.json").read_text())
    assert comp["strategies"]["reactive"]["limit_violations"] == 0
    assert Episode.load(out / comp["run_files"]["reactive"][0]).q.shape[1] == 7
    assert "panda (7 joints" in capsys.readouterr().out
    wrong = [a if a != PANDA_TIP else "knife" for a in arm]
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "w"), "--runs", "reactive", *wrong]) == 1
    err = capsys.readouterr().err
    assert "'knife'" in err and PANDA_TIP in err  # the valid frames are named
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "m"), "--runs", "reactive",
                 *arm[:4]]) == 1
    assert "--mount" in capsys.readouterr().err
    fast = arm[:-2] + ["--acceleration-limit", "80"]
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "f"), "--runs", "reactive", *fast]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "braking at 40 rad/s²" in err and "--acceleration-limit" in err


def test_the_announced_size_is_within_ten_percent_of_the_run_files_written(trained, tmp_path, capsys):
    import re

    data, model = trained
    out = tmp_path / "sized"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "3",
                 "--runs", "voluntary", "reactive", "gate", "oracle_handover"]) == 0
    said = capsys.readouterr().out
    number, unit = re.search(r"writing about ([\d.]+) (kB|MB) of run files", said).groups()
    announced = float(number) * {"kB": 1e3, "MB": 1e6}[unit]
    written = sum(p.stat().st_size for p in (out / "runs").iterdir())
    assert abs(announced / written - 1) < 0.10, (announced, written)
    assert said.index("writing about") < said.index("voluntary")  # said before the first run
    assert len(list((out / "runs").iterdir())) == 4  # the oracle keeps one run file per trial: its best


def test_sim_on_an_arm_preset_chooses_and_says_its_caps(trained, tmp_path, capsys):
    """``--robot panda``: the preset's file, tip, fingers and mount; the caps chosen and printed in one line."""
    data, model = trained
    out = tmp_path / "preset"
    assert main(["sim", "--model", str(model), "--out", str(out), "--trials", "1", "--duration", "1",
                 "--runs", "reactive", "--robot", "panda"]) == 0
    printed = capsys.readouterr().out
    caps = [line for line in printed.splitlines() if line.startswith("arm caps: ")]
    assert len(caps) == 1 and "rad/s²" in caps[0] and "chosen" in caps[0]
    comp = json.loads((out / "comparison.json").read_text())
    assert comp["strategies"]["reactive"]["limit_violations"] == 0
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "x"), "--robot", "pandas"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("mpcshare sim: --robot pandas: no arm preset 'pandas'; presets: panda, xarm7")


def test_sim_video_renders_headless_or_says_why_once(trained, tmp_path, capsys, monkeypatch):
    """``python -m mpcshare sim --video`` with neither DISPLAY nor MUJOCO_GL set writes the clip; without an
    OpenGL context the command says so in one line, once."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    data, model = trained
    root = Path(__file__).resolve().parents[3]
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "MUJOCO_GL", "PYOPENGL_PLATFORM")}
    env["PYTHONPATH"] = os.pathsep.join([str(root), env.get("PYTHONPATH", "")])
    out = tmp_path / "video"
    run = subprocess.run([sys.executable, "-m", "mpcshare", "sim", "--model", str(model), "--out", str(out),
                          "--trials", "1", "--duration", "1", "--runs", "gate", "--video"], capture_output=True,
                         text=True, env=env, cwd=root, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "no video" not in run.stdout + run.stderr and "GLFW" not in run.stderr
    video = json.loads((out / "comparison.json").read_text())["video"]
    assert video and (out / video).stat().st_size > 10_000

    import sim.render

    def no_gl(*args, **kwargs):
        raise RuntimeError("an OpenGL platform library has not been loaded")

    monkeypatch.setattr(sim.render.mujoco, "Renderer", no_gl)
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "novideo"), "--trials", "1", "--duration",
                 "1", "--runs", "gate", "--video"]) == 0
    captured = capsys.readouterr()
    said = [line for line in (captured.out + captured.err).splitlines() if "no video" in line]
    assert len(said) == 1 and said[0].startswith("no video: offscreen OpenGL is not available") \
        and "no video: no video" not in said[0] and "MUJOCO_GL" in said[0]


#: a task of the user's own, outside the package: eating's four mode labels under other names, no strokes,
#: judged by its lag alone
_TIDYING = '''
import numpy as np

from robot.shoulder import ShoulderMap
from sim.task import EATING
from sim.task.metrics import rms_by_mode, time_lag, wearer_share_by_mode


class Tidying:
    name = "tidying"
    mode_names = ("sweep", "carry", "gather", "drop")
    mode_colours = {"sweep": "#111111", "carry": "#222222", "gather": "#333333", "drop": "#444444"}
    stroke_mode = None
    stroke_band_hz = None
    criterion = "the tip within 0.2 s of the intent"
    metric_keys = ("lag_s", "rms_by_mode_m", "wearer_share_by_mode", "mode_steps")
    body = EATING.body
    shoulder_channels = EATING.shoulder_channels
    shoulder_to_plate = EATING.shoulder_to_plate

    def episode_metrics(self, tip, intent, dt, true_mode, mode_names=None, alpha=None):
        lag, _ = time_lag(tip, intent, dt)
        out = {"lag_s": None if not np.isfinite(lag) else lag, "rms_by_mode_m": {}, "wearer_share_by_mode": {},
               "mode_steps": {}}
        if true_mode is not None:
            out["rms_by_mode_m"] = rms_by_mode(tip, intent, true_mode, tuple(mode_names or ()))
            if alpha is not None:
                out["wearer_share_by_mode"], out["mode_steps"] = wearer_share_by_mode(alpha, true_mode,
                                                                                      tuple(mode_names or ()))
        return out

    def done(self, metrics):
        return metrics.get("lag_s") is not None and abs(metrics["lag_s"]) <= 0.2

    def shoulder_map(self, names=(), gain=0.5, deadband_rad=0.01):
        return ShoulderMap.for_channels(names, self.shoulder_channels, self.shoulder_to_plate, gain, deadband_rad)


TASK = Tidying()
'''


def test_sim_runs_the_task_the_bundle_was_trained_for_and_refuses_another(trained, tmp_path, monkeypatch, capsys):
    from mpcshare.bundle import load_bundle, save_bundle

    data, model = trained
    assert json.loads((model / "bundle.json").read_text())["config"]["task"] == "eating"  # recorded by train
    (tmp_path / "tidying_for_test.py").write_text(_TIDYING)
    monkeypatch.syspath_prepend(str(tmp_path))
    spec = "tidying_for_test:TASK"
    assert main(["sim", "--model", str(model), "--out", str(tmp_path / "a"), "--task", spec]) == 1
    err = capsys.readouterr().err.strip()
    assert err == (f"mpcshare sim: --task {spec}: the bundle was trained for task 'eating' (modes cutting, "
                   f"repositioning, collecting, removing); leave --task out, or train it again with --task {spec}")
    with pytest.raises(SystemExit) as exc:
        main(["sim", "--model", str(model), "--out", str(tmp_path / "b"), "--task", "tidying"])
    assert exc.value.code == 2 and "unknown task 'tidying'; valid choices: eating" in capsys.readouterr().err
    bundle = load_bundle(model)
    bundle.config["task"] = spec  # as `mpcshare train --task tidying_for_test:TASK` records it
    save_bundle(bundle, tmp_path / "tidying_model")
    out = tmp_path / "tidying"
    assert main(["sim", "--model", str(tmp_path / "tidying_model"), "--out", str(out), "--trials", "1",
                 "--duration", "1", "--runs", "voluntary", "gate"]) == 0
    printed = capsys.readouterr().out
    comp = json.loads((out / "comparison.json").read_text())
    gate = comp["strategies"]["gate"]
    assert "saw_correlation" not in gate and set(gate["wearer_share_by_mode"]) <= {"sweep", "carry", "gather", "drop"}
    assert gate["wearer_share_by_mode"] and set(gate["rms_by_mode_m"]) == set(gate["wearer_share_by_mode"])
    md = (out / "comparison.md").read_text()
    verdict = "yes, done" if abs(gate["lag_s"]) <= 0.2 else "NO, not done"
    assert f"**The task: {verdict}.**" in md and "(the tip within 0.2 s of the intent)" in md  # its criterion
    assert any(f"| {mode} |" in md for mode in gate["wearer_share_by_mode"])  # its mode names
    assert "cutting" not in md and "saw" not in md.lower()
    assert f"The task: {verdict}." in printed
