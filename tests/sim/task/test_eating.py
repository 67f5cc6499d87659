"""The eating task: its figures, its sawing criterion, its shoulder layout and body, and the data that use them."""

import numpy as np
import pytest

from sim.demonstrator import CUTTING, VOL_NAMES, generate_demonstrations
from sim.task.eating import (
    BODY,
    METRIC_KEYS,
    MODE_COLOURS,
    MODE_NAMES,
    SAWING_CRITERION,
    SHOULDER_CHANNELS,
    SHOULDER_TO_PLATE,
    STROKE_BAND_HZ,
    STROKE_MODE,
    TASK,
    episode_task_metrics,
    saws,
)
from sim.task.metrics import sawing_fidelity

DT = 0.01


def _episode(seconds: float = 20.0, late_s: float = 0.0):
    """A 2 Hz stroke along x during the first half (cutting), a slow drift during the second (collecting)."""
    t = np.arange(int(seconds / DT)) * DT
    intent = np.stack([0.02 * np.sin(2 * np.pi * 2.0 * t), 0.01 * np.sin(0.3 * t), 0.0 * t], axis=1)
    tip = np.stack([0.02 * np.sin(2 * np.pi * 2.0 * (t - late_s)), 0.01 * np.sin(0.3 * (t - late_s)), 0.0 * t], 1)
    mode = np.where(t < seconds / 2, MODE_NAMES.index("cutting"), MODE_NAMES.index("collecting"))
    return tip, intent, mode


def test_the_figures_judge_the_strokes_of_the_cutting_mode_only():
    tip, intent, mode = _episode()
    m = episode_task_metrics(tip, intent, DT, mode, MODE_NAMES, alpha=np.ones(len(mode)))
    assert tuple(m) == METRIC_KEYS
    cut = mode == MODE_NAMES.index(STROKE_MODE)
    want = sawing_fidelity(tip, intent, cut, DT, STROKE_BAND_HZ)
    assert m["saw_correlation"] == want.correlation and m["cutting_s"] == pytest.approx(cut.sum() * DT)
    assert set(m["rms_by_mode_m"]) == {"cutting", "collecting"} and TASK.done(m)
    assert [(e["start_s"], e["cutting_s"]) for e in m["saw_by_episode"]] == [(0.0, pytest.approx(cut.sum() * DT))]
    assert m["saw_by_episode"][0]["saw_correlation"] == want.correlation  # one episode: the pooled figures
    tip_late, _, _ = _episode(late_s=0.125)  # a quarter stroke late
    late = episode_task_metrics(tip_late, intent, DT, mode, MODE_NAMES)
    assert not TASK.done(late) and late["lag_s"] == pytest.approx(0.13, abs=0.011)
    unnamed = episode_task_metrics(tip, intent, DT, mode, None)  # no names: no mode to saw in
    assert unnamed["saw_correlation"] is None and unnamed["cutting_s"] == 0.0 and unnamed["saw_by_episode"] == []
    assert TASK.episode_metrics(tip, intent, DT, mode, MODE_NAMES) == episode_task_metrics(tip, intent, DT, mode,
                                                                                           MODE_NAMES)


def test_sawing_needs_both_thresholds_and_the_sentence_states_them():
    assert saws(0.7, 0.6) and not saws(0.69, 0.9) and not saws(0.9, 0.59) and not saws(None, 1.0)
    assert "0.7" in SAWING_CRITERION and "0.6" in SAWING_CRITERION and TASK.criterion == SAWING_CRITERION
    assert TASK.done({"saw_correlation": 0.8, "saw_amplitude_ratio": 0.8}) and not TASK.done({})


def test_the_demonstrations_label_and_name_their_channels_by_the_task():
    demos = generate_demonstrations(n_subjects=1, minutes=0.5, seed=2)
    labels = np.unique(np.concatenate([t.mode for t in demos.trials]))
    assert set(labels) <= set(range(len(MODE_NAMES))) and MODE_NAMES[CUTTING] == STROKE_MODE
    assert tuple(demos.vol_names) == VOL_NAMES == SHOULDER_CHANNELS
    assert set(MODE_COLOURS) == set(MODE_NAMES) and len(set(MODE_COLOURS.values())) == len(MODE_NAMES)


def test_the_shoulder_and_the_body_are_the_tasks_values():
    m = TASK.shoulder_map()
    np.testing.assert_array_equal(m.matrix, SHOULDER_TO_PLATE)
    np.testing.assert_allclose(m.tip_velocity(np.array([0.11, 0.0, 0.0])), [0.0, 0.0, 0.05])  # elevation → z
    two = TASK.shoulder_map(["shoulder_abduction", "imu"], gain=1.0, deadband_rad=0.0)
    np.testing.assert_allclose(two.tip_velocity(np.array([0.1, 3.0])), [0.0, 0.1, 0.0])  # abduction → y
    with pytest.raises(ValueError):
        SHOULDER_TO_PLATE[0, 0] = 1.0  # read-only
    assert BODY.hand_radius == 0.045 and BODY.head_speed_cap == 0.06 and TASK.body is BODY
