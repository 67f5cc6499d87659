"""Synthetic bimanual-eating demonstrations (fork = observation, knife = action), seeded: same ``seed``, same data.

The real SuperLimb data set is not public; this generator behaves like it so that the analysis has something to find:

* observation ``o`` (9): fork tip position [m] (x, y, z, plate frame), orientation [rad] (roll, pitch, yaw) and
  contact force [N] (fx, fy, fz); action ``u`` (9): the knife's, same layout;
* voluntary channel (3): shoulder elevation, protraction and abduction [rad] of the wearer's affected arm;
* the eating task's four modes (:data:`sim.task.eating.MODE_NAMES`, in label order), semi-Markov: ``cutting``
  (the fork holds the food, the knife saws: not predictable from the fork), ``repositioning`` (the knife
  escorts the fork to the next piece), ``collecting`` (the knife pushes the piece on), ``removing`` (the fork
  lifts to the mouth, the knife returns to rest).

Within a mode the knife is a smooth function of the fork's recent motion, u = f_m(o_t, ȯ_t) + low-pass; the
fork's poses of different modes overlap where the f_m differ, so without the mode the data confound. Each
subject has a style (speed, amplitude, mode durations, offsets). The knife tip never goes below the plate
(z = 0): where the hand aims lower it rests on the plate and presses harder (:func:`_rest_on_plate`; only the
0.5 mm sensor noise reads below). Every tip is reachable by the arm on the swaying torso
(tests/robot/test_kinematics.py). Calibration against the paper's shares of large quotients: docs/results.md,
"How the synthetic demonstrations were calibrated". Bad sizes raise ValueError.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import signal

from learning.data import Demonstrations, Trial
from sim.task.eating import MODE_NAMES, SHOULDER_CHANNELS

__all__ = [
    "DEFAULT_MINUTES",
    "DEFAULT_SUBJECTS",
    "OBS_NAMES",
    "ACT_NAMES",
    "VOL_NAMES",
    "SubjectStyle",
    "GeneratorConfig",
    "generate_demonstrations",
    "generate_trial",
]

#: the labels of the modes (the rows of the tables below)
CUTTING, REPOSITIONING, COLLECTING, REMOVING = (MODE_NAMES.index(m) for m in
                                                ("cutting", "repositioning", "collecting", "removing"))
_POSE_FORCE = ("x", "y", "z", "roll", "pitch", "yaw", "fx", "fy", "fz")
OBS_NAMES: tuple[str, ...] = tuple(f"fork_{c}" for c in _POSE_FORCE)
ACT_NAMES: tuple[str, ...] = tuple(f"knife_{c}" for c in _POSE_FORCE)
VOL_NAMES: tuple[str, ...] = SHOULDER_CHANNELS
#: the default data set's size: subjects, and minutes per subject (``mpcshare generate`` and ``demo`` read them)
DEFAULT_SUBJECTS: int = 3
DEFAULT_MINUTES: float = 10.0

# Embedded transition matrix between *different* modes (rows: from, cols: to);
# the usual cycle is repositioning → cutting → collecting → removing → repositioning,
# with re-cuts and re-collects.
_TRANSITIONS = np.array([
    # cut   repo  coll  rem
    [0.00, 0.15, 0.85, 0.00],  # cutting
    [0.25, 0.00, 0.75, 0.00],  # repositioning (soft pieces need no cutting)
    [0.10, 0.05, 0.00, 0.85],  # collecting
    [0.00, 1.00, 0.00, 0.00],  # removing
])
# Mean segment duration [s] per mode for a subject of speed 1.
_MEAN_DURATION_S = np.array([4.5, 7.0, 5.0, 6.0])


@dataclass(frozen=True)
class SubjectStyle:
    """How one subject eats.

    Attributes:
        speed: time scale of motions (>1 faster) [-].
        amplitude: scale of fork excursions [-].
        duration_scale: multiplies the mode durations [-].
        saw_hz: sawing frequency of the knife [Hz].
        saw_amplitude_m: sawing half-stroke [m].
        offset_m: subject-specific knife offset added in every mode [m] (3,).
    """

    speed: float = 1.0
    amplitude: float = 1.0
    duration_scale: float = 1.0
    saw_hz: float = 2.0
    saw_amplitude_m: float = 0.02
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @staticmethod
    def random(rng: np.random.Generator) -> "SubjectStyle":
        """A plausible random style."""
        return SubjectStyle(
            speed=float(rng.uniform(0.85, 1.2)),
            amplitude=float(rng.uniform(0.85, 1.15)),
            duration_scale=float(rng.uniform(0.85, 1.2)),
            saw_hz=float(rng.uniform(1.6, 2.6)),
            saw_amplitude_m=float(rng.uniform(0.015, 0.025)),
            offset_m=tuple(float(v) for v in rng.normal(0.0, 0.004, 3)),
        )


@dataclass(frozen=True)
class GeneratorConfig:
    """Parameters of the generator (defaults are the calibrated ones).

    Attributes:
        rate_hz: sample rate [Hz].
        trial_minutes: length of one continuous demonstration [min].
        overlap: how much the fork poses of different modes overlap, 0 (well
            separated modes, no confounding) … 1 (identical mode poses) [-].
        obs_noise: sensor noise std of the fork, in units of each channel's
            typical range [-].
        act_noise: same for the knife [-].
        contrast: how different the knife behaviours of the modes are (scales
            each mode's knife offset from the mean of all modes) [-].
        reaction_s: delay between a change of the fork's mode and the knife's [s].
        single_regime: if True, one mode only (no mode structure): the knife is
            one smooth function of the fork; used to check that the analysis
            does not report a gain from modes where there is none.
    """

    rate_hz: float = 100.0
    trial_minutes: float = 2.0
    overlap: float = 0.6
    obs_noise: float = 0.004
    act_noise: float = 0.01
    contrast: float = 1.5
    reaction_s: float = 0.1
    single_regime: bool = False
    styles: tuple[SubjectStyle, ...] = field(default_factory=tuple)


# Typical range of each channel (for noise scaling): position [m], angle [rad], force [N].
SCOOP_TILT_RAD = 0.15  # fork pitch added when scooping a piece [rad]
REMOVING_HOLD = 0.1  # share of a removing segment the fork holds before lifting [-]
_CHANNEL_SCALE = np.array([0.05, 0.05, 0.05, 0.2, 0.2, 0.2, 2.0, 2.0, 2.0])
PLATE_SURFACE_Z = 0.0  # [m] the plate's top surface in the plate frame
# [N/m] extra knife pressing force per metre aimed below the plate: 2 cm → 0.4 N on top of the
# mode's own pressing force. Kept soft: 100 N/m moved the calibration (seed 1: 45.8 % → 51.2 %
# of points above K = 5 without modes, 11.7 % → 13.6 % within modes); 20 N/m leaves it in place.
PLATE_CONTACT_STIFFNESS = 20.0


def _mode_sequence(rng: np.random.Generator, n_samples: int, rate_hz: float,
                   style: SubjectStyle, single_regime: bool) -> tuple[np.ndarray, np.ndarray]:
    """Semi-Markov mode labels (T,) and the start index of each segment."""
    if single_regime:
        modes, starts, t = [], [], 0
        while t < n_samples:  # segments still exist (new target poses), one regime
            d = max(int(rng.gamma(6.0, 3.0 / 6.0) * rate_hz / style.speed), 5)
            modes.append(REPOSITIONING)
            starts.append(t)
            t += d
        labels = np.repeat(np.array(modes), np.diff(np.append(starts, n_samples)))
        return labels[:n_samples], np.array(starts)
    m = int(rng.choice([REPOSITIONING, CUTTING]))
    modes, starts, t = [], [], 0
    while t < n_samples:
        mean_s = _MEAN_DURATION_S[m] * style.duration_scale / style.speed
        d = max(int(rng.gamma(8.0, mean_s / 8.0) * rate_hz), int(0.8 * rate_hz))
        modes.append(m)
        starts.append(t)
        t += d
        m = int(rng.choice(4, p=_TRANSITIONS[m]))
    labels = np.repeat(np.array(modes), np.diff(np.append(starts, n_samples)))
    return labels[:n_samples], np.array(starts)


def _critically_damped(x: np.ndarray, tau_s: float, rate_hz: float) -> np.ndarray:
    """Second-order critically damped low-pass along axis 0 (time constant tau [s])."""
    a = np.exp(-1.0 / (tau_s * rate_hz))
    b, den = [(1 - a) ** 2], [1.0, -2 * a, a * a]
    zi = signal.lfilter_zi(b, den)
    out = np.empty_like(x)
    for c in range(x.shape[1]):
        out[:, c], _ = signal.lfilter(b, den, x[:, c], zi=zi * x[0, c])
    return out


def _fork_targets(rng: np.random.Generator, labels: np.ndarray, starts: np.ndarray,
                  rate_hz: float, style: SubjectStyle, overlap: float) -> np.ndarray:
    """Piecewise fork targets (T, 9): where each mode drives the fork.

    Three modes hold the fork at the current piece on the plate (cutting presses,
    collecting tilts to scoop, removing starts from it); their *holding poses*
    differ only by small cues whose size is ``(1 - overlap)`` times a full cue, so
    ``overlap`` sets how confounding the data is.
    """
    T = labels.shape[0]
    hold = np.array([0.0, 0.0, 0.005, 0.0, -0.55, 0.0, 0.0, 0.0, -1.6])  # fork on a piece
    cue = np.array([
        # x  y   z      roll  pitch  yaw   fx    fy   fz       (full-size mode cues)
        [0, 0, -0.004, 0.10, -0.10, 0.00, 0.3, 0.0, -2.5],   # cutting: presses harder
        [0, 0, 0.020, -0.06, 0.10, 0.06, 0.0, 0.0, 1.2],     # repositioning: lifted, light
        [0, 0, 0.004, -0.03, 0.10, -0.06, -0.3, 0.2, 0.4],   # collecting: tilted, lighter
        [0, 0, 0.010, 0.03, 0.05, 0.03, 0.0, -0.2, 0.8],     # removing: unloading
    ])
    mode_pose = hold + (1.0 - overlap) * cue
    out = np.empty((T, 9))
    piece = rng.normal(0.0, 0.035, 2)  # current piece on the plate [m]
    bounds = np.append(starts, T)
    for k in range(len(starts)):
        a, b = bounds[k], bounds[k + 1]
        m = labels[a]
        n = b - a
        tt = np.arange(n) / rate_hz
        s = np.clip(tt / max(tt[-1], 1e-9), 0.0, 1.0)  # segment progress 0..1
        seg = np.tile(mode_pose[m], (n, 1))
        seg += rng.normal(0.0, 0.02, 9) * _CHANNEL_SCALE  # this piece's own pose
        seg[:, :2] += piece
        if m == REPOSITIONING:
            new_piece = np.clip(piece + rng.normal(0.0, 0.04, 2) * style.amplitude, -0.08, 0.08)
            ease = 0.5 - 0.5 * np.cos(np.pi * s)
            seg[:, :2] += np.outer(ease, new_piece - piece)
            seg[:, 2] += 0.02 * style.amplitude * np.sin(np.pi * s)
            piece = new_piece
        elif m == COLLECTING:  # hold while the knife comes round, then tilt to scoop
            scoop = np.clip((s - 0.4) / 0.6, 0.0, 1.0)
            seg[:, 4] += SCOOP_TILT_RAD * style.amplitude * (0.5 - 0.5 * np.cos(np.pi * scoop))
            seg[:, 0] += 0.01 * style.amplitude * scoop
        elif m == REMOVING:  # hold the scoop while the knife withdraws, lift to the mouth, return
            seg[:, 4] += SCOOP_TILT_RAD * style.amplitude
            seg[:, 0] += 0.01 * style.amplitude
            lift = np.sin(np.pi * np.clip((s - REMOVING_HOLD) / (1 - REMOVING_HOLD), 0.0, 1.0)) ** 2
            seg[:, 2] += 0.22 * style.amplitude * lift
            seg[:, 0] -= 0.10 * style.amplitude * lift
            seg[:, 3] += 0.5 * lift
        out[a:b] = seg
    return out


# Knife behaviour per mode: u = base_m + gain_m ⊙ [p, r, f] + lead_m · ṗ  (p, r, f: fork
# position, orientation, force; ṗ: fork velocity [m/s]). Rows: cutting, repositioning,
# collecting, removing. Columns of KNIFE_BASE: x y z [m], roll pitch yaw [rad], fx fy fz [N].
KNIFE_BASE = np.array([
    [0.035, 0.015, 0.00, 0.0, 0.90, 0.2, 0.0, 0.0, -3.0],   # cutting: beside the fork, pressing
    [0.040, -0.050, 0.01, 0.0, 0.35, 0.5, 0.0, 0.0, 0.0],   # repositioning: escorts the fork
    [0.050, 0.020, 0.00, 0.0, 0.60, -0.4, 1.0, 0.0, -0.5],  # collecting: pushes the piece on
    [0.070, -0.060, 0.06, 0.0, 0.40, 0.4, 0.0, 0.0, 0.0],   # removing: back to rest
])
KNIFE_GAIN = np.array([  # per mode: gain on fork position, orientation, force
    [1.0, 0.3, 0.3],
    [1.0, 0.5, 0.1],
    [1.0, -1.0, -0.6],
    [0.2, 0.2, 0.0],
])
KNIFE_LEAD_S = np.array([0.0, 0.4, -0.8, 0.0])  # knife position lead on fork velocity [s]


def _knife_from_fork(fork: np.ndarray, fork_vel: np.ndarray, labels: np.ndarray,
                     rate_hz: float, style: SubjectStyle, rng: np.random.Generator,
                     contrast: float) -> np.ndarray:
    """Knife pose and force (T, 9): a smooth affine function of the fork per mode, plus sawing.

    ``contrast`` scales how far the modes' knife behaviours lie from their mean.
    """
    T = fork.shape[0]
    base = KNIFE_BASE.mean(axis=0) + contrast * (KNIFE_BASE - KNIFE_BASE.mean(axis=0))
    base[:, :3] += np.array(style.offset_m)
    gain = np.repeat(KNIFE_GAIN, 3, axis=1)  # (4, 9)
    knife = base[labels] + gain[labels] * fork
    knife[:, :3] += KNIFE_LEAD_S[labels, None] * fork_vel[:, :3]
    # sawing: back-and-forth along x while cutting, amplitude and frequency wander
    cut = (labels == CUTTING).astype(float)
    t = np.arange(T) / rate_hz
    freq = style.saw_hz * (1.0 + 0.15 * np.sin(2 * np.pi * 0.05 * t + rng.uniform(0, 6.3)))
    phase = 2 * np.pi * np.cumsum(freq) / rate_hz + rng.uniform(0, 2 * np.pi)
    amp = style.saw_amplitude_m * (1.0 + 0.3 * np.sin(2 * np.pi * 0.11 * t + rng.uniform(0, 6.3)))
    ramp = _critically_damped(cut[:, None], 0.1, rate_hz)[:, 0]
    saw = ramp * amp * np.sin(phase)
    knife[:, 0] += saw
    knife[:, 5] += 4.0 * saw  # the blade yaws with the stroke
    knife[:, 6] += 60.0 * saw * np.cos(phase) * ramp  # friction force along the stroke
    return knife


def _rest_on_plate(knife: np.ndarray) -> None:
    """Keep the knife tip on or above the plate's surface (z = 0), in place.

    Where the hand's aim ``z`` lies below the surface by d = −z > 0 the tip rests
    on the plate (z = 0) and presses harder: f_z −= k·d with k =
    :data:`PLATE_CONTACT_STIFFNESS`.  Applied before the hand's low-pass, whose
    impulse response is non-negative, so the filtered tip stays ≥ 0 too; only
    the added sensor noise (σ = ``act_noise``·0.05 m) can read below it.
    """
    depth = np.maximum(PLATE_SURFACE_Z - knife[:, 2], 0.0)
    knife[:, 2] += depth
    knife[:, 8] -= PLATE_CONTACT_STIFFNESS * depth


def generate_trial(rng: np.random.Generator, n_samples: int, style: SubjectStyle,
                   config: GeneratorConfig, trial_id: int = 0, subject: int = 0,
                   t0: float = 0.0) -> Trial:
    """One continuous demonstration of ``n_samples`` samples at ``config.rate_hz``."""
    if n_samples < 2:
        raise ValueError(f"a trial needs at least 2 samples, got {n_samples}")
    rate = config.rate_hz
    labels, starts = _mode_sequence(rng, n_samples, rate, style, config.single_regime)
    targets = _fork_targets(rng, labels, starts, rate, style,
                            1.0 if config.single_regime else config.overlap)
    fork = _critically_damped(targets, 0.06 / style.speed, rate)
    fork_vel = np.gradient(fork, 1.0 / rate, axis=0)
    # the knife reacts to what the fork does: it changes behaviour a reaction time
    # after the fork has changed mode
    lag = int(round(config.reaction_s * rate))
    knife_labels = np.concatenate([np.full(lag, labels[0]), labels[:n_samples - lag]]) if lag else labels
    knife_raw = _knife_from_fork(fork, fork_vel, knife_labels, rate, style, rng, config.contrast)
    _rest_on_plate(knife_raw)
    # the knife is held by a hand: it cannot jump when the mode switches
    knife = _critically_damped(knife_raw, 0.06, rate)
    # voluntary channel: shoulder motion proportional to the intended knife velocity
    knife_vel = np.gradient(knife, 1.0 / rate, axis=0)
    W = np.array([[0.0, 0.0, 2.5], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]])  # [rad per m/s]
    shoulder = knife_vel[:, :3] @ W.T
    shoulder = _critically_damped(shoulder, 0.08, rate) + rng.normal(0.0, 0.01, (n_samples, 3))
    fork = fork + rng.normal(0.0, 1.0, fork.shape) * _CHANNEL_SCALE * config.obs_noise
    knife = knife + rng.normal(0.0, 1.0, knife.shape) * _CHANNEL_SCALE * config.act_noise
    t = t0 + np.arange(n_samples) / rate
    return Trial(obs=fork, act=knife, t=t, trial_id=trial_id, subject=subject,
                 mode=labels.astype(int), voluntary=shoulder)


def generate_demonstrations(n_subjects: int = DEFAULT_SUBJECTS, minutes: float = DEFAULT_MINUTES, seed: int = 0,
                            config: GeneratorConfig | None = None) -> Demonstrations:
    """Synthetic eating demonstrations: ``minutes`` per subject, split into trials.

    Args:
        n_subjects: number of subjects, each with its own style.
        minutes: recorded time per subject [min] (up to 60 and beyond; memory is
            O(samples), about 170 bytes a sample).
        seed: the same seed gives the same data set.
        config: generator parameters; ``config.styles`` fixes subject styles.

    Returns:
        Demonstrations at ``config.rate_hz`` with ground-truth ``mode`` labels
        (indices into :data:`sim.task.eating.MODE_NAMES`) and the voluntary channel.
    """
    config = config or GeneratorConfig()
    if n_subjects < 1:
        raise ValueError(f"n_subjects must be >= 1, got {n_subjects}")
    if not minutes > 0:
        raise ValueError(f"minutes must be > 0, got {minutes}")
    rate = config.rate_hz
    root = np.random.default_rng(seed)
    trials: list[Trial] = []
    per_trial = max(int(round(config.trial_minutes * 60 * rate)), 2)
    total = int(round(minutes * 60 * rate))
    for s in range(n_subjects):
        rng = np.random.default_rng(root.integers(2**63))
        style = config.styles[s] if s < len(config.styles) else SubjectStyle.random(rng)
        left = total
        while left >= 2:
            n = per_trial if left - per_trial >= per_trial // 2 else left
            trials.append(generate_trial(rng, n, style, config, trial_id=len(trials), subject=s))
            left -= n
    return Demonstrations(trials, rate, list(OBS_NAMES), list(ACT_NAMES), list(VOL_NAMES))
