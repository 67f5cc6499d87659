"""Where the time of ``mpcshare run``'s ticks goes, and why a long period was long.

:class:`TickProfile` records per tick, into arrays allocated once (nothing allocated on the tick): the command's
stamp (``sent``, monotonic [s]), the stamp of the arm's joint state it used (ROS time [s]), the wall clock at
the tick's start, its phases' durations (``poll``: the DDS takes, ``step``: the controller, ``publish``: the
command and the status, ``live``: the live view), and, from :data:`gc.callbacks`, every garbage collection
(generation, start, duration). Beyond ``capacity`` ticks or collections nothing more is recorded (``dropped``).

A **long period**: command stamps more than T + ``long_after_s`` apart (a skipped tick, ``late``, makes one).
Its cause (:meth:`TickProfile.report`) is the largest excess over [previous command, this command]:

- ``gc genN``: the collections inside it (N the oldest generation collected);
- ``poll``, ``step``, ``publish``, ``live``: the phase's time above its median (publish and live: the previous
  tick's, which follow its command);
- ``input late``: the arm's joint state stamped later than one period after the previous one, or none new;
- ``woke late``: from the joint state's stamp to the tick's start, above its median (the machine busy);
- ``unexplained``: none of these reaches 0.5 ms.
"""

from __future__ import annotations

import gc
import time
from typing import Any

import numpy as np

__all__ = ["PHASES", "TickProfile"]

#: The tick's timed phases, in order.
PHASES: tuple[str, ...] = ("poll", "step", "publish", "live")
_EXPLAINS_S = 0.5e-3  # an excess below this explains nothing


class TickProfile:
    """Per-tick times and garbage collections of a run (module docstring); ``period_s``: T [s]."""

    def __init__(self, period_s: float, capacity: int = 200_000, long_after_s: float = 2e-3) -> None:
        self.period_s, self.capacity, self.long_after_s = float(period_s), int(capacity), float(long_after_s)
        self.sent = np.full(capacity, np.nan)
        self.wall_start = np.full(capacity, np.nan)
        self.arm_stamp = np.full(capacity, np.nan)
        self.phases = np.zeros((capacity, len(PHASES)))
        self.late = np.zeros(capacity, dtype=bool)
        self.gc = np.zeros((capacity, 3))  # generation, start [s, monotonic], duration [s]
        self.n = self.n_gc = self.dropped = 0
        self._gc_start = 0.0
        self._installed = False

    # ------------------------------------------------------------------ recording
    def install(self) -> None:
        """Start recording garbage collections (idempotent); :meth:`uninstall` ends it."""
        if not self._installed:
            gc.callbacks.append(self._on_gc)
            self._installed = True

    def uninstall(self) -> None:
        if self._installed:
            gc.callbacks.remove(self._on_gc)
            self._installed = False

    def _on_gc(self, phase: str, info: dict[str, Any]) -> None:
        now = time.perf_counter()
        if phase == "start":
            self._gc_start = now
        elif self.n_gc < self.capacity:
            self.gc[self.n_gc] = (info.get("generation", -1), self._gc_start, now - self._gc_start)
            self.n_gc += 1
        else:
            self.dropped += 1

    def tick(self, wall_start: float, arm_stamp: float, sent: float, durations: tuple[float, ...],
             late: bool = False) -> None:
        """One tick: the wall clock at its start [s], its joint state's stamp [s] (NaN: none), when its
        command was stamped (``time.perf_counter()`` [s]; NaN: no command), the phases' durations [s]."""
        i = self.n
        if i >= self.capacity:
            self.dropped += 1
            return
        self.wall_start[i], self.arm_stamp[i], self.sent[i], self.late[i] = wall_start, arm_stamp, sent, late
        self.phases[i, :len(durations)] = durations
        self.n = i + 1

    def after(self, phase: str, duration_s: float) -> None:
        """Add ``duration_s`` [s] to the last tick's ``phase`` (the phases that follow its command)."""
        if self.n:
            self.phases[self.n - 1, PHASES.index(phase)] += duration_s

    # ------------------------------------------------------------------ the report
    def report(self) -> dict[str, Any]:
        """Figures of the recorded ticks: periods between commands (median, p99, max [ms]), jitter p99 [ms],
        the phases' median and p99 [ms], the collections per generation (count, max [ms]), and the long
        periods by cause (``causes``: cause → count; ``late_ticks``: the skipped ticks by cause; ``worst``:
        the ten longest periods with their excesses [ms])."""
        n = self.n
        sent = self.sent[:n]
        have = np.flatnonzero(np.isfinite(sent))
        out: dict[str, Any] = {"ticks": n, "dropped": self.dropped}
        ph = self.phases[:n]
        out["phases_ms"] = {p: {"median": float(np.median(ph[:, j]) * 1e3) if n else None,
                                "p99": float(np.percentile(ph[:, j], 99) * 1e3) if n else None}
                            for j, p in enumerate(PHASES)}
        g = self.gc[:self.n_gc]
        out["gc"] = {f"gen{k}": {"count": int((g[:, 0] == k).sum()),
                                 "max_ms": float(g[g[:, 0] == k, 2].max() * 1e3) if (g[:, 0] == k).any() else 0.0}
                     for k in range(3)}
        if have.size < 2:
            return {**out, "causes": {}, "late_ticks": {}, "worst": []}
        period = np.diff(sent[have])
        out["period_ms"] = {"median": float(np.median(period) * 1e3), "p99": float(np.percentile(period, 99) * 1e3),
                            "max": float(period.max() * 1e3)}
        out["jitter_p99_ms"] = float(np.percentile(np.abs(period - self.period_s), 99) * 1e3)
        medians = np.median(ph[have], axis=0)
        wake = self.wall_start[have] - self.arm_stamp[have]
        wake_median = float(np.nanmedian(wake)) if np.isfinite(wake).any() else 0.0
        causes: dict[str, int] = {}
        late: dict[str, int] = {}
        worst: list[tuple[float, dict[str, Any]]] = []
        for j in np.flatnonzero(period > self.period_s + self.long_after_s):
            a, b = have[j], have[j + 1]
            parts = self._excesses(a, b, medians, wake[j + 1] - wake_median)
            cause = max(parts, key=parts.__getitem__) if parts and max(parts.values()) >= _EXPLAINS_S \
                else "unexplained"
            causes[cause] = causes.get(cause, 0) + 1
            if self.late[a + 1:b + 1].any():
                late[cause] = late.get(cause, 0) + int(self.late[a + 1:b + 1].sum())
            worst.append((float(period[j]), {"tick": int(b), "period_ms": float(period[j] * 1e3), "cause": cause,
                                             **{k: round(v * 1e3, 3) for k, v in parts.items()}}))
        worst.sort(key=lambda w: -w[0])
        out.update(causes=causes, late_ticks=late, worst=[w for _, w in worst[:10]])
        return out

    def _excesses(self, a: int, b: int, medians: np.ndarray, wake_excess: float) -> dict[str, float]:
        """What each suspect adds [s] to the period from tick a's command to tick b's."""
        ph = self.phases
        parts = {"poll": float(ph[b, 0] - medians[0]), "step": float(ph[b, 1] - medians[1]),
                 "publish": float(ph[a, 2] - medians[2]), "live": float(ph[a, 3] - medians[3])}
        g = self.gc[:self.n_gc]
        inside = g[(g[:, 1] >= self.sent[a]) & (g[:, 1] < self.sent[b])]
        if inside.size:
            parts[f"gc gen{int(inside[:, 0].max())}"] = float(inside[:, 2].sum())
        gap = self.arm_stamp[b] - self.arm_stamp[a]
        if np.isfinite(gap) and gap <= 0:  # no new joint state: the tick waited out its window
            parts["input late"] = float(self.sent[b] - self.sent[a] - (b - a) * self.period_s)
        elif np.isfinite(gap):
            parts["input late"] = float(gap - (b - a) * self.period_s)
            if np.isfinite(wake_excess):
                parts["woke late"] = float(wake_excess)
        return parts
