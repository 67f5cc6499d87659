"""The line ratio: a strategy's tracking RMS over the straight voluntary–reactive line at its effort.

The two parties draw a line in the (effort, tracking RMS) plane, from ``reactive``
R = (e_r, ε_r) to ``voluntary`` V = (e_v, ε_v). Mixing the two (a constant α) lies near it;
a shared strategy is worth having where it lies *below* it. At a strategy's effort e_s

    t = clip((e_s − e_r) / (e_v − e_r), 0, 1),    ε_line(e_s) = ε_r + t · (ε_v − ε_r),
    line_ratio = ε_s / ε_line(e_s)

so ``line_ratio`` < 1 is better than mixing the parties at the same effort, and the two
parties themselves are at 1. **Outside the segment's effort range** it is never extrapolated
(which could reach zero or negative RMS): a strategy with *less* effort than both parties is
compared with the RMS of the party of least effort (the line held at that end); one with *more*
effort than both with the better party's RMS, min(ε_r, ε_v) (either party needs no more effort
than it does). Usually ``reactive`` is the end of least effort and ``voluntary`` the better one,
so this is the line held at its ends; where one party is better on both (e.g. the robot so
poor that the wearer corrects it harder than leading alone) a run beyond both efforts is still
compared with the better party, not with the worse end. Where the parties' efforts are equal
(|e_v − e_r| ≤ 1e-12) the line is min(ε_r, ε_v). None where a figure is missing or not finite,
or ε_line ≤ 0.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

__all__ = ["add_line_ratios", "line_ratio", "line_rms"]



def _finite(*xs: Any) -> bool:
    return all(x is not None and math.isfinite(float(x)) for x in xs)


def line_rms(effort: float, voluntary: tuple[float, float], reactive: tuple[float, float]) -> float | None:
    """ε_line(effort) of the line from ``reactive`` = (e_r, ε_r) to ``voluntary`` = (e_v, ε_v) (module docstring)."""
    (e_v, r_v), (e_r, r_r) = voluntary, reactive
    if not _finite(effort, e_v, r_v, e_r, r_r):
        return None
    if abs(e_v - e_r) <= 1e-12:
        return float(min(r_v, r_r))
    if effort > max(e_v, e_r):
        return float(min(r_v, r_r))
    t = min(max((effort - e_r) / (e_v - e_r), 0.0), 1.0)
    return float(r_r + t * (r_v - r_r))


def line_ratio(rms: float | None, effort: float | None, voluntary: tuple[float, float],
               reactive: tuple[float, float]) -> float | None:
    """ε_s / ε_line(e_s) (module docstring); None where it is not defined."""
    if not _finite(rms, effort):
        return None
    line = line_rms(float(effort), voluntary, reactive)  # type: ignore[arg-type]
    return float(rms) / line if line is not None and line > 0 else None  # type: ignore[arg-type]


def _point(m: Mapping[str, Any] | None) -> tuple[float, float] | None:
    if not m or not _finite(m.get("voluntary_effort"), m.get("tracking_rmse_m")):
        return None
    return float(m["voluntary_effort"]), float(m["tracking_rmse_m"])


def add_line_ratios(metrics: dict[str, dict[str, Any]], voluntary: str = "voluntary",
                    reactive: str = "reactive") -> dict[str, dict[str, Any]]:
    """``metrics`` (run name → metrics with ``tracking_rmse_m`` and ``voluntary_effort``) with
    ``line_ratio`` set in every run's metrics, in place and returned; None for every run when
    either party is missing."""
    v, r = _point(metrics.get(voluntary)), _point(metrics.get(reactive))
    for m in metrics.values():
        m["line_ratio"] = (line_ratio(m.get("tracking_rmse_m"), m.get("voluntary_effort"), v, r)
                           if v is not None and r is not None else None)
    return metrics
