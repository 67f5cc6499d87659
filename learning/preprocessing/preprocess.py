"""Preprocessing of demonstrations as in Song & Asada: downsample, standardise, causal window.

The analysis calls :func:`preprocess`, which chains

1. :func:`downsample` — anti-aliased resampling of every trial (default 100 → 10 Hz);
2. :class:`Standardizer` — z-scoring of ``obs`` and of ``act`` (two standardizers,
   fitted on the data passed, i.e. the training trials only);
3. :func:`causal_windows` — per-sample causal windows ``[o_t, o_{t−1}, …, o_{t−L+1}]``
   that never cross a trial boundary.

:func:`learning.data.split_by_trial` and :func:`learning.data.split_by_subject`
make train/test splits.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Literal

import numpy as np
from scipy import signal

from learning.data import Demonstrations, Trial

__all__ = [
    "Preprocessor",
    "Standardizer",
    "WindowedData",
    "causal_windows",
    "downsample",
    "preprocess",
    "window_lags",
]


# ---------------------------------------------------------------- downsample


def _rational_factor(rate_hz: float, target_hz: float) -> tuple[int, int]:
    """``(up, down)`` with ``up / down == target_hz / rate_hz`` (relative error ≤ 1e-6)."""
    ratio = target_hz / rate_hz
    frac = Fraction(ratio).limit_denominator(1000)
    if frac.numerator == 0 or abs(float(frac) / ratio - 1.0) > 1e-6:
        raise ValueError(f"cannot resample {rate_hz} Hz → {target_hz} Hz by a rational factor "
                         f"with denominator ≤ 1000")
    return frac.numerator, frac.denominator


def downsample(demos: Demonstrations, target_hz: float = 10.0) -> Demonstrations:
    """Anti-aliased downsampling of every trial to ``target_hz`` [Hz].

    Each trial's ``obs``, ``act`` and ``voluntary`` go through
    :func:`scipy.signal.resample_poly` (zero-phase Kaiser-windowed FIR, so no
    delay; edges padded by a fitted line) with the integer or rational factor
    ``up/down = target_hz / rate_hz``. Output sample ``k`` lies at input index
    ``k·down/up``: ``t`` is interpolated there and ``mode`` is the label of the
    nearest input sample. ``subject`` and ``trial_id`` are carried. A set already
    at ``target_hz`` is returned as a copy.

    Raises:
        ValueError: ``target_hz`` ≤ 0 or > ``rate_hz``, or a trial would keep fewer
            than 2 samples (the message names the trial).
    """
    rate = float(demos.rate_hz)
    target = float(target_hz)
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"target_hz must be finite and > 0, got {target_hz!r}")
    if target > rate * (1 + 1e-9):
        raise ValueError(f"target_hz = {target} Hz is above the data's rate {rate} Hz; "
                         f"downsample cannot upsample")
    if abs(target / rate - 1.0) <= 1e-9:
        return demos.with_trials([_copy_trial(tr) for tr in demos.trials])
    up, down = _rational_factor(rate, target)
    out: list[Trial] = []
    for tr in demos.trials:
        T = len(tr)
        n_out = -(-T * up // down)  # ceil(T·up/down), resample_poly's output length
        if n_out < 2:
            raise ValueError(f"trial {tr.trial_id} has {T} samples at {rate} Hz and would keep only "
                             f"{n_out} at {target} Hz; need at least 2")
        idx = np.arange(n_out) * (down / up)  # input index of each kept instant
        last = T - 1
        t_new = np.where(idx <= last, np.interp(np.minimum(idx, last), np.arange(T), tr.t),
                         tr.t[-1] + (idx - last) / rate)
        near = np.minimum(np.rint(idx).astype(int), last)

        def rs(x: np.ndarray, n_out: int = n_out) -> np.ndarray:
            return signal.resample_poly(x, up, down, axis=0, padtype="line")[:n_out]

        out.append(Trial(obs=rs(tr.obs), act=rs(tr.act), t=t_new, trial_id=tr.trial_id,
                         subject=tr.subject, mode=None if tr.mode is None else tr.mode[near].copy(),
                         voluntary=None if tr.voluntary is None else rs(tr.voluntary)))
    res = demos.with_trials(out)
    res.rate_hz = target
    return res


def _copy_trial(tr: Trial) -> Trial:
    return Trial(obs=tr.obs.copy(), act=tr.act.copy(), t=tr.t.copy(), trial_id=tr.trial_id,
                 subject=tr.subject, mode=None if tr.mode is None else tr.mode.copy(),
                 voluntary=None if tr.voluntary is None else tr.voluntary.copy())


# -------------------------------------------------------------- standardise

Field = Literal["obs", "act", "voluntary"]


class Standardizer:
    """Centre and scale channels (scikit-learn style ``fit`` / ``transform``).

    Args:
        scope: ``"channel"`` — per-channel z-score (mean 0, standard deviation 1);
            ``"sensor"`` — per-channel centring, then one scale per sensor (group of
            channels) so the sensor's centred vector has unit RMS magnitude,
            ``mean_t ‖x_t,g‖² = 1`` (the paper's scaling of position, orientation,
            force).
        sensors: for ``"sensor"``: a group size (default 3: xyz, rpy, force xyz
            of consecutive channels; a shorter last group if the count is not a
            multiple) or explicit groups, a partition of the channel indices.
        field: which array of a :class:`Demonstrations` the standardizer acts on
            (``"obs"``, ``"act"`` or ``"voluntary"``); arrays are taken as they are.

    Fitted attributes: ``mean_`` (d,), ``scale_`` (d,) (x' = (x − mean_) / scale_),
    ``groups_`` (list of index arrays), ``n_features_in_``. A constant channel or
    sensor gets scale 1.
    """

    def __init__(self, scope: Literal["channel", "sensor"] = "channel",
                 sensors: int | Sequence[Sequence[int]] | None = None, field: Field = "obs") -> None:
        if scope not in ("channel", "sensor"):
            raise ValueError(f"scope must be 'channel' or 'sensor', got {scope!r}")
        if field not in ("obs", "act", "voluntary"):
            raise ValueError(f"field must be 'obs', 'act' or 'voluntary', got {field!r}")
        self.scope = scope
        self.sensors = sensors
        self.field = field

    def _data(self, x: Demonstrations | np.ndarray) -> np.ndarray:
        if isinstance(x, Demonstrations):
            arrays = [getattr(tr, self.field) for tr in x.trials]
            if not arrays or any(a is None for a in arrays):
                raise ValueError(f"the demonstrations have no '{self.field}' in every trial")
            return np.concatenate(arrays)
        a = np.asarray(x, dtype=float)
        if a.ndim != 2:
            raise ValueError(f"expected a 2-D array (N, d), got shape {a.shape}")
        return a

    def _groups(self, d: int) -> list[np.ndarray]:
        if self.scope == "channel":
            return [np.array([j]) for j in range(d)]
        if self.sensors is None or isinstance(self.sensors, (int, np.integer)):
            size = 3 if self.sensors is None else int(self.sensors)
            if size < 1:
                raise ValueError(f"sensor group size must be ≥ 1, got {size}")
            return [np.arange(s, min(s + size, d)) for s in range(0, d, size)]
        groups = [np.asarray(g, dtype=int).reshape(-1) for g in self.sensors]
        flat = np.concatenate(groups) if groups else np.array([], dtype=int)
        if sorted(flat.tolist()) != list(range(d)):
            raise ValueError(f"sensors must partition the channel indices 0..{d - 1}, got "
                             f"{[g.tolist() for g in groups]}")
        return groups

    def fit(self, x: Demonstrations | np.ndarray) -> Standardizer:
        """Fit mean and scale on ``x`` (the training trials only), (N, d) or a set."""
        a = self._data(x)
        if a.shape[0] == 0:
            raise ValueError("cannot fit a standardizer on 0 samples")
        if not np.isfinite(a).all():
            raise ValueError("cannot fit a standardizer on non-finite values")
        d = a.shape[1]
        mean = a.mean(axis=0)
        centred = a - mean
        scale = np.ones(d)
        groups = self._groups(d)
        for g in groups:
            rms = float(np.sqrt(np.mean(np.sum(centred[:, g] ** 2, axis=1))))
            tiny = 1e-12 * (1.0 + float(np.linalg.norm(mean[g])))
            scale[g] = rms if rms > tiny else 1.0
        self.mean_ = mean
        self.scale_ = scale
        self.groups_ = groups
        self.n_features_in_ = d
        return self

    def _check(self, a: np.ndarray) -> None:
        if not hasattr(self, "mean_"):
            raise RuntimeError("Standardizer is not fitted; call fit() first")
        if a.shape[-1] != self.n_features_in_:
            raise ValueError(f"expected {self.n_features_in_} channels, got {a.shape[-1]}")

    def _apply(self, x: Demonstrations | np.ndarray, inverse: bool) -> Demonstrations | np.ndarray:
        def f(a: np.ndarray) -> np.ndarray:
            a = np.asarray(a, dtype=float)
            self._check(a)
            return a * self.scale_ + self.mean_ if inverse else (a - self.mean_) / self.scale_

        if isinstance(x, Demonstrations):
            trials = []
            for tr in x.trials:
                new = _copy_trial(tr)
                setattr(new, self.field, f(getattr(tr, self.field)))
                trials.append(new)
            return x.with_trials(trials)
        return f(x)

    def transform(self, x: Demonstrations | np.ndarray) -> Demonstrations | np.ndarray:
        """``(x − mean_) / scale_`` on an array (…, d) or on ``field`` of every trial (new set)."""
        return self._apply(x, inverse=False)

    def inverse_transform(self, x: Demonstrations | np.ndarray) -> Demonstrations | np.ndarray:
        """``x · scale_ + mean_``: back to physical units."""
        return self._apply(x, inverse=True)

    def fit_transform(self, x: Demonstrations | np.ndarray) -> Demonstrations | np.ndarray:
        return self.fit(x).transform(x)

    def __repr__(self) -> str:
        return f"Standardizer(scope={self.scope!r}, sensors={self.sensors!r}, field={self.field!r})"


# ------------------------------------------------------------------ windows


@dataclass
class WindowedData:
    """Causal windows stacked over trials.

    Attributes:
        X: (N, d_o·L) rows ``[o_t, o_{t−1}, …, o_{t−L+1}]`` flattened lag-major:
            ``X[:, l·d_o:(l+1)·d_o] = o_{t−l}``.
        Y: (N, d_u) action at ``t``.
        trial: (N,) trial id; subject: (N,) subject id.
        mode: (N,) label at ``t`` or None; voluntary: (N, d_v) at ``t`` or None.
        t: (N,) time [s] of ``t``.
        source_index: (N,) row of ``t`` in ``demos.stacked()`` of the windowed set.
        lags: L; obs_dim: d_o; rate_hz: sample rate [Hz]; window_s: requested window [s].
    """

    X: np.ndarray
    Y: np.ndarray
    trial: np.ndarray
    subject: np.ndarray
    mode: np.ndarray | None
    voluntary: np.ndarray | None
    t: np.ndarray
    source_index: np.ndarray
    lags: int
    obs_dim: int
    rate_hz: float = float("nan")
    window_s: float = float("nan")

    def __len__(self) -> int:
        return int(self.X.shape[0])

    def lag(self, l: int) -> np.ndarray:
        """(N, d_o) block of ``o_{t−l}``."""
        if not 0 <= l < self.lags:
            raise IndexError(f"lag {l} outside 0..{self.lags - 1}")
        return self.X[:, l * self.obs_dim:(l + 1) * self.obs_dim]


def window_lags(window_s: float, rate_hz: float) -> int:
    """Number of samples L = max(1, round(window_s · rate_hz)): the window holds the
    current sample and L−1 past ones, L sample periods = ``window_s`` [s]."""
    if not (math.isfinite(window_s) and window_s >= 0):
        raise ValueError(f"window_s must be finite and ≥ 0, got {window_s!r}")
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ValueError(f"rate_hz must be finite and > 0, got {rate_hz!r}")
    return max(1, int(np.rint(window_s * rate_hz)))


def causal_windows(demos: Demonstrations, window_s: float, *, rate_hz: float | None = None,
                   rms: bool = False) -> WindowedData:
    """Causal sliding windows of ``obs`` that never cross a trial boundary.

    ``L = window_lags(window_s, rate)`` with ``rate = rate_hz or demos.rate_hz``.
    With ``rms=True`` the window is divided by √L, so that ‖x_i − x_j‖ is the RMS
    over lags of the per-sample distance ‖o_{i−l} − o_{j−l}‖: distances, and so
    Lipschitz quotients, keep the scale of one sample whatever the window length
    (without it a longer window inflates every distance by √L and deflates every
    quotient, which would bias a comparison of window lengths).
    The first L−1 samples of each trial have no full window and are dropped; a
    trial with fewer than L samples is skipped with a :class:`UserWarning`.

    Raises:
        ValueError: no trial is long enough.
    """
    rate = float(demos.rate_hz if rate_hz is None else rate_hz)
    L = window_lags(float(window_s), rate)
    d_o = demos.obs_dim
    Xs, Ys, trial, subject, mode, vol, tt, src = [], [], [], [], [], [], [], []
    offset = 0
    skipped: list[int] = []
    for tr in demos.trials:
        T = len(tr)
        if T < L:
            skipped.append(tr.trial_id)
            offset += T
            continue
        n = T - L + 1
        win = np.lib.stride_tricks.sliding_window_view(tr.obs, L, axis=0)  # (n, d_o, L): obs[k + j]
        Xs.append(np.ascontiguousarray(win[:, :, ::-1].transpose(0, 2, 1)).reshape(n, L * d_o))
        keep = slice(L - 1, T)
        Ys.append(tr.act[keep])
        trial.append(np.full(n, tr.trial_id, dtype=int))
        subject.append(np.full(n, tr.subject, dtype=int))
        if tr.mode is not None:
            mode.append(tr.mode[keep])
        if tr.voluntary is not None:
            vol.append(tr.voluntary[keep])
        tt.append(tr.t[keep])
        src.append(offset + np.arange(L - 1, T))
        offset += T
    if skipped:
        msg = (f"{len(skipped)} trial(s) shorter than the window of {L} samples skipped: "
               f"{skipped[:10]}{' …' if len(skipped) > 10 else ''}")
        if not Xs:
            raise ValueError(f"no trial is long enough for a {window_s} s window ({L} samples at "
                             f"{rate} Hz); {msg}")
        warnings.warn(msg, UserWarning, stacklevel=2)
    X = np.concatenate(Xs)
    if rms:
        X /= math.sqrt(L)
    return WindowedData(
        X=X, Y=np.concatenate(Ys), trial=np.concatenate(trial),
        subject=np.concatenate(subject),
        mode=np.concatenate(mode) if mode and len(mode) == len(Xs) else None,
        voluntary=np.concatenate(vol) if vol and len(vol) == len(Xs) else None,
        t=np.concatenate(tt), source_index=np.concatenate(src), lags=L, obs_dim=d_o,
        rate_hz=rate, window_s=float(window_s))


# --------------------------------------------------------------- pipeline


@dataclass
class Preprocessor:
    """The fitted preprocessing: two standardizers and the resampling/window settings.

    Attributes:
        obs: fitted :class:`Standardizer` for ``obs``; act: fitted one for ``act``.
        target_hz: rate after downsampling [Hz]; window_s: causal window [s].
    """

    obs: Standardizer
    act: Standardizer
    target_hz: float = 10.0
    window_s: float = 1.0

    def standardize(self, demos: Demonstrations) -> Demonstrations:
        """Standardise ``obs`` and ``act`` of an already downsampled set."""
        return self.act.transform(self.obs.transform(demos))

    def transform(self, demos: Demonstrations) -> WindowedData:
        """Downsample, standardise with the fitted scalers and window (for test data)."""
        return causal_windows(self.standardize(downsample(demos, self.target_hz)), self.window_s)


def preprocess(demos: Demonstrations, *, target_hz: float = 10.0, window_s: float = 1.0,
               scope: Literal["channel", "sensor"] = "channel", rms: bool = False,
               standardizer: Preprocessor | None = None) -> tuple[WindowedData, Preprocessor]:
    """Downsample → standardise ``obs`` and ``act`` → causal windows.

    With ``standardizer=None`` two :class:`Standardizer` (``scope``) are fitted on
    the downsampled ``demos`` (pass training trials only); a fitted
    :class:`Preprocessor` passed in is reused as it is (its scalers; ``target_hz``
    and ``window_s`` still come from the arguments). The voluntary channel is
    downsampled but not standardised. ``rms`` is passed to :func:`causal_windows`.

    Returns:
        ``(windows, preprocessor)``; ``preprocessor.transform(test_demos)`` applies
        the same steps to other data.
    """
    low = downsample(demos, target_hz)
    if standardizer is None:
        pre = Preprocessor(obs=Standardizer(scope, field="obs").fit(low),
                           act=Standardizer(scope, field="act").fit(low),
                           target_hz=float(target_hz), window_s=float(window_s))
    else:
        if not isinstance(standardizer, Preprocessor):
            raise TypeError(f"standardizer must be a fitted Preprocessor, got {type(standardizer).__name__}")
        pre = standardizer
    return causal_windows(pre.standardize(low), window_s, rms=rms), pre
