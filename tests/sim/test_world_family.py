"""The randomised world family: its structure varies with the seed, the same seed gives the same data."""

from __future__ import annotations

import numpy as np
import pytest

from sim.demonstrator import ACT_NAMES, OBS_NAMES, VOL_NAMES
from sim.task.metrics import bandpass
from sim.world_family import KINDS, draw_world, world_demonstrations


def test_same_seed_same_world_and_data() -> None:
    a, sa = world_demonstrations(7, n_trials=2, trial_s=10.0)
    b, sb = world_demonstrations(7, n_trials=2, trial_s=10.0)
    assert sa.to_dict() == sb.to_dict()
    for ta, tb in zip(a.trials, b.trials):
        np.testing.assert_array_equal(ta.obs, tb.obs)
        np.testing.assert_array_equal(ta.act, tb.act)
        np.testing.assert_array_equal(ta.voluntary, tb.voluntary)
        np.testing.assert_array_equal(ta.mode, tb.mode)
    c, _ = world_demonstrations(8, n_trials=2, trial_s=10.0)
    assert not np.allclose(a.trials[0].act, c.trials[0].act)


def test_structure_varies_with_the_seed() -> None:
    specs = [draw_world(s) for s in range(20)]
    assert len({s.n_modes for s in specs}) >= 3  # the number of modes
    assert len({s.kinds for s in specs}) >= 5  # which modes do what
    assert len({tuple(np.round(s.transitions.ravel(), 3)) for s in specs if s.n_modes > 2}) > 1
    assert np.ptp([s.stroke_hz for s in specs]) > 1.0
    assert np.ptp([s.knife_delay_s for s in specs]) > 0.2
    assert np.ptp([s.act_noise_m for s in specs]) > 0.0005
    for s in specs:
        assert s.kinds[0] == "stroke" and "track" in s.kinds and set(s.kinds) <= set(KINDS)
        np.testing.assert_allclose(s.transitions.sum(axis=1), 1.0)
        assert np.all(np.diag(s.transitions) == 0)


@pytest.mark.parametrize("seed", [0, 3])
def test_channels_labels_and_the_stroke(seed: int) -> None:
    demos, spec = world_demonstrations(seed, n_trials=3, trial_s=40.0)
    assert list(demos.obs_names) == list(OBS_NAMES) and list(demos.act_names) == list(ACT_NAMES)
    assert list(demos.vol_names) == list(VOL_NAMES)
    act = np.concatenate([t.act for t in demos.trials])
    mode = np.concatenate([t.mode for t in demos.trials])
    assert set(np.unique(mode)) <= set(range(spec.n_modes))
    assert act[:, 2].min() > -5 * spec.act_noise_m  # the knife tip on or above the plate, but for noise
    # the stroke is in the stroke mode's band along its axis, and not outside the stroke mode
    dt = 1.0 / demos.rate_hz
    power = {True: [], False: []}
    for t in demos.trials:
        b = bandpass(t.act[:, :3] @ spec.stroke_axis, dt, (0.8 * spec.stroke_hz, 1.25 * spec.stroke_hz))
        lag = int(round(spec.knife_delay_s * demos.rate_hz)) + int(0.5 * demos.rate_hz)
        inside = np.concatenate([np.zeros(lag, bool), t.mode[:-lag] == 0]) & np.concatenate(
            [t.mode[lag:] == 0, np.zeros(lag, bool)])
        for k in (True, False):
            sel = inside if k else np.convolve(t.mode == 0, np.ones(2 * lag), "same") == 0
            power[k] += list(b[sel] ** 2)
    rms_in, rms_out = (float(np.sqrt(np.mean(power[k]))) for k in (True, False))
    assert rms_in > 0.45 * spec.stroke_amp_m  # a sine of amplitude a has RMS 0.71 a
    assert rms_out < 0.5 * rms_in


def test_bad_sizes_are_refused() -> None:
    with pytest.raises(ValueError, match="n_trials"):
        world_demonstrations(0, n_trials=0)
    with pytest.raises(ValueError, match="fewer than 2 samples"):
        world_demonstrations(0, trial_s=0.001)
