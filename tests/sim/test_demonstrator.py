"""The synthetic eating demonstrations: shapes, labels, determinism, physics-like properties."""

import numpy as np
import pytest
from scipy import signal

from learning.lipschitz import pointwise_quotients
from learning.preprocessing.preprocess import preprocess
from sim.demonstrator import (
    ACT_NAMES,
    CUTTING,
    MODE_NAMES,
    OBS_NAMES,
    VOL_NAMES,
    GeneratorConfig,
    SubjectStyle,
    generate_demonstrations,
)


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(n_subjects=2, minutes=4, seed=3)


def test_shapes_names_and_rate(demos):
    assert demos.rate_hz == 100.0
    assert demos.obs_names == list(OBS_NAMES) and demos.act_names == list(ACT_NAMES)
    assert demos.vol_names == list(VOL_NAMES)
    assert demos.n_samples == 2 * 4 * 60 * 100
    assert demos.subjects == [0, 1]
    for tr in demos:
        T = len(tr)
        assert tr.obs.shape == (T, 9) and tr.act.shape == (T, 9) and tr.voluntary.shape == (T, 3)
        assert tr.mode.shape == (T,)
        assert np.all(np.diff(tr.t) > 0)
        assert np.allclose(np.diff(tr.t), 0.01)
        assert np.isfinite(tr.obs).all() and np.isfinite(tr.act).all()
    assert [tr.trial_id for tr in demos] == list(range(len(demos)))
    demos.validate()


def test_all_four_modes_with_plausible_durations(demos):
    labels = np.concatenate([tr.mode for tr in demos])
    assert set(np.unique(labels)) == set(range(len(MODE_NAMES)))
    shares = np.bincount(labels, minlength=4) / len(labels)
    assert np.all(shares > 0.05), shares
    for tr in demos:  # segments last seconds, not samples
        change = np.flatnonzero(np.diff(tr.mode)) + 1
        seg = np.diff(np.r_[0, change, len(tr)])
        assert np.median(seg) / demos.rate_hz > 2.0


def test_same_seed_same_data_other_seed_other_data():
    a = generate_demonstrations(1, 1, seed=11)
    b = generate_demonstrations(1, 1, seed=11)
    c = generate_demonstrations(1, 1, seed=12)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.obs, y.obs)
        np.testing.assert_array_equal(x.act, y.act)
        np.testing.assert_array_equal(x.mode, y.mode)
    assert not np.array_equal(a[0].obs, c[0].obs)


def test_subjects_have_their_own_style():
    styles = (SubjectStyle(speed=0.85), SubjectStyle(speed=1.2))
    d = generate_demonstrations(2, 3, seed=0, config=GeneratorConfig(styles=styles))
    speed = [np.mean(np.abs(np.diff(tr.obs[:, :3], axis=0))) for tr in d]
    by_subject = {s: np.mean([v for v, tr in zip(speed, d) if tr.subject == s]) for s in (0, 1)}
    assert by_subject[1] > by_subject[0]


def test_fork_holds_still_while_knife_saws(demos):
    fork_speed, knife_speed = [], []
    for tr in demos:
        cut = tr.mode == CUTTING
        # inside cutting segments, once the fork has settled (1 s in): fork still, knife saws
        inner = cut & np.roll(cut, 100) & np.roll(cut, -20)
        fork_speed.append(np.abs(np.gradient(tr.obs[:, 0], tr.t))[inner])
        knife_speed.append(np.abs(np.gradient(tr.act[:, 0], tr.t))[inner])
    fork_speed, knife_speed = np.concatenate(fork_speed), np.concatenate(knife_speed)
    assert fork_speed.size > 100
    assert np.median(knife_speed) > 10 * np.median(fork_speed)


def test_voluntary_channel_follows_knife_velocity(demos):
    from scipy.ndimage import uniform_filter1d

    tr = demos[0]
    knife_vz = np.gradient(uniform_filter1d(tr.act[:, 2], 20), tr.t)  # smoothed: sensor noise
    r = np.corrcoef(tr.voluntary[:, 0], knife_vz)[0, 1]
    assert r > 0.6


def test_modes_explain_confounding():
    """Calibration: without modes many points are confounded, within the true modes few are."""
    d = generate_demonstrations(2, 6, seed=0)
    w, _ = preprocess(d, scope="sensor", rms=True)
    q = pointwise_quotients(w.X, w.Y)
    q_modes = pointwise_quotients(w.X, w.Y, w.mode)
    share, share_modes = np.mean(q > 5), np.mean(q_modes > 5)
    assert share > 0.25
    assert share_modes < 0.2
    assert share > 2.5 * share_modes


SAW = (SubjectStyle(saw_hz=2.0),)  # one known sawing frequency [Hz]


def _saw_band(tr, rate_hz: float = 100.0) -> np.ndarray:
    """knife_x band-passed around the sawing frequency (1.6–2.4 Hz; the stroke wanders ±15 %)."""
    sos = signal.butter(4, [1.6, 2.4], btype="bandpass", fs=rate_hz, output="sos")
    return signal.sosfiltfilt(sos, tr.act[:, 0])


def _rms(parts: list[np.ndarray]) -> float:
    x = np.concatenate(parts)
    assert x.size > 300
    return float(np.sqrt(np.mean(x ** 2)))


@pytest.fixture(scope="module")
def saw_power():
    """RMS [m] of knife_x at the sawing frequency: inside cutting, outside it, and in single-regime data
    (samples 1 s away from any mode change, so that filter edges and ramps do not count)."""
    inside, outside = [], []
    for tr in generate_demonstrations(1, 4, seed=1, config=GeneratorConfig(styles=SAW)):
        y, cut = _saw_band(tr), tr.mode == CUTTING
        inside.append(y[cut & np.roll(cut, 100) & np.roll(cut, -100)])
        outside.append(y[~cut & np.roll(~cut, 100) & np.roll(~cut, -100)])
    single = [_saw_band(tr)[100:-100] for tr in
              generate_demonstrations(1, 4, seed=1, config=GeneratorConfig(styles=SAW, single_regime=True))]
    return _rms(inside), _rms(outside), _rms(single)


def test_knife_saws_while_cutting_and_only_then(saw_power):
    inside, outside, _ = saw_power
    assert inside > 0.005  # a 2 cm half-stroke: RMS ≈ 1.4 cm before band-passing
    assert inside > 4 * outside


def test_single_regime_has_one_mode_and_no_sawing(saw_power):
    d = generate_demonstrations(1, 2, seed=0, config=GeneratorConfig(single_regime=True))
    assert len(np.unique(np.concatenate([tr.mode for tr in d]))) == 1
    inside, _, single = saw_power
    assert single < 0.1 * inside


def test_one_hour_per_subject_is_cheap():
    d = generate_demonstrations(1, 60, seed=0)
    assert d.n_samples == 360_000
    nbytes = sum(tr.obs.nbytes + tr.act.nbytes + tr.voluntary.nbytes + tr.t.nbytes + tr.mode.nbytes
                 for tr in d)
    assert nbytes < 100e6


@pytest.mark.parametrize("kwargs, match", [
    (dict(n_subjects=0), "n_subjects"),
    (dict(minutes=0), "minutes"),
    (dict(minutes=-1), "minutes"),
])
def test_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        generate_demonstrations(**{"n_subjects": 1, "minutes": 1, **kwargs})
