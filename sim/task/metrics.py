"""The figures a task's metrics are made of: is the tip on time, does it stroke as intended, per mode.

The machinery every task composes (:mod:`sim.task.eating` picks its own; :class:`sim.task.Task`): tracking RMS
hides a tip 0.4 s late and a tip that misses the strokes (a missed 2 cm stroke costs only about 14 mm RMS).
With p the tip and p* the intent (plate frame [m], control period Δ [s]):

* **lag** τ* [s] = argmin_τ sqrt(mean_k ‖p(t_k + τ) − p*(t_k)‖²), τ ∈ {−τ_max, …, τ_max} in steps of Δ
  (positive: late); ``rms_at_lag_m`` is that minimum.
* **stroke fidelity** on the stroke mode's samples (``cutting_mask``), both signals band-passed to the task's
  stroke band (zero-phase 2nd-order Butterworth over the whole episode: no transient at the mask's edges) to
  b, b*: amplitude ratio = sqrt(Σ‖b_k‖² / Σ‖b*_k‖²), correlation = Σ b_k·b*_k / sqrt(Σ‖b_k‖² Σ‖b*_k‖²)
  (no shift: a stroke a quarter cycle late scores 0).
* **strokes executed**: the intent's band-passed motion along its principal direction in the mode, cut at
  upward zero crossings into cycles; a cycle is executed when the tip's peak-to-peak excursion along it is at
  least ``stroke_fraction`` (0.5) of the intent's; the share counts cycles whose intended excursion is at least
  ``min_stroke_m`` (5 mm).
* **stroke fidelity per episode** (:func:`sawing_by_episode`): the same over each run of stroke-mode samples at
  least ``min_episode_s`` long (one cutting episode; a shorter run is not judged), band-passed as above.
* **RMS per mode**: the tracking RMS over the steps of each (true) mode.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from scipy.signal import butter, sosfiltfilt

__all__ = ["MIN_EPISODE_S", "PICKUP_WINDOW_S", "SawingFidelity", "bandpass", "pickup_error", "rms_by_mode",
           "sawing_by_episode", "sawing_fidelity", "time_lag", "wearer_share_by_mode"]

#: [s] the shortest run of the stroke mode judged as a cutting episode of its own: one cycle at 1 Hz (the
#: demonstrations saw at 1.6–2.6 Hz, so such an episode holds 1.6–2.6 strokes)
MIN_EPISODE_S = 1.0


def _check(tip: np.ndarray, intent: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    tip, intent = np.asarray(tip, dtype=float), np.asarray(intent, dtype=float)
    if tip.ndim != 2 or tip.shape != intent.shape:
        raise ValueError(f"tip and intent must be (N, d) arrays of one shape, got {tip.shape} and {intent.shape}")
    return tip, intent


def time_lag(tip: np.ndarray, intent: np.ndarray, dt: float, max_lag_s: float = 1.0) -> tuple[float, float]:
    """(τ* [s], RMS at τ* [m]) of the module docstring; (nan, nan) without two finite samples."""
    tip, intent = _check(tip, intent)
    if not dt > 0:
        raise ValueError(f"dt must be > 0, got {dt}")
    n = len(tip)
    max_shift = int(min(round(max_lag_s / dt), n // 2))
    best = (float("nan"), float("inf"))
    for s in range(-max_shift, max_shift + 1):
        a = tip[s:] if s >= 0 else tip[:n + s]  # p(t_k + τ) for τ = s·Δ
        b = intent[:n - s] if s >= 0 else intent[-s:]
        e = np.sum((a - b) ** 2, axis=1)
        e = e[np.isfinite(e)]
        if e.size < 2:
            continue
        rms = float(np.sqrt(e.mean()))
        if rms < best[1]:
            best = (s * dt, rms)
    return best if np.isfinite(best[1]) else (float("nan"), float("nan"))


@dataclass(frozen=True)
class SawingFidelity:
    """The stroke-band figures while cutting (module docstring); None where there was no cutting."""

    amplitude_ratio: float | None
    correlation: float | None
    strokes_intended: int
    strokes_executed: int
    stroke_share: float | None
    cutting_s: float

    def to_dict(self) -> dict:
        return asdict(self)


def bandpass(x: np.ndarray, dt: float, band: tuple[float, float]) -> np.ndarray:
    """Zero-phase Butterworth band-pass (order 2, forward-backward) of (N, d) samples every dt [s]."""
    nyquist = 0.5 / dt
    if not 0 < band[0] < band[1] < nyquist:
        raise ValueError(f"stroke band {band} Hz must lie in (0, {nyquist:g}) Hz")
    sos = butter(2, [band[0] / nyquist, band[1] / nyquist], btype="bandpass", output="sos")
    x = np.where(np.isfinite(x), x, 0.0)
    if len(x) <= 15:  # too short for sosfiltfilt's padding
        return np.zeros_like(x)
    return sosfiltfilt(sos, x, axis=0)


def sawing_fidelity(tip: np.ndarray, intent: np.ndarray, cutting_mask: np.ndarray, dt: float,
                    band: tuple[float, float], stroke_fraction: float = 0.5,
                    min_stroke_m: float = 0.005) -> SawingFidelity:
    """Amplitude ratio, correlation and share of strokes executed in the stroke mode, in ``band`` [Hz]
    (module docstring)."""
    tip, intent = _check(tip, intent)
    mask = _mask(cutting_mask, len(tip))
    return _fidelity(bandpass(tip, dt, band), bandpass(intent, dt, band), mask, dt, stroke_fraction, min_stroke_m)


def sawing_by_episode(tip: np.ndarray, intent: np.ndarray, cutting_mask: np.ndarray, dt: float,
                      band: tuple[float, float], min_episode_s: float = MIN_EPISODE_S, stroke_fraction: float = 0.5,
                      min_stroke_m: float = 0.005) -> list[tuple[float, SawingFidelity]]:
    """(start [s] from the first sample, :func:`sawing_fidelity`'s figures) of each cutting episode: each run of
    consecutive ``cutting_mask`` samples at least ``min_episode_s`` long, in time order (module docstring); the
    band-pass runs once over the whole signals. ValueError for a mask of another length, ``dt`` ≤ 0 or a
    negative ``min_episode_s``."""
    tip, intent = _check(tip, intent)
    mask = _mask(cutting_mask, len(tip))
    if not dt > 0 or not min_episode_s >= 0:
        raise ValueError(f"dt must be > 0 and min_episode_s >= 0, got {dt!r} and {min_episode_s!r}")
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(np.int8), [0]])))
    runs = [(a, z) for a, z in zip(edges[::2], edges[1::2]) if (z - a) * dt >= min_episode_s - 1e-9]
    if not runs:
        return []
    b, b_star = bandpass(tip, dt, band), bandpass(intent, dt, band)
    out = []
    for a, z in runs:
        run = np.zeros_like(mask)
        run[a:z] = True
        out.append((float(a * dt), _fidelity(b, b_star, run, dt, stroke_fraction, min_stroke_m)))
    return out


def _mask(cutting_mask: np.ndarray, n: int) -> np.ndarray:
    """``cutting_mask`` as a boolean (n,) array; ValueError for another shape."""
    mask = np.asarray(cutting_mask, dtype=bool)
    if mask.shape != (n,):
        raise ValueError(f"cutting_mask must have shape ({n},), got {mask.shape}")
    return mask


def _fidelity(b_all: np.ndarray, b_star_all: np.ndarray, mask: np.ndarray, dt: float, stroke_fraction: float,
              min_stroke_m: float) -> SawingFidelity:
    """:func:`sawing_fidelity` from the band-passed tip and intent over the whole episode."""
    cutting_s = float(mask.sum() * dt)
    if mask.sum() < 2:
        return SawingFidelity(None, None, 0, 0, None, cutting_s)
    b, b_star = b_all[mask], b_star_all[mask]
    e_tip, e_int = float(np.sum(b**2)), float(np.sum(b_star**2))
    amplitude = float(np.sqrt(e_tip / e_int)) if e_int > 0 else None
    corr = float(np.sum(b * b_star) / np.sqrt(e_tip * e_int)) if e_tip > 0 and e_int > 0 else None
    intended, executed = _strokes(b, b_star, mask, stroke_fraction, min_stroke_m)
    share = executed / intended if intended else None
    return SawingFidelity(amplitude, corr, intended, executed, share, cutting_s)


def _strokes(b: np.ndarray, b_star: np.ndarray, mask: np.ndarray, fraction: float,
             min_stroke_m: float) -> tuple[int, int]:
    """(cycles intended, cycles executed) along the intent's principal stroke direction."""
    _, _, vt = np.linalg.svd(b_star - b_star.mean(axis=0), full_matrices=False)
    axis = vt[0]
    s_int, s_tip = b_star @ axis, b @ axis
    # runs of consecutive cutting samples: a cycle never spans two cutting segments
    idx = np.flatnonzero(mask)
    breaks = np.flatnonzero(np.diff(idx) > 1) + 1
    intended = executed = 0
    for seg in np.split(np.arange(len(idx)), breaks):
        up = seg[:-1][(s_int[seg[:-1]] < 0) & (s_int[seg[1:]] >= 0)] + 1
        for a, z in zip(up[:-1], up[1:]):
            p2p = float(np.ptp(s_int[a:z]))
            if p2p < min_stroke_m:
                continue
            intended += 1
            executed += float(np.ptp(s_tip[a:z])) >= fraction * p2p
    return intended, executed


def rms_by_mode(tip: np.ndarray, intent: np.ndarray, modes: np.ndarray,
                names: tuple[str, ...] | None = None) -> dict[str, float | None]:
    """Tracking RMS [m] over the steps of each mode (label ≥ 0), keyed by name (or the label)."""
    tip, intent = _check(tip, intent)
    modes = np.asarray(modes)
    if modes.shape != (len(tip),):
        raise ValueError(f"modes must have shape ({len(tip)},), got {modes.shape}")
    e2 = np.sum((tip - intent) ** 2, axis=1)
    out: dict[str, float | None] = {}
    for m in sorted(int(x) for x in np.unique(modes) if x >= 0):
        sel = (modes == m) & np.isfinite(e2)
        key = names[m] if names is not None and m < len(names) else str(m)
        out[key] = float(np.sqrt(e2[sel].mean())) if sel.any() else None
    return out


#: [s] how long after a hand-over to the wearer counts as their pick-up (:func:`pickup_error`): the
#: default wearer's reaction (0.3 s) and one corrective time constant (1/K ≈ 0.67 s at K = 1.5/s) about
PICKUP_WINDOW_S = 1.0


def pickup_error(tip: np.ndarray, intent: np.ndarray, alpha: np.ndarray, dt: float,
                 window_s: float = PICKUP_WINDOW_S) -> dict[str, Any]:
    """What the hand-overs to the wearer cost while they pick up: over the ``window_s`` [s]
    after each step where α crosses below 0.5 (the robot led the step before, the wearer leads now),

        pickup_rms_m = √(mean ‖p − p*‖² over those steps),   pickup_s = their time [s],
        pickup_error_share = Σ_window ‖p − p*‖² / Σ_all ‖p − p*‖²,   pickups = the number of hand-overs;

    ``pickup_rms_m`` and the share are None without such a hand-over."""
    tip, intent = _check(tip, intent)
    a = np.asarray(alpha, dtype=float)
    if a.shape != (tip.shape[0],):
        raise ValueError(f"alpha has shape {a.shape}, the episode {tip.shape[0]} steps")
    lead = a >= 0.5  # NaN: the wearer leads
    starts = np.flatnonzero(lead[:-1] & ~lead[1:]) + 1
    inside = np.zeros(a.size, dtype=bool)
    n_win = max(int(round(window_s / dt)), 1)
    for k in starts:
        inside[k:k + n_win] = True
    err2 = np.sum((tip - intent) ** 2, axis=1)
    ok = np.isfinite(err2)
    total, win = float(np.sum(err2[ok])), inside & ok
    if not starts.size or not win.any():
        return {"pickups": 0, "pickup_rms_m": None, "pickup_s": 0.0, "pickup_error_share": None}
    return {"pickups": int(starts.size), "pickup_rms_m": float(np.sqrt(np.mean(err2[win]))),
            "pickup_s": float(win.sum() * dt), "pickup_error_share": float(np.sum(err2[win]) / total) if total > 0
            else None}


def wearer_share_by_mode(alpha: np.ndarray, true_mode: np.ndarray, mode_names: tuple[str, ...] | None = None
                         ) -> tuple[dict[str, float], dict[str, int]]:
    """Per true mode: the share of control steps where the wearer leads (α < 0.5), and the step count."""
    alpha, true_mode = np.asarray(alpha, dtype=float), np.asarray(true_mode)
    if alpha.shape != true_mode.shape:
        raise ValueError(f"alpha {alpha.shape} and true_mode {true_mode.shape} must have one shape")
    shares, counts = {}, {}
    for j in np.unique(true_mode[true_mode >= 0]):
        sel = true_mode == j
        name = mode_names[j] if mode_names is not None and 0 <= j < len(mode_names) else str(int(j))
        shares[name], counts[name] = float(np.mean(~(alpha[sel] >= 0.5))), int(sel.sum())
    return shares, counts
