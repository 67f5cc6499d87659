"""Per-input deadlines of ``mpcshare run``: stale inputs and the protective stop.

An input's age at time ``now`` is ``now − (its last message's arrival)``, or ``now − start`` before its
first message (times on one monotonic clock [s]; header stamps are not used: the sender's clock may
differ). Age > ``deadline_s``: the input is **stale** (its values are withheld from the controller,
which takes its fault path). Age > ``stop_after_s`` for a required input: **protective stop**, latched
until :meth:`Watchdog.resume`. An optional input that never sent is neither stale nor a stop.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

__all__ = ["Deadline", "Watchdog", "WatchState"]


@dataclass(frozen=True)
class Deadline:
    """One input's deadlines [s] (``0 < deadline_s < stop_after_s``) and whether it is optional."""

    name: str
    deadline_s: float
    stop_after_s: float
    optional: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.deadline_s) and 0.0 < self.deadline_s < self.stop_after_s
                and math.isfinite(self.stop_after_s)):
            raise ValueError(f"input {self.name!r}: need 0 < deadline_s < stop_after_s, got "
                             f"{self.deadline_s!r}, {self.stop_after_s!r}")


@dataclass(frozen=True)
class WatchState:
    """What the watchdog says at one time: ``stale`` input names, ``stop_reason`` (None: no stop; latched),
    ``ages`` [s] by input (NaN: an optional input that never sent)."""

    stale: tuple[str, ...]
    stop_reason: str | None
    ages: dict[str, float]

    @property
    def stopped(self) -> bool:
        """True once a protective stop has been latched."""
        return self.stop_reason is not None


class Watchdog:
    """Ages of the inputs against their deadlines (module docstring); ``start`` [s] on the caller's clock."""

    def __init__(self, deadlines: Sequence[Deadline], start: float) -> None:
        names = [d.name for d in deadlines]
        if len(set(names)) != len(names):
            raise ValueError(f"input names repeat: {names}")
        self.deadlines = {d.name: d for d in deadlines}
        self.start = float(start)
        self._seen: dict[str, float] = {}
        self._stop: str | None = None

    def seen(self, name: str, now: float) -> None:
        """A message of input ``name`` arrived at ``now``; KeyError for an unknown input."""
        if name not in self.deadlines:
            raise KeyError(f"no input {name!r} (inputs: {', '.join(self.deadlines)})")
        self._seen[name] = float(now)

    def age(self, name: str, now: float) -> float:
        """Seconds since input ``name`` last sent (since ``start`` before its first message; NaN for an
        optional input that never sent)."""
        if name in self._seen:
            return now - self._seen[name]
        return math.nan if self.deadlines[name].optional else now - self.start

    def check(self, now: float) -> WatchState:
        """The stale inputs and the (latched) protective stop at ``now``."""
        ages = {n: self.age(n, now) for n in self.deadlines}
        stale = tuple(n for n, a in ages.items() if a > self.deadlines[n].deadline_s)
        if self._stop is None:
            for n in stale:
                d = self.deadlines[n]
                if not d.optional and ages[n] > d.stop_after_s:
                    never = " (none yet)" if n not in self._seen else ""
                    self._stop = f"{n}: no message for {ages[n]:.3f} s{never}, stop after {d.stop_after_s:g} s"
                    break
        return WatchState(stale, self._stop, ages)

    def resume(self) -> None:
        """Clear the latched protective stop (the caller decides when the inputs are back)."""
        self._stop = None
