"""Irregular, per-topic samples onto one regular grid: common span, gaps, unwrapping, interpolation.

Each topic of a recording has its own sample times (header stamps with jitter,
different rates, late starts). :func:`regrid` puts every channel on one grid of
``rate_hz`` over the span where every topic has data, by linear interpolation
(``numpy.interp``); angles are unwrapped first, so an angle crossing ±π is
interpolated the short way round (it comes out continuous, not wrapped back).

A *gap* is an interval longer than ``max_gap`` between two consecutive samples of
a topic. With ``on_gap="error"`` the first gap inside the span raises
:class:`~learning.data.DataFormatError` naming the topic and the time; with
``"split"`` the grid points inside gaps are dropped and each remaining run of
consecutive grid points becomes one segment (a trial of its own).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .checks import DataFormatError

__all__ = ["ON_GAP", "Segment", "TopicSeries", "regrid"]

#: What a gap longer than ``max_gap`` does.
ON_GAP: tuple[str, ...] = ("error", "split")


@dataclass
class TopicSeries:
    """The samples of one topic.

    Attributes:
        topic: the topic name (for messages).
        t: (n,) sample times [s] from the recording's reference time, sorted, distinct.
        values: (n, k) one column per channel read from the topic.
        angle: (k,) bool, True for the columns that are angles (unwrapped before interpolation).
    """

    topic: str
    t: np.ndarray
    values: np.ndarray
    angle: np.ndarray


@dataclass
class Segment:
    """A stretch of the grid without gaps: grid times [s] and the interpolated columns per topic."""

    t: np.ndarray
    columns: dict[str, np.ndarray]


def _span_error(series: list[TopicSeries], path: str | None) -> DataFormatError:
    latest = max(series, key=lambda s: s.t[0])
    earliest_end = min(series, key=lambda s: s.t[-1])
    return DataFormatError(
        f"empty overlap: no time at which every mapped topic has data ({earliest_end.topic} ends at "
        f"t = {earliest_end.t[-1]:.3f} s, {latest.topic} starts at t = {latest.t[0]:.3f} s)", path=path)


def regrid(series: list[TopicSeries], rate_hz: float, *, max_gap: float = 0.1, on_gap: str = "error",
           path: str | None = None, min_samples: int = 2, time_origin: str = "") -> list[Segment]:
    """Interpolate every topic onto one grid of ``rate_hz`` over the common span (module docstring).

    The grid is ``t_0 + k / rate_hz`` with ``t_0`` the latest first sample over the
    topics, up to the earliest last sample. Segments with fewer than ``min_samples``
    grid points (between two gaps) are dropped. ``path`` names the recording in
    errors, ``time_origin`` says in them what t = 0 is. Raises :class:`DataFormatError`
    for an empty overlap, a gap (with ``on_gap="error"``), or when no segment is left.
    """
    if on_gap not in ON_GAP:
        raise ValueError(f"on_gap must be one of {ON_GAP}, got {on_gap!r}")
    if not (rate_hz > 0 and np.isfinite(rate_hz)):
        raise ValueError(f"rate_hz must be finite and > 0, got {rate_hz!r}")
    if not (max_gap > 0):
        raise ValueError(f"max_gap must be > 0, got {max_gap!r}")
    for s in series:
        if len(s.t) == 0:
            raise DataFormatError(f"topic {s.topic} has no messages", path=path)
    start = max(float(s.t[0]) for s in series)
    end = min(float(s.t[-1]) for s in series)
    if not end > start:
        raise _span_error(series, path)
    n = int(np.floor((end - start) * rate_hz + 1e-9)) + 1
    grid = start + np.arange(n) / rate_hz
    keep = np.ones(n, dtype=bool)
    gaps: list[tuple[float, str, float, float]] = []
    for s in series:
        dt = np.diff(s.t)
        for i in np.flatnonzero(dt > max_gap):
            a, b = float(s.t[i]), float(s.t[i + 1])
            if b > start and a < end:
                gaps.append((a, s.topic, a, b))
    if gaps:
        if on_gap == "error":
            _, topic, a, b = min(gaps)
            where = f" ({time_origin})" if time_origin else ""
            raise DataFormatError(
                f"gap in topic {topic}: no message for {b - a:.3f} s after t = {a:.3f} s{where}, longer than "
                f"max-gap {max_gap:g} s; use --on-gap split to cut the trial there", path=path)
        for _, _, a, b in gaps:
            keep[(grid > a) & (grid < b)] = False

    columns_full: dict[str, np.ndarray] = {}
    for s in series:
        v = np.array(s.values, dtype=float, copy=True)
        if v.ndim != 2 or v.shape[0] != len(s.t):
            raise ValueError(f"topic {s.topic}: values must be (n, k) with n = {len(s.t)}, got {v.shape}")
        for j in np.flatnonzero(np.asarray(s.angle, dtype=bool)):
            v[:, j] = _unwrap_finite(v[:, j])
        columns_full[s.topic] = np.stack([np.interp(grid, s.t, v[:, j]) for j in range(v.shape[1])], axis=1) \
            if v.shape[1] else np.zeros((n, 0))

    segments: list[Segment] = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], keep.astype(np.int8), [0]])))
    for a, b in zip(edges[0::2], edges[1::2]):
        if b - a >= min_samples:
            segments.append(Segment(grid[a:b].copy(), {k: c[a:b].copy() for k, c in columns_full.items()}))
    if not segments:
        raise DataFormatError(f"no stretch of at least {min_samples} samples at {rate_hz:g} Hz between gaps "
                              f"longer than {max_gap:g} s", path=path)
    return segments


def _unwrap_finite(x: np.ndarray) -> np.ndarray:
    """``np.unwrap`` over the finite values (NaN stays NaN, and is reported by the data set's validation)."""
    ok = np.isfinite(x)
    if ok.all():
        return np.unwrap(x)
    out = x.copy()
    out[ok] = np.unwrap(x[ok])
    return out
