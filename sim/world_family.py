"""A randomised family of eating worlds: the *structure* of each world is drawn from its seed.

Unlike :mod:`sim.demonstrator` in structure, a world (:func:`draw_world`, one :class:`WorldSpec` a seed) draws:

* **modes**: K ∈ {2, …, 5}, transitions Dirichlet(1) between different modes, gamma(3) dwells of mean 2–9 s;
  label 0 the *stroke* mode ``cutting`` (rhythmic knife motion along a drawn axis, 0.9–2.8 Hz ± 10 %,
  half-stroke 0.8–3 cm, a new phase at each entry: no function of the fork); the others ``track``, ``fidget``
  (plus noise of 0.2–0.8 Hz, 0.6–1.5 cm) or ``rest`` (the knife's own pose, slow drift), at least one ``track``;
* **the knife**, per mode m:  k(t) = b_m + A_m·(h_m(t − d) − c) + ℓ_m·ḟ(t − d) + s_m(t)  [m], h_m the fork
  position low-passed with τ_m ∈ [0.05, 0.8] s, A_m a rotation about z by ±60° times a gain in [0.4, 1.2],
  ℓ_m ∈ [−0.4, 0.6] s, b_m the mode's offset, c the plate centre, s_m the stroke or fidget, d ∈ [0, 0.4] s
  (the knife's labels switch d later too);
* **the fork**: Ornstein–Uhlenbeck (0.4–2 s, 0.6–2.5 cm) around a per-mode anchor that moves 1–3 cm at each
  entry, low-passed 0.1–0.4 s; orientation and force carry a per-mode cue of drawn size;
* **noise** (fork 0.2–1.5 mm, knife 0.3–2 mm), the hand's low-pass (0.02–0.06 s, the stroke scaled by its
  inverse gain), the shoulder gains (1.5–3 rad per m/s, :data:`sim.task.eating.SHOULDER_TO_PLATE` layout),
  1–3 subjects whose pace scales dwells and stroke frequency (± 15 %).

Channels as :data:`sim.demonstrator.OBS_NAMES` (plate frame; m, rad, N), ``mode`` the fork's true mode, the tip
at z ≥ 0 (before noise) inside the project's demonstrations' region. Same seed, same world and data.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy import signal

from learning.data import Demonstrations, Trial
from sim.demonstrator import ACT_NAMES, OBS_NAMES, VOL_NAMES
from sim.task.eating import STROKE_MODE

__all__ = ["KINDS", "WorldSpec", "draw_world", "world_demonstrations", "world_trial"]

KINDS: tuple[str, ...] = ("stroke", "track", "fidget", "rest")
_KNIFE_LO = np.array([-0.04, -0.08, 0.0])  # [m] the knife region of the project's demonstrations
_KNIFE_HI = np.array([0.10, 0.12, 0.13])


@dataclass(frozen=True)
class WorldSpec:
    """The drawn structure of one world (module docstring); arrays are per mode (K first)."""

    seed: int
    kinds: tuple[str, ...]
    transitions: np.ndarray  # (K, K) rows sum to 1, zero diagonal
    dwell_s: np.ndarray  # (K,) mean dwell [s]
    stroke_hz: float
    stroke_amp_m: float
    stroke_axis: np.ndarray  # (3,) unit
    fidget_hz: float
    fidget_amp_m: float
    anchor_m: np.ndarray  # (K, 3) fork anchor [m]
    cue: np.ndarray  # (K, 4) fork roll, pitch, yaw [rad] and force fz [N] per mode
    gain: np.ndarray  # (K, 3, 3) A_m
    tau_s: np.ndarray  # (K,) τ_m [s]
    lead_s: np.ndarray  # (K,) ℓ_m [s]
    offset_m: np.ndarray  # (K, 3) b_m [m]
    knife_delay_s: float
    fork_drift_s: float
    fork_spread_m: float
    fork_smooth_s: float
    piece_jitter_m: float
    hand_s: float
    obs_noise_m: float
    act_noise_m: float
    shoulder_gain: np.ndarray  # (3,) [rad per m/s] elevation←z, protraction←x, abduction←y
    paces: tuple[float, ...]  # per subject

    @property
    def n_modes(self) -> int:
        return len(self.kinds)

    @property
    def mode_names(self) -> tuple[str, ...]:
        """``cutting`` for the stroke mode (label 0), ``<kind><label>`` for the others."""
        return tuple(STROKE_MODE if k == "stroke" else f"{k}{j}" for j, k in enumerate(self.kinds))

    def to_dict(self) -> dict:
        """JSON-able description (arrays as lists)."""
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in asdict(self).items()} | {
            "mode_names": list(self.mode_names)}


def _rotation_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def draw_world(seed: int) -> WorldSpec:
    """The structure of world ``seed`` (module docstring)."""
    rng = np.random.default_rng([28, int(seed)])
    K = int(rng.integers(2, 6))
    others = [str(k) for k in rng.choice(["track", "fidget", "rest"], size=K - 1, p=[0.5, 0.25, 0.25])]
    if "track" not in others:
        others[int(rng.integers(K - 1))] = "track"
    P = np.zeros((K, K))
    for i in range(K):
        idx = [j for j in range(K) if j != i]
        P[i, idx] = rng.dirichlet(np.ones(K - 1))
    axis = np.array([np.cos(a := rng.uniform(0, np.pi)), np.sin(a), rng.uniform(-0.3, 0.3)])
    anchor = np.column_stack([rng.uniform(-0.05, 0.05, K), rng.uniform(-0.04, 0.06, K), rng.uniform(0.005, 0.06, K)])
    cue_size = rng.uniform(0.2, 1.0)  # small: confounded modes
    cue = cue_size * np.column_stack([rng.normal(0, 0.1, K), rng.normal(-0.5, 0.1, K), rng.normal(0, 0.1, K),
                                      rng.uniform(-3.0, 0.5, K)])
    gain = np.stack([_rotation_z(rng.uniform(-np.pi / 3, np.pi / 3)) @ np.diag(rng.uniform(0.4, 1.2, 3))
                     for _ in range(K)])
    offset = np.column_stack([rng.uniform(0.0, 0.06, K), rng.uniform(-0.05, 0.05, K), rng.uniform(0.0, 0.05, K)])
    return WorldSpec(
        seed=int(seed), kinds=("stroke", *others), transitions=P, dwell_s=rng.uniform(2.0, 9.0, K),
        stroke_hz=float(rng.uniform(0.9, 2.8)), stroke_amp_m=float(rng.uniform(0.008, 0.03)),
        stroke_axis=axis / np.linalg.norm(axis), fidget_hz=float(rng.uniform(0.2, 0.8)),
        fidget_amp_m=float(rng.uniform(0.006, 0.015)), anchor_m=anchor, cue=cue, gain=gain,
        tau_s=rng.uniform(0.05, 0.8, K), lead_s=rng.uniform(-0.4, 0.6, K), offset_m=offset,
        knife_delay_s=float(rng.uniform(0.0, 0.4)), fork_drift_s=float(rng.uniform(0.4, 2.0)),
        fork_spread_m=float(rng.uniform(0.006, 0.025)), fork_smooth_s=float(rng.uniform(0.1, 0.4)),
        piece_jitter_m=float(rng.uniform(0.01, 0.03)), hand_s=float(rng.uniform(0.02, 0.06)),
        obs_noise_m=float(rng.uniform(0.0002, 0.0015)), act_noise_m=float(rng.uniform(0.0003, 0.002)),
        shoulder_gain=rng.uniform(1.5, 3.0, 3), paces=tuple(float(p) for p in rng.uniform(0.85, 1.15,
                                                                                          int(rng.integers(1, 4)))))


def _lowpass(x: np.ndarray, tau_s: float, rate: float, order: int = 2) -> np.ndarray:
    """Critically damped low-pass of ``order`` (1 or 2) along axis 0, started at rest on x[0]."""
    a = np.exp(-1.0 / (max(tau_s, 1e-6) * rate))
    b, den = ([1 - a], [1.0, -a]) if order == 1 else ([(1 - a) ** 2], [1.0, -2 * a, a * a])
    zi = signal.lfilter_zi(b, den)
    return np.column_stack([signal.lfilter(b, den, x[:, c], zi=zi * x[0, c])[0] for c in range(x.shape[1])])


def _modes(rng: np.random.Generator, spec: WorldSpec, n: int, rate: float, pace: float) -> np.ndarray:
    """Semi-Markov labels (n,): gamma(3) dwell of mean ``dwell_s / pace``, ≥ 0.6 s."""
    out = np.empty(n, dtype=np.int64)
    t, m = 0, int(rng.integers(spec.n_modes))
    while t < n:
        d = max(int(rng.gamma(3.0, spec.dwell_s[m] / pace / 3.0) * rate), int(0.6 * rate))
        out[t:t + d] = m
        t += d
        m = int(rng.choice(spec.n_modes, p=spec.transitions[m]))
    return out


def _fork(rng: np.random.Generator, spec: WorldSpec, labels: np.ndarray, rate: float) -> np.ndarray:
    """Fork (n, 9): OU drift around the mode's anchor (a new piece at each entry), mode cues."""
    n = labels.size
    starts = np.flatnonzero(np.diff(labels, prepend=-1))
    target = spec.anchor_m[labels].copy()
    for a, b in zip(starts, np.append(starts[1:], n)):
        target[a:b] += rng.normal(0.0, spec.piece_jitter_m, 3) * (1.0, 1.0, 0.3)
    a = np.exp(-1.0 / (spec.fork_drift_s * rate))
    w = rng.normal(0.0, spec.fork_spread_m * np.sqrt(1 - a * a), (n, 3))
    drift = signal.lfilter([1.0], [1.0, -a], w, axis=0)
    pos = _lowpass(target + drift, spec.fork_smooth_s, rate)
    pos[:, 2] = np.maximum(pos[:, 2], 0.002)  # the fork tip on or above the plate
    cue = _lowpass(spec.cue[labels], spec.fork_smooth_s, rate)
    force = np.column_stack([rng.normal(0, 0.1, n), rng.normal(0, 0.1, n), cue[:, 3]])
    return np.column_stack([pos, cue[:, :3], force])


def _spontaneous(rng: np.random.Generator, spec: WorldSpec, mask: np.ndarray, rate: float,
                 pace: float) -> tuple[np.ndarray, np.ndarray]:
    """Stroke (n,) [m] along ``stroke_axis`` while ``mask`` (new phase per entry) and fidget noise (n, 3)."""
    n = mask.size
    t = np.arange(n) / rate
    freq = spec.stroke_hz * pace * (1.0 + 0.1 * np.sin(2 * np.pi * 0.07 * t + rng.uniform(0, 6.3)))
    phase = 2 * np.pi * np.cumsum(freq) / rate
    entries = np.flatnonzero(np.diff(mask.astype(np.int8), prepend=0) == 1)
    offsets = np.zeros(n)
    for e in entries:  # a spontaneous start: the phase at each entry is random
        offsets[e:] = rng.uniform(0, 2 * np.pi) - phase[e]
    ramp = _lowpass(mask[:, None].astype(float), 0.15, rate)[:, 0]
    w_tau = 2 * np.pi * spec.stroke_hz * pace * spec.hand_s  # the hand's 2nd-order low-pass: |H| = 1/(1 + (ωτ)²)
    stroke = spec.stroke_amp_m * (1.0 + w_tau ** 2) * ramp * np.sin(phase + offsets)
    fid = _lowpass(rng.normal(0.0, 1.0, (n, 3)), 1.0 / (2 * np.pi * spec.fidget_hz), rate)
    fid *= spec.fidget_amp_m / max(float(np.sqrt(np.mean(fid ** 2))), 1e-12)
    return stroke, fid


def _knife(rng: np.random.Generator, spec: WorldSpec, fork: np.ndarray, labels: np.ndarray, rate: float,
           pace: float) -> np.ndarray:
    """Knife (n, 9) from the fork's delayed history per mode (module docstring), before noise."""
    n = labels.size
    lag = int(round(spec.knife_delay_s * rate))
    late = np.concatenate([np.repeat(fork[:1], lag, axis=0), fork[:n - lag]]) if lag else fork
    kl = np.concatenate([np.full(lag, labels[0]), labels[:n - lag]]) if lag else labels
    vel = np.gradient(late[:, :3], 1.0 / rate, axis=0)
    centre = spec.anchor_m.mean(axis=0)
    kinds = np.array(spec.kinds)[kl]
    stroke, fid = _spontaneous(rng, spec, kinds == "stroke", rate, pace)
    pos = np.empty((n, 3))
    for m in range(spec.n_modes):
        sel = kl == m
        if not sel.any():
            continue
        if spec.kinds[m] == "rest":
            pos[sel] = spec.offset_m[m] + centre
            continue
        hist = _lowpass(late[:, :3], spec.tau_s[m], rate, order=1)[sel] - centre
        pos[sel] = spec.offset_m[m] + centre + hist @ spec.gain[m].T + spec.lead_s[m] * vel[sel]
    pos += np.outer(stroke, spec.stroke_axis)
    pos += fid * (kinds == "fidget")[:, None]
    rest = kinds == "rest"
    pos[rest] += 0.3 * fid[rest]  # the slow drift of a knife held still
    pos = np.clip(pos, _KNIFE_LO, _KNIFE_HI)
    orient = np.column_stack([np.zeros(n), 0.6 + 0.2 * (kinds == "stroke"), 8.0 * stroke])
    force = np.column_stack([40.0 * np.gradient(stroke, 1.0 / rate), np.zeros(n),
                             -2.0 * (kinds == "stroke") - 20.0 * np.maximum(0.01 - pos[:, 2], 0.0)])
    return _lowpass(np.column_stack([pos, orient, force]), spec.hand_s, rate)


def world_trial(spec: WorldSpec, rng: np.random.Generator, n: int, rate: float, pace: float,
                   trial_id: int, subject: int, t0: float) -> Trial:
    """One trial of ``n`` samples of the world ``spec``."""
    labels = _modes(rng, spec, n, rate, pace)
    fork = _fork(rng, spec, labels, rate)
    knife = _knife(rng, spec, fork, labels, rate, pace)
    vel = np.gradient(knife[:, :3], 1.0 / rate, axis=0)
    g = spec.shoulder_gain  # elevation ← z, protraction ← x, abduction ← y (SHOULDER_TO_PLATE's layout)
    shoulder = _lowpass(np.column_stack([g[0] * vel[:, 2], g[1] * vel[:, 0], g[2] * vel[:, 1]]), 0.08, rate)
    shoulder += rng.normal(0.0, 0.01, shoulder.shape)
    scale = np.array([1, 1, 1, 4, 4, 4, 40, 40, 40])  # noise per channel: m, rad (×4), N (×40)
    fork = fork + rng.normal(0.0, 1.0, fork.shape) * spec.obs_noise_m * scale
    knife = knife + rng.normal(0.0, 1.0, knife.shape) * spec.act_noise_m * scale
    return Trial(obs=fork, act=knife, t=t0 + np.arange(n) / rate, trial_id=trial_id, subject=subject,
                 mode=labels, voluntary=shoulder)


def world_demonstrations(world: int | WorldSpec, n_trials: int = 12, trial_s: float = 60.0,
                         rate_hz: float = 100.0) -> tuple[Demonstrations, WorldSpec]:
    """``n_trials`` trials of ``trial_s`` seconds of a world (a seed or a :class:`WorldSpec`) and its spec.

    Subjects take the trials in turn; each subject's pace scales dwell times and the stroke's
    frequency. The same world and arguments give the same data.
    """
    spec = world if isinstance(world, WorldSpec) else draw_world(int(world))
    if int(n_trials) != n_trials or n_trials < 1:
        raise ValueError(f"n_trials must be a positive integer, got {n_trials!r}")
    n = int(round(trial_s * rate_hz))
    if n < 2:
        raise ValueError(f"a trial of {trial_s} s at {rate_hz} Hz has fewer than 2 samples")
    root = np.random.default_rng([28, spec.seed, 1])
    trials = []
    for k in range(int(n_trials)):
        s = k % len(spec.paces)
        trials.append(world_trial(spec, np.random.default_rng(root.integers(2**63)), n, rate_hz, spec.paces[s],
                                     trial_id=k, subject=s, t0=k * (trial_s + 10.0)))
    return Demonstrations(trials, rate_hz, list(OBS_NAMES), list(ACT_NAMES), list(VOL_NAMES)), spec
