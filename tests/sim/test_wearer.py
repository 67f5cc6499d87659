"""The simulated wearer: self-generated strokes, delayed corrections, the α cue, its settings."""

from dataclasses import replace

import numpy as np
import pytest

from sim.task import EATING
from sim.wearer import SimulatedWearer, WearerConfig, rhythmic_plan
from sim.wearer_presets import WEARER_PRESETS, wearer_preset

SILENT = {"noise_rad": 0.0, "noise_signal_dependent": 0.0}
QUIET = {**SILENT, "feedforward": False, "reaction_delay_s": 0.2}  # a purely corrective wearer
RATE = 100.0


def _still_intent(T=200):
    return np.zeros((T, 3))


def _stroke(T=600, f=2.0, amp=0.02):
    """A 2 Hz, 2 cm (amplitude) sawing stroke along plate x."""
    intent = np.zeros((T, 3))
    intent[:, 0] = amp * np.sin(2 * np.pi * f * np.arange(T) / RATE)
    return intent


def _drive(w: SimulatedWearer, intent: np.ndarray, cue=None) -> tuple[np.ndarray, np.ndarray]:
    """Perfect tracking of the shoulder's command: tip_{k+1} = tip_k + tip_velocity(θ_k)·Δ."""
    tip, tips, thetas = intent[0].copy(), [], []
    for k in range(len(intent)):
        tips.append(tip.copy())
        th = w.step(k, tip, alpha_cue=cue)
        thetas.append(th)
        tip = tip + w.config.shoulder.tip_velocity(th) / RATE
    return np.array(tips), np.array(thetas)


def _amplitude_corr_lag(x: np.ndarray, y: np.ndarray, max_lag: int = 25) -> tuple[float, float, int]:
    """Amplitude ratio std(x)/std(y), correlation, and the lag [steps] of x behind y maximising it."""
    x, y = x - x.mean(), y - y.mean()
    lags = np.arange(-max_lag, max_lag + 1)
    cc = [np.dot(x[max_lag + lag:len(x) - max_lag + lag], y[max_lag:len(y) - max_lag]) for lag in lags]
    return float(x.std() / y.std()), float(np.corrcoef(x, y)[0, 1]), int(lags[int(np.argmax(cc))])


# --- self-generated motion ---------------------------------------------------------------------------

@pytest.mark.parametrize("preset", list(WEARER_PRESETS))
def test_a_leading_wearer_saws_without_delay(preset):
    intent = _stroke()
    w = SimulatedWearer(intent, RATE, replace(WEARER_PRESETS[preset], **SILENT))
    tips, _ = _drive(w, intent)
    amp, corr, lag = _amplitude_corr_lag(tips[100:, 0], intent[100:, 0])
    assert abs(lag) <= 2  # attenuated, not delayed: the old wearer was a quarter cycle (12 steps) late
    assert corr >= 0.9
    if preset == "unimpaired":
        assert amp >= 0.8
    if preset == "hemiparetic_severe":
        assert amp < 0.6  # 2 Hz is above a severe wearer's rhythmic bandwidth (1.5 Hz)


def test_stroke_amplitude_falls_with_the_impairment():
    intent = _stroke()
    amps = []
    for name in ("unimpaired", "hemiparetic_mild", "hemiparetic_severe"):
        w = SimulatedWearer(intent, RATE, replace(wearer_preset(name), **SILENT))
        amps.append(_amplitude_corr_lag(_drive(w, intent)[0][100:, 0], intent[100:, 0])[0])
    assert amps[0] > amps[1] > amps[2]


def test_the_rhythmic_plan_is_zero_phase_with_minus_3_db_at_its_bandwidth():
    T, f = 2000, 2.0
    x = np.zeros((T, 3))
    x[:, 1] = np.sin(2 * np.pi * f * np.arange(T) / RATE)
    p, _ = rhythmic_plan(x, RATE, bandwidth_hz=f)
    mid = slice(500, 1500)
    assert np.std(p[mid, 1]) / np.std(x[mid, 1]) == pytest.approx(1 / np.sqrt(2), abs=0.01)
    assert _amplitude_corr_lag(p[mid, 1], x[mid, 1])[2] == 0


def test_without_self_generated_motion_nobody_saws():
    """``feedforward=False``: corrections alone (delayed, dead band, low-pass) cannot make a 2 Hz stroke."""
    intent = _stroke()
    w = SimulatedWearer(intent, RATE, WearerConfig(**QUIET, bandwidth_hz=2.0, feedback_gain_per_s=2.0))
    amp, _, _ = _amplitude_corr_lag(_drive(w, intent)[0][100:, 0], intent[100:, 0])
    assert amp < 0.3


# --- who leads ---------------------------------------------------------------------------------------

def test_the_cue_is_perceived_exactly_after_the_reaction_delay():
    cfg = replace(wearer_preset("hemiparetic_mild"), **SILENT)
    w = SimulatedWearer(_stroke(), RATE, cfg)
    d = w.delay_steps
    assert d == 30
    leads = []
    for k in range(100):
        w.step(k, np.zeros(3), alpha_cue=None if k < 5 else (0.0 if k < 10 else 1.0))
        leads.append(w.wearer_leads)
    assert all(leads[:10 + d])  # no cue, then α = 0: the wearer leads
    assert not any(leads[10 + d:])  # α = 1 given from step 10 is seen at step 10 + d
    assert w.perceived_alpha == 1.0


def test_a_missing_cue_keeps_the_leader_perceived_last():
    w = SimulatedWearer(_stroke(), RATE, WearerConfig(**SILENT, reaction_delay_s=0.0))
    w.step(0, np.zeros(3), alpha_cue=0.9)
    assert not w.wearer_leads
    w.step(1, np.zeros(3), alpha_cue=float("nan"))
    w.step(2, np.zeros(3), alpha_cue=None)
    assert not w.wearer_leads
    w.step(3, np.zeros(3), alpha_cue=0.2)
    assert w.wearer_leads


def test_when_the_robot_leads_and_the_error_is_tolerated_the_shoulder_is_still():
    intent = _stroke()
    tip_error = np.array([0.004, -0.005, 0.003])  # 7 mm < the 1 cm dead band
    still = SimulatedWearer(intent, RATE, replace(wearer_preset("hemiparetic_mild"), **SILENT))
    out = np.array([still.step(k, intent[k] + tip_error, alpha_cue=1.0) for k in range(200)])
    assert np.all(np.any(out[:still.delay_steps] != 0.0, axis=1))  # leading (no cue perceived yet): drives the plan
    assert np.all(out[still.delay_steps:] == 0.0)  # the robot leads, nothing to correct: still
    noisy = SimulatedWearer(intent, RATE, wearer_preset("hemiparetic_mild"), seed=1)
    out = np.array([noisy.step(k, intent[k] + tip_error, alpha_cue=1.0) for k in range(200)])[noisy.delay_steps:]
    assert 0.0005 < out.std() < 0.006  # only noise: tremor-level, inside the shoulder map's dead zone
    assert np.all([np.linalg.norm(EATING.shoulder_map().tip_velocity(th)) < 0.003 for th in out])


# --- corrections ---------------------------------------------------------------------------------------

def test_reaction_delay_then_correction_toward_the_intent():
    w = SimulatedWearer(_still_intent(), RATE, WearerConfig(**QUIET))
    tip = np.array([0.0, 0.0, -0.05])  # 5 cm below the intent, appearing at step 10
    out = np.array([w.step(k, np.zeros(3) if k < 10 else tip) for k in range(80)])
    assert np.all(out[:30] == 0.0)  # steps 10..29: the error is not perceived yet (0.2 s = 20 steps)
    assert np.any(out[31] != 0.0)
    u = EATING.shoulder_map().tip_velocity(out[-1])
    assert u[2] > 0 and abs(u[0]) < 1e-12 and abs(u[1]) < 1e-12  # commands the tip up, toward the intent


@pytest.mark.parametrize("preset", list(WEARER_PRESETS))
def test_corrections_wait_for_the_presets_reaction_time_even_when_the_robot_leads(preset):
    cfg = replace(wearer_preset(preset), **SILENT)
    w = SimulatedWearer(_still_intent(300), RATE, cfg)
    d = w.delay_steps
    out = np.array([w.step(k, np.zeros(3) if k < 50 else np.array([0.05, 0.0, 0.0]), alpha_cue=1.0)
                    for k in range(50 + d + 5)])
    assert np.all(out[:50 + d] == 0.0) and np.any(out[50 + d + 1] != 0.0)
    assert EATING.shoulder_map().tip_velocity(out[-1])[0] < 0  # the tip is ahead in x: pull it back


def test_errors_inside_the_deadband_are_tolerated():
    w = SimulatedWearer(_still_intent(), RATE, WearerConfig(**QUIET))
    out = np.array([w.step(k, np.array([0.006, -0.005, 0.0])) for k in range(100)])  # 7.8 mm < 10 mm
    assert np.all(out == 0.0)


def test_limited_bandwidth_smooths_a_correction():
    cfg = WearerConfig(**{**QUIET, "reaction_delay_s": 0.0}, bandwidth_hz=2.0, feedback_gain_per_s=2.0)
    w = SimulatedWearer(_still_intent(), RATE, cfg)
    out = np.array([w.step(k, np.array([0.0, 0.0, -0.05])) for k in range(100)])
    target = EATING.shoulder_map().angles_for(np.array([0.0, 0.0, 0.1]))  # K·e = 2/s · 5 cm
    z = out[:, 0]  # elevation drives plate z
    assert np.all(np.diff(z) >= -1e-15)  # critically damped: no overshoot, monotone
    assert z[5] < 0.5 * target[0]  # slow start: a 2 Hz second-order stage
    assert abs(z[-1] - target[0]) < 0.01 * abs(target[0])


def test_a_leading_wearer_adds_corrections_to_the_plan_and_is_capped():
    T = 300
    intent = np.zeros((T, 3))
    intent[:, 0] = 0.1 * np.arange(T) / RATE  # 0.1 m/s along x
    w = SimulatedWearer(intent, RATE, WearerConfig(**SILENT, reaction_delay_s=0.0, feedback_gain_per_s=2.0))
    tip = np.array([-0.05, 0.0, 0.0])  # 5 cm behind: fully engaged
    out = [w.step(k, tip) for k in range(31)]
    assert w.engagement == 1.0 and w.wearer_leads
    assert w.desired_velocity[0] == pytest.approx(0.1 + 2.0 * (intent[30, 0] + 0.05), rel=1e-3)  # ṗ_r + K·e
    assert EATING.shoulder_map().tip_velocity(out[-1])[0] > 0.1  # the plan at once, corrections on top
    for k in range(31, 150):
        w.step(k, tip)
    assert np.linalg.norm(w.desired_velocity) == pytest.approx(w.config.max_speed_mps)


def test_noise_is_seeded_and_signal_dependent():
    cfg = WearerConfig(reaction_delay_s=0.0)
    a = SimulatedWearer(_still_intent(), RATE, cfg, seed=3)
    b = SimulatedWearer(_still_intent(), RATE, cfg, seed=3)
    xa = np.array([a.step(k, np.zeros(3)) for k in range(100)])
    xb = np.array([b.step(k, np.zeros(3)) for k in range(100)])
    np.testing.assert_array_equal(xa, xb)
    assert 0.0005 < xa.std() < 0.006  # tremor-level noise at rest
    moving = SimulatedWearer(_stroke(), RATE, cfg, seed=3)
    xm = np.array([moving.step(k, _stroke()[k]) for k in range(300)])
    clean = SimulatedWearer(_stroke(), RATE, replace(cfg, **SILENT))
    xc = np.array([clean.step(k, _stroke()[k]) for k in range(300)])
    assert np.std(xm - xc) > 1.5 * xa.std()  # larger noise while moving


# --- settings ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [{"reaction_delay_s": -0.1}, {"bandwidth_hz": 0.0}, {"deadband_m": float("nan")},
                                 {"rhythmic_bandwidth_hz": -1.0}])
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        WearerConfig(**bad)


def test_bad_intent_is_refused():
    with pytest.raises(ValueError, match="non-finite"):
        SimulatedWearer(np.full((10, 3), np.nan), RATE)
    with pytest.raises(ValueError, match=r"\(T, 3\)"):
        SimulatedWearer(np.zeros((10, 2)), RATE)


def test_a_two_angle_shoulder_tracks_the_axes_it_reaches():
    """Through a map of elevation and protraction only (z and x), the wearer drives those axes and
    returns two angles; y stays where it started."""
    intent = np.zeros((300, 3))
    intent[:, 0] = np.linspace(0.0, 0.05, 300)
    intent[:, 1] = np.linspace(0.0, 0.04, 300)  # y: out of this shoulder's reach
    intent[:, 2] = np.linspace(0.0, -0.03, 300)
    shoulder = EATING.shoulder_map(["shoulder_elevation", "shoulder_protraction"])
    w = SimulatedWearer(intent, RATE, replace(WearerConfig(), shoulder=shoulder, noise_rad=0.0,
                                               noise_signal_dependent=0.0))
    tips, thetas = _drive(w, intent)
    assert thetas.shape == (300, 2)
    assert abs(tips[-1, 0] - 0.05) < 0.01 and abs(tips[-1, 2] + 0.03) < 0.01
    assert np.all(tips[:, 1] == 0.0)
    assert "shoulder_matrix" in w.info() and "shoulder_matrix" not in SimulatedWearer(intent, RATE).info()
