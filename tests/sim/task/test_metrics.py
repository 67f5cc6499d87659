"""The figures tasks are made of (sim/task/metrics.py), on signals written here: lag, strokes, RMS per mode."""

import numpy as np
import pytest

from sim.task.metrics import MIN_EPISODE_S, rms_by_mode, sawing_by_episode, sawing_fidelity, time_lag

DT = 0.01
BAND = (0.8, 3.0)  # [Hz] a stroke band about the 2 Hz strokes below


def _smooth(n: int, seed: int, f_max: float = 1.5) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    f, ph, a = rng.uniform(0.05, f_max, (3, 4)), rng.uniform(0, 2 * np.pi, (3, 4)), rng.uniform(0.005, 0.03, (3, 4))
    return np.stack([np.sum(a[i] * np.sin(2 * np.pi * f[i] * t[:, None] + ph[i]), axis=1) for i in range(3)], 1)


@pytest.mark.parametrize("shift_s", [0.3, 0.0, -0.2, 0.47])
def test_lag_recovers_a_known_shift(shift_s):
    base = _smooth(3000, seed=1)
    s = round(shift_s / DT)
    intent = base[100:2100]
    tip = base[100 - s:2100 - s]  # tip(t) = intent(t − shift): late by shift_s
    lag, rms = time_lag(tip, intent, DT)
    assert lag == pytest.approx(shift_s, abs=1e-12) and rms == pytest.approx(0.0, abs=1e-12)


def test_lag_of_a_noisy_copy_and_bad_input():
    intent = _smooth(2000, seed=2)
    tip = np.roll(intent, 25, axis=0) + np.random.default_rng(0).normal(0, 1e-4, intent.shape)
    lag, rms = time_lag(tip, intent, DT)
    assert lag == pytest.approx(0.25) and rms < 1e-3
    with pytest.raises(ValueError, match="one shape"):
        time_lag(tip[:10], intent, DT)
    with pytest.raises(ValueError, match="dt must be > 0"):
        time_lag(tip, intent, 0.0)


def _cutting(freq_hz=2.0, amp=0.01, n=2400):
    t = np.arange(n) * DT
    drift = 0.5 * _smooth(n, seed=3, f_max=0.3) * np.array([1, 1, 0.2])  # below the stroke band
    mask = (t >= 4) & (t < 16)
    stroke = np.zeros((n, 3))
    stroke[mask, 0] = amp * np.sin(2 * np.pi * freq_hz * t[mask])
    return t, drift, stroke, mask


@pytest.mark.parametrize("freq_hz", [2.0, 1.3])
def test_a_knife_that_saws_as_intended_scores_one(freq_hz):
    _, drift, stroke, mask = _cutting(freq_hz)
    f = sawing_fidelity(drift + stroke, drift + stroke, mask, DT, BAND)
    assert f.amplitude_ratio == pytest.approx(1.0) and f.correlation == pytest.approx(1.0)
    assert abs(f.strokes_intended - freq_hz * 12.0) <= 1.0 and f.stroke_share == 1.0
    assert f.cutting_s == pytest.approx(12.0)


def test_a_knife_that_never_saws_scores_near_zero():
    _, drift, stroke, mask = _cutting()
    f = sawing_fidelity(drift, drift + stroke, mask, DT, BAND)
    assert f.amplitude_ratio < 0.1 and f.stroke_share == 0.0


def test_half_strokes_and_late_strokes():
    t, drift, stroke, mask = _cutting()
    half = sawing_fidelity(drift + 0.5 * stroke, drift + stroke, mask, DT, BAND)
    assert half.amplitude_ratio == pytest.approx(0.5, abs=0.02) and half.correlation > 0.99
    assert sawing_fidelity(drift + 0.6 * stroke, drift + stroke, mask, DT, BAND).stroke_share == 1.0
    assert sawing_fidelity(drift + 0.4 * stroke, drift + stroke, mask, DT, BAND).stroke_share == 0.0
    late = np.zeros_like(stroke)
    late[mask, 0] = 0.01 * np.sin(2 * np.pi * 2.0 * (t[mask] - 0.125))  # a quarter cycle late
    q = sawing_fidelity(drift + late, drift + stroke, mask, DT, BAND)
    assert q.amplitude_ratio == pytest.approx(1.0, abs=0.05) and abs(q.correlation) < 0.1


def test_no_cutting_and_bad_input():
    _, drift, stroke, mask = _cutting()
    none = sawing_fidelity(drift, drift, np.zeros(len(drift), bool), DT, BAND)
    assert none.amplitude_ratio is None and none.stroke_share is None and none.cutting_s == 0.0
    with pytest.raises(ValueError, match="cutting_mask must have shape"):
        sawing_fidelity(drift, drift, mask[:-1], DT, BAND)
    with pytest.raises(ValueError, match="stroke band"):
        sawing_fidelity(drift, drift, mask, DT, band=(1.0, 80.0))


def test_each_cutting_episode_is_judged_on_its_own():
    """Three cutting runs: 4–8 s sawn as intended, 10–14 s not sawn (the tip holds still in the band), 16.0–16.5 s
    too short to judge. Pooled, the tip looks half right; per episode, the first scores 1 and the second near 0,
    each exactly :func:`sawing_fidelity` on that run's samples alone (the band-pass runs over the whole signal)."""
    n = 2400
    t = np.arange(n) * DT
    drift = 0.5 * _smooth(n, seed=3, f_max=0.3)
    runs = [(4.0, 8.0), (10.0, 14.0), (16.0, 16.5)]
    mask = np.zeros(n, bool)
    for a, z in runs:
        mask[round(a / DT):round(z / DT)] = True
    stroke = np.zeros((n, 3))
    stroke[mask, 0] = 0.01 * np.sin(2 * np.pi * 2.0 * t[mask])
    tip = drift + np.where((t < 9.0)[:, None], stroke, 0.0)
    got = sawing_by_episode(tip, drift + stroke, mask, DT, BAND)
    assert [round(s, 6) for s, _ in got] == [4.0, 10.0]  # the 0.5-s run is below MIN_EPISODE_S
    for (start, f), (a, z) in zip(got, runs):
        alone = np.zeros(n, bool)
        alone[round(a / DT):round(z / DT)] = True
        want = sawing_fidelity(tip, drift + stroke, alone, DT, BAND)
        assert f == want and f.cutting_s == pytest.approx(z - a)
    assert got[0][1].correlation == pytest.approx(1.0, abs=1e-3) and got[1][1].amplitude_ratio < 0.1
    pooled = sawing_fidelity(tip, drift + stroke, mask, DT, BAND)
    assert 0.3 < pooled.amplitude_ratio < 0.9  # the pooled figure hides the episode that did not saw
    assert [s for s, _ in sawing_by_episode(tip, drift + stroke, mask, DT, BAND, min_episode_s=0.5)] == [
        4.0, 10.0, 16.0]
    assert sawing_by_episode(tip, tip, np.zeros(n, bool), DT, BAND) == [] and MIN_EPISODE_S == 1.0
    with pytest.raises(ValueError, match="cutting_mask must have shape"):
        sawing_by_episode(tip, tip, mask[:-1], DT, BAND)
    with pytest.raises(ValueError, match="min_episode_s"):
        sawing_by_episode(tip, tip, mask, DT, BAND, min_episode_s=-1.0)


def test_rms_by_mode_matches_a_direct_computation():
    rng = np.random.default_rng(4)
    tip, intent = rng.normal(size=(500, 3)), rng.normal(size=(500, 3))
    modes = rng.integers(-1, 3, 500)
    got = rms_by_mode(tip, intent, modes, names=("cutting", "repositioning", "collecting"))
    for m, name in enumerate(("cutting", "repositioning", "collecting")):
        e = tip[modes == m] - intent[modes == m]
        assert got[name] == pytest.approx(np.sqrt(np.mean(np.sum(e**2, axis=1))))
    assert set(got) == {"cutting", "repositioning", "collecting"}


def test_wearer_share_by_mode_counts_alpha_below_half_and_nan():
    from sim.task.metrics import wearer_share_by_mode

    alpha = np.array([1.0, 0.0, np.nan, 0.6, 0.4, 1.0])
    modes = np.array([0, 0, 0, 1, 1, -1])
    shares, counts = wearer_share_by_mode(alpha, modes, ("cutting", "collecting"))
    assert shares == {"cutting": pytest.approx(2 / 3), "collecting": pytest.approx(0.5)}
    assert counts == {"cutting": 3, "collecting": 2}
    with pytest.raises(ValueError, match="one shape"):
        wearer_share_by_mode(alpha[:3], modes, None)


def test_pickup_error_against_a_direct_computation():
    """Two hand-overs to the wearer (α falls below 0.5 at steps 100 and 400, 10 ms steps): the 1 s after
    each holds its error; one back to the robot (step 300) does not count."""
    from sim.task.metrics import pickup_error

    dt, n = 0.01, 700
    alpha = np.ones(n)
    alpha[100:300] = 0.0
    alpha[400:] = 0.25  # the wearer leads at any α below 0.5
    intent = np.zeros((n, 3))
    tip = np.zeros((n, 3))
    tip[:, 0] = 0.002
    tip[100:150, 0] = 0.03  # the pick-up's error
    tip[400:420, 1] = 0.02
    out = pickup_error(tip, intent, alpha, dt)
    win = np.r_[100:200, 400:500]
    err2 = np.sum((tip - intent) ** 2, axis=1)
    assert out["pickups"] == 2 and out["pickup_s"] == pytest.approx(2.0)
    assert out["pickup_rms_m"] == pytest.approx(np.sqrt(err2[win].mean()))
    assert out["pickup_error_share"] == pytest.approx(err2[win].sum() / err2.sum())
    none = pickup_error(tip, intent, np.ones(n), dt)  # the robot leads throughout
    assert none["pickups"] == 0 and none["pickup_rms_m"] is None and none["pickup_error_share"] is None
    short = pickup_error(tip, intent, alpha, dt, window_s=0.3)
    assert short["pickup_s"] == pytest.approx(0.6) and short["pickup_rms_m"] > out["pickup_rms_m"]
    with pytest.raises(ValueError, match="alpha has shape"):
        pickup_error(tip, intent, alpha[:-1], dt)


def test_pooled_pickups_weigh_by_time_and_squared_error():
    from mpcshare.evaluation.pooling import pool_task_metrics

    a = {"pickups": 2, "pickup_rms_m": 0.03, "pickup_s": 2.0, "pickup_error_share": 0.5, "tracking_rmse_m": 0.01}
    b = {"pickups": 0, "pickup_rms_m": None, "pickup_s": 0.0, "pickup_error_share": None, "tracking_rmse_m": 0.02}
    c = {"pickups": 1, "pickup_rms_m": 0.01, "pickup_s": 1.0, "pickup_error_share": 0.2, "tracking_rmse_m": 0.01}
    pooled = pool_task_metrics([a, b, c], [np.zeros(1000)] * 3)
    assert pooled["pickups"] == 3 and pooled["pickup_s"] == pytest.approx(3.0)
    assert pooled["pickup_rms_m"] == pytest.approx(np.sqrt((2 * 0.03**2 + 1 * 0.01**2) / 3))
    sq = np.array([1e-4, 4e-4, 1e-4]) * 1000  # n·rms² per episode
    assert pooled["pickup_error_share"] == pytest.approx((sq[0] * 0.5 + sq[2] * 0.2) / sq.sum())
