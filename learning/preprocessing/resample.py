"""Causal anti-aliased downsampling, offline and streaming, with identical results.

The analysis may use the zero-phase :func:`learning.preprocessing.preprocess.downsample` (it sees
whole trials). Models that run online must be trained on what the control loop can
compute: a *causal* low-pass filter followed by keeping every ``f``-th sample,
``f = rate_hz / target_hz`` (an integer). :func:`causal_downsample` does that for a
data set; :class:`StreamingDecimator` does it one sample at a time; both use the same
second-order sections and the same initial state, so a recorded trial streamed sample
by sample gives the offline samples (to rounding, ~1e-15).

Filter: Butterworth low-pass of order ``order`` (default 4) with cut-off
``cutoff_ratio × target_hz / 2`` (default 0.8 of the new Nyquist frequency), as
second-order sections (scipy.signal.butter, sosfilt). Its state starts at the steady
state of the first sample (``sosfilt_zi · x_0``), so a trial does not start with a
transient from zero. Kept samples are at input indices 0, f, 2f, …
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from learning.data import Demonstrations, Trial

__all__ = ["StreamingDecimator", "causal_downsample", "decimation_factor", "lowpass_sos"]


def decimation_factor(rate_hz: float, target_hz: float) -> int:
    """The integer ``f = rate_hz / target_hz``; raises ValueError when it is not an integer ≥ 1."""
    rate, target = float(rate_hz), float(target_hz)
    if not (math.isfinite(rate) and rate > 0 and math.isfinite(target) and target > 0):
        raise ValueError(f"rates must be finite and > 0, got rate_hz={rate_hz!r}, target_hz={target_hz!r}")
    f = rate / target
    if f < 1 - 1e-9 or abs(f - round(f)) > 1e-6:
        raise ValueError(f"causal downsampling needs an integer factor rate_hz / target_hz ≥ 1; "
                         f"got {rate:g} Hz / {target:g} Hz = {f:g}")
    return int(np.rint(f))


def lowpass_sos(rate_hz: float, target_hz: float, order: int = 4, cutoff_ratio: float = 0.8) -> np.ndarray:
    """Second-order sections of the anti-aliasing Butterworth low-pass (module docstring).

    Returns an empty (0, 6) array when no filtering is needed (factor 1).
    """
    f = decimation_factor(rate_hz, target_hz)
    if f == 1:
        return np.zeros((0, 6))
    if not 0 < cutoff_ratio <= 1:
        raise ValueError(f"cutoff_ratio must be in (0, 1], got {cutoff_ratio!r}")
    return signal.butter(int(order), cutoff_ratio * 0.5 * float(target_hz), btype="low",
                         fs=float(rate_hz), output="sos")


def _filter_block(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Causal filter of (T, d) ``x`` along time, state starting at the steady state of x[0]."""
    if sos.shape[0] == 0:
        return x.astype(float, copy=True)
    zi = signal.sosfilt_zi(sos)[:, :, None] * x[0][None, None, :]  # (n_sections, 2, d)
    y, _ = signal.sosfilt(sos, x, axis=0, zi=zi)
    return y


def _zero_phase_block(sos: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Forward-backward filter of (T, d) ``x`` along time (no delay), edges padded by odd reflection."""
    if sos.shape[0] == 0:
        return x.astype(float, copy=True)
    pad = min(3 * (2 * sos.shape[0] + 1), x.shape[0] - 1)
    return signal.sosfiltfilt(sos, x, axis=0, padlen=pad)


def causal_downsample(demos: Demonstrations, target_hz: float = 10.0, *, order: int = 4,
                      cutoff_ratio: float = 0.8, zero_phase_act: bool = False) -> Demonstrations:
    """Causally low-pass every trial's ``obs``, ``act`` and ``voluntary``, keep every f-th sample.

    ``t``, ``mode`` are taken at the kept samples (indices 0, f, 2f, …). The result's
    ``rate_hz`` is ``target_hz``. With ``zero_phase_act`` the actions are filtered
    forward and backward instead (``sosfiltfilt``, no delay): a model's *inputs* must be
    causal, but its *targets* are known offline, and a causally filtered target would
    teach the model to predict the knife as it was a filter delay ago (≈ 0.1 s at the
    defaults, about 1 cm of tip error at eating speeds). Raises ValueError for a
    non-integer factor or a trial that would keep fewer than 2 samples (naming the trial).
    """
    f = decimation_factor(demos.rate_hz, target_hz)
    sos = lowpass_sos(demos.rate_hz, target_hz, order, cutoff_ratio)
    out: list[Trial] = []
    for tr in demos.trials:
        keep = slice(0, None, f)
        n_keep = -(-len(tr) // f)
        if n_keep < 2:
            raise ValueError(f"trial {tr.trial_id} has {len(tr)} samples at {demos.rate_hz:g} Hz and would "
                             f"keep only {n_keep} at {target_hz:g} Hz; need at least 2")
        act = _zero_phase_block(sos, tr.act) if zero_phase_act else _filter_block(sos, tr.act)
        out.append(Trial(obs=_filter_block(sos, tr.obs)[keep], act=act[keep],
                         t=tr.t[keep].copy(), trial_id=tr.trial_id, subject=tr.subject,
                         mode=None if tr.mode is None else tr.mode[keep].copy(),
                         voluntary=None if tr.voluntary is None else _filter_block(sos, tr.voluntary)[keep]))
    res = demos.with_trials(out)
    res.rate_hz = float(target_hz)
    return res


class StreamingDecimator:
    """:func:`causal_downsample` one sample at a time, for the control loop.

    ``push(x)`` filters one (d,) sample and returns the filtered sample when it is a
    kept one (the 1st, (f+1)-th, … since ``reset``), else None. The first ``push``
    after ``reset`` initialises the filter state at the steady state of that sample.
    Direct-form II transposed second-order sections, as scipy's ``sosfilt``.
    """

    def __init__(self, rate_hz: float, target_hz: float, n_channels: int, *, order: int = 4,
                 cutoff_ratio: float = 0.8) -> None:
        self.factor = decimation_factor(rate_hz, target_hz)
        self.sos = lowpass_sos(rate_hz, target_hz, order, cutoff_ratio)
        self.n_channels = int(n_channels)
        self._zi_unit = signal.sosfilt_zi(self.sos) if self.sos.shape[0] else np.zeros((0, 2))
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next ``push`` is the first sample of a trial."""
        self.n_pushed = 0
        self._z = np.zeros((self.sos.shape[0], 2, self.n_channels))
        self.last_output: np.ndarray | None = None

    def push(self, x: np.ndarray) -> np.ndarray | None:
        """Absorb one (d,) sample; return the filtered sample on a kept index, else None."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.n_channels,):
            raise ValueError(f"sample has shape {x.shape}, expected ({self.n_channels},)")
        if self.n_pushed == 0:
            self._z = self._zi_unit[:, :, None] * x[None, None, :]
        y = x
        z = self._z
        for s, (b0, b1, b2, _a0, a1, a2) in enumerate(self.sos):
            out = b0 * y + z[s, 0]
            z[s, 0] = b1 * y - a1 * out + z[s, 1]
            z[s, 1] = b2 * y - a2 * out
            y = out
        kept = self.n_pushed % self.factor == 0
        self.n_pushed += 1
        if kept:
            self.last_output = np.array(y, dtype=float)
            return self.last_output
        return None
