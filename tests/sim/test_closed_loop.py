"""Short closed loops with controllers written here: limits in the physics, sane metrics, the run file."""

import dataclasses
import json

import numpy as np
import pytest

from robot.superlimb import SuperLimbParams
from sim.closed_loop import fork_pose_rows, run_episode
from sim.demonstrator import generate_demonstrations
from sim.episode import CONTROL_KEYS, PHYSICS_KEYS, Episode
from sim.metrics import METRIC_KEYS, episode_metrics
from sim.wearer import WearerConfig
from tests.sim.controllers import (
    AggressiveController,
    IdleController,
    OracleController,
    TestCommand,
    VoluntaryController,
)

P = SuperLimbParams()


@pytest.fixture(scope="module")
def trial():
    return generate_demonstrations(n_subjects=1, minutes=0.5, seed=11).trials[0]


@pytest.fixture(scope="module")
def oracle_episode(trial):
    return run_episode(OracleController(trial.act[:, :3]), trial, duration_s=8.0, seed=1)


@pytest.fixture(scope="module")
def idle_episode(trial):
    return run_episode(IdleController(), trial, duration_s=5.0, seed=1)


def _check_limits_in_physics(ep: Episode) -> None:
    """Independent of the loop's own counter: the recorded physics-rate arrays."""
    assert np.all(ep.q >= P.lower - 1e-6) and np.all(ep.q <= P.upper + 1e-6)
    assert np.all(np.abs(ep.v) <= P.velocity_limit + 1e-6)
    assert np.all(np.abs(ep.tau) <= P.torque_limit + 1e-9)
    assert ep.info["limit_violations"] == 0


def test_oracle_tracks_the_intent_within_the_limits(oracle_episode):
    ep = oracle_episode
    _check_limits_in_physics(ep)
    assert ep.q.shape == (8000, 3) and ep.t.shape == (800,)
    np.testing.assert_allclose(np.diff(ep.t_physics), 0.001, atol=1e-9)
    m = episode_metrics(ep)
    assert m["limit_violations"] == 0
    assert m["tracking_rmse_m"] < 0.005 and m["tracking_p95_m"] < 0.01
    assert m["reactive_share"] == 1.0 and m["handovers"] == 0
    # the robot serves the intent: once the wearer has seen α = 1 (after their reaction time) they stay still
    seen = round(WearerConfig().reaction_delay_s / 0.01) + 1
    assert np.linalg.norm(ep.voluntary[seen:], axis=1).mean() < 0.01
    assert m["voluntary_effort"] < 0.02
    assert set(ep.status) == {"ok"}


def test_limits_hold_when_a_controller_drives_into_them(trial):
    ep = run_episode(AggressiveController(), trial, duration_s=6.0)
    _check_limits_in_physics(ep)
    # the test is not vacuous: the arm reaches every position, velocity and torque limit
    assert np.all(np.minimum(ep.q - P.lower, P.upper - ep.q).min(axis=0) < 1e-3)
    assert np.all(np.abs(ep.v).max(axis=0) > 0.999 * P.velocity_limit)
    assert np.any(np.abs(ep.tau).max(axis=0) > 0.999 * P.torque_limit)
    assert ep.info["servo_qp_steps"] > 0 and ep.info["brake_infeasible_steps"] == 0


def test_effort_is_higher_without_help(oracle_episode, idle_episode, trial):
    _check_limits_in_physics(idle_episode)
    idle, oracle = episode_metrics(idle_episode), episode_metrics(oracle_episode)
    assert idle["voluntary_effort"] > 10 * oracle["voluntary_effort"]
    assert idle["tracking_rmse_m"] > 5 * oracle["tracking_rmse_m"]
    # a controller that follows the shoulder: the wearer steers the knife to within a few cm
    vol = episode_metrics(run_episode(VoluntaryController(), trial, duration_s=8.0, seed=1))
    assert vol["limit_violations"] == 0
    assert vol["tracking_rmse_m"] < 0.5 * idle["tracking_rmse_m"]
    assert vol["voluntary_effort"] > 5 * oracle["voluntary_effort"]
    assert vol["reactive_share"] == 0.0


def test_run_file_round_trip(oracle_episode, tmp_path):
    path = oracle_episode.save(tmp_path / "run.npz")
    with np.load(path) as z:
        for k in PHYSICS_KEYS + CONTROL_KEYS:
            assert k in z.files
        assert z["tau"].shape == (8000, 3) and z["status"].dtype.kind == "U"
    back = Episode.load(path)
    np.testing.assert_array_equal(back.q, oracle_episode.q)
    assert back.info["limit_violations"] == 0
    assert episode_metrics(back)["tracking_rmse_m"] == episode_metrics(oracle_episode)["tracking_rmse_m"]
    with pytest.raises(ValueError, match=r"\.npz"):
        oracle_episode.save(tmp_path / "run.txt")


def test_metric_keys_are_the_contract(oracle_episode):
    assert tuple(episode_metrics(oracle_episode)) == METRIC_KEYS == (
        "tracking_rmse_m", "tracking_p95_m", "voluntary_effort", "reactive_share", "handovers",
        "conflict_share", "limit_violations", "step_p50_ms", "step_p99_ms", "realtime_factor")


class _Faulty:
    """Raises on some steps, returns garbage on others, a good command otherwise."""

    def __init__(self):
        self.qp = IdleController()

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        k = round(t * 100)
        if k % 7 == 3:
            raise RuntimeError("boom")
        if k % 7 == 5:
            return TestCommand(np.full(3, np.nan), np.zeros(3), np.zeros(3), np.zeros(3))
        if k % 7 == 6:
            return object()
        return self.qp.step(t, obs, voluntary, q, v, base_pose)


def test_a_faulty_controller_never_stops_the_loop(trial):
    ep = run_episode(_Faulty(), trial, duration_s=1.0)
    _check_limits_in_physics(ep)
    st = list(ep.status)
    assert st[3].startswith("controller_error: RuntimeError") and st[5] == "invalid_command"
    assert st[6] == "invalid_command" and st[0] == "ok"


def test_bad_inputs_are_refused(trial):
    with pytest.raises(TypeError, match="step"):
        run_episode(object(), trial)
    with pytest.raises(ValueError, match="knife_x"):
        run_episode(IdleController(), trial, act_names=[f"a{i}" for i in range(9)])
    slow = type(trial)(obs=trial.obs[::2], act=trial.act[::2], t=trial.t[::2], trial_id=4)
    with pytest.raises(ValueError, match="resample"):
        run_episode(IdleController(), slow)


def test_render_writes_a_video_or_says_why(trial, tmp_path):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ep = run_episode(IdleController(), trial, duration_s=0.5, render=tmp_path / "clip.mp4", record=False)
    if ep.info["video"] is None:
        assert "OpenGL" in ep.info["render_message"] or "frame" in ep.info["render_message"]
        assert any("no video" in str(w.message) for w in caught)
    else:
        from PIL import Image

        video = ep.info["video"]
        assert video.endswith((".mp4", ".gif"))
        if video.endswith(".gif"):
            with Image.open(video) as im:
                assert im.n_frames >= 5
    assert ep.q.shape == (0, 3)  # record=False keeps no physics arrays


def test_without_opengl_the_loop_says_so_and_goes_on(trial, tmp_path, monkeypatch):
    import sim.render

    def no_gl(*args, **kwargs):
        raise RuntimeError("an OpenGL platform library has not been loaded")

    monkeypatch.setattr(sim.render.mujoco, "Renderer", no_gl)
    with pytest.warns(RuntimeWarning, match="no video: offscreen OpenGL is not available"):
        ep = run_episode(IdleController(), trial, duration_s=0.3, render=tmp_path / "clip.mp4")
    assert ep.info["video"] is None and "MUJOCO_GL=egl" in ep.info["render_message"]
    assert not (tmp_path / "clip.mp4").exists() and not (tmp_path / "clip.gif").exists()
    assert ep.t.size == 30 and ep.info["limit_violations"] == 0


def test_a_leading_wearer_saws_in_the_closed_loop(trial):
    """Under a controller that follows the shoulder (α = 0), the wearer's own strokes reach the knife on time."""
    from sim.task.eating import MODE_NAMES, episode_task_metrics
    from sim.wearer_presets import wearer_preset

    def figures(wearer):
        ep = run_episode(VoluntaryController(), trial, duration_s=5.0, seed=1, wearer=wearer)  # cutting: 0–2.75 s
        assert ep.info["limit_violations"] == 0
        return ep, episode_task_metrics(ep.tip, ep.tip_intent, 0.01, trial.mode[:ep.t.size], MODE_NAMES)

    ep, saws = figures(wearer_preset("unimpaired"))
    assert ep.info["wearer_preset"] == "unimpaired"
    assert saws["saw_correlation"] > 0.8 and saws["saw_amplitude_ratio"] > 0.7 and abs(saws["lag_s"]) <= 0.05
    _, corrects_only = figures(WearerConfig(feedforward=False))  # corrections alone: no stroke
    assert corrects_only["saw_correlation"] < 0.5 and corrects_only["saw_amplitude_ratio"] < 0.5


def test_fork_pose_rows_make_a_level_fork_without_angles_and_name_what_is_missing():
    obs = np.arange(12.0).reshape(3, 4)
    np.testing.assert_array_equal(fork_pose_rows(obs, ["f", "fork_x", "fork_y", "fork_z"]),
                                  np.c_[obs[:, 1:], np.zeros((3, 3))])
    with pytest.raises(ValueError, match=r"no channel\(s\) \['fork_pitch', 'fork_yaw'\]"):
        fork_pose_rows(obs, ["fork_roll", "fork_x", "fork_y", "fork_z"])
    with pytest.raises(ValueError, match="fork_z"):
        fork_pose_rows(obs, ["a", "fork_x", "fork_y", "b"])


def test_the_scene_holds_the_tasks_body_zones(trial):
    from sim.scene import SceneConfig
    from sim.task import EATING
    from tests.sim.task.test_protocol import Pouring

    zones = [json.loads(run_episode(IdleController(), trial, duration_s=0.1, scene=scene, task=task).info["body_zones"])
             for scene, task in ((None, Pouring()), (SceneConfig(), Pouring()), (None, EATING))]
    assert zones[0]["head_speed_cap"] == zones[1]["head_speed_cap"] == 0.03  # the task's, also over a given scene
    assert zones[2] == json.loads(json.dumps({**EATING.body.to_dict(), "blade_length": SceneConfig().blade_length}))
    assert EATING.body.head_speed_cap != 0.03 and dataclasses.replace(EATING.body, head_speed_cap=0.03) == Pouring.body


class _Tidying:
    """The task parts the closed loop reads: its body (eating's), mode names and colours, shoulder roles."""

    def __init__(self):
        from sim.task import EATING

        self.body = EATING.body
        self.mode_names = ("sweep", "carry", "gather", "drop")
        self.mode_colours = {"sweep": "#010203", "carry": "#040506", "gather": "#070809", "drop": "#0a0b0c"}
        self.shoulder_channels = ("lift",)
        self.shoulder_to_plate = np.array([[0.0], [0.0], [1.0]])


def test_the_caption_names_the_tasks_modes_and_the_episode_its_shoulder_roles(trial, monkeypatch):
    import sim.render

    captions = []

    class Recorder:
        def __init__(self, *args, **kwargs):
            pass

        def wants(self, k):
            return True

        def maybe_capture(self, data, k, caption):
            captions.append(caption)

        def close(self):
            return None, None

    monkeypatch.setattr(sim.render, "VideoRecorder", Recorder)
    task = _Tidying()
    ep = run_episode(IdleController(), trial, duration_s=0.2, render="unused.mp4", record=False, task=task)
    label = int(trial.mode[0])
    assert captions[0].parts[-1] == task.mode_names[label]
    assert captions[0].patch_colour == task.mode_colours[task.mode_names[label]]
    assert json.loads(ep.info["shoulder_roles"]) == ["lift"]
    lifted = dataclasses.replace(ep, info={**ep.info, "shoulder_matrix": "[[0.0], [0.0], [1.0]]"})
    assert lifted.shoulder_names == ["lift"]  # the wearer's column is the task's role "lift"
    old = {k: v for k, v in ep.info.items() if k not in ("shoulder_roles", "shoulder_layout")}  # an older run file
    assert dataclasses.replace(ep, info=old).shoulder_names == ["shoulder_elevation", "shoulder_protraction",
                                                                "shoulder_abduction"]


def test_a_recorded_episode_counts_the_limits_as_an_unrecorded_one(trial, monkeypatch):
    """The recording is checked once at its end, an unrecorded run per period: the same count and worst excesses."""
    import sim.closed_loop as closed_loop

    monkeypatch.setattr(closed_loop, "LIMIT_TOL", -0.01)  # limits drawn 0.01 inside: the arm crosses them
    monkeypatch.setattr(closed_loop, "TORQUE_TOL", -0.01)
    keys = ("limit_violations", "max_q_excess_rad", "max_v_excess_rad_s", "max_tau_excess_nm")
    recorded = run_episode(AggressiveController(), trial, duration_s=2.0, record=True).info
    unrecorded = run_episode(AggressiveController(), trial, duration_s=2.0, record=False).info
    assert recorded["limit_violations"] > 0 and recorded["max_v_excess_rad_s"] > 0.0
    assert [recorded[k] for k in keys] == [unrecorded[k] for k in keys]
