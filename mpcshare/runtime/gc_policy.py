"""The garbage collector while ``mpcshare run`` ticks.

``python``: Python's own automatic collection (a generation-2 collection scans every object the
process holds, the model's and the libraries' included: tens of milliseconds at an arbitrary tick).
``managed`` (the default): at the start of the loop, a full collection, then :func:`gc.freeze` (every
object alive then is never scanned again) and automatic collection off; after each tick, when at least
``min_slack_s`` is left before the next one, the generation Python would collect by its own thresholds
(:func:`gc.get_threshold`, :func:`gc.get_count`) is collected there instead, over the objects made
since the freeze only. :meth:`CollectorPolicy.stop` restores automatic collection. Under either policy,
:meth:`CollectorPolicy.start` times one full collection of the heap as set up (``full_ms``: what an
automatic generation-2 collection costs at a tick), and under ``managed`` one more after the freeze
(``frozen_full_ms``).
"""

from __future__ import annotations

import gc
import time

__all__ = ["GC_POLICIES", "CollectorPolicy"]

#: The policies (module docstring).
GC_POLICIES: tuple[str, ...] = ("managed", "python")


class CollectorPolicy:
    """The collector under ``policy`` (:data:`GC_POLICIES`); ValueError naming the policies otherwise."""

    def __init__(self, policy: str = "managed", min_slack_s: float = 2e-3) -> None:
        if policy not in GC_POLICIES:
            raise ValueError(f"gc policy {policy!r}: expected one of {', '.join(GC_POLICIES)}")
        self.policy, self.min_slack_s = policy, float(min_slack_s)
        self.collections = [0, 0, 0]  # collections made in the slack, per generation
        self.full_ms = self.frozen_full_ms = float("nan")
        self._enabled: bool | None = None
        self._started = False

    def start(self) -> None:
        """Time a full collection; ``managed``: then freeze what is alive, time a full collection again and stop
        automatic collection (idempotent)."""
        if self._started:
            return
        self._started = True
        t0 = time.perf_counter()
        gc.collect()
        self.full_ms = (time.perf_counter() - t0) * 1e3
        if self.policy != "managed":
            return
        self._enabled = gc.isenabled()
        gc.freeze()
        t0 = time.perf_counter()
        gc.collect()
        self.frozen_full_ms = (time.perf_counter() - t0) * 1e3
        gc.disable()

    def idle(self, slack_s: float) -> int:
        """With ``slack_s`` [s] left before the next tick: collect the generation due, if any and if the
        slack is at least ``min_slack_s``; returns the generation collected (-1: none)."""
        if self._enabled is None or slack_s < self.min_slack_s:
            return -1
        counts, thresholds = gc.get_count(), gc.get_threshold()
        if counts[0] < thresholds[0]:
            return -1
        generation = 2 if counts[2] >= thresholds[2] else 1 if counts[1] >= thresholds[1] else 0
        gc.collect(generation)
        self.collections[generation] += 1
        return generation

    def stop(self) -> None:
        """Automatic collection as it was before :meth:`start`; the frozen objects back in the heap."""
        self._started = False
        if self._enabled is None:
            return
        gc.unfreeze()
        if self._enabled:
            gc.enable()
        self._enabled = None

    def report(self) -> dict[str, object]:
        """The policy, the timed full collections [ms] (None: not timed) and the collections made in the slack
        per generation."""
        def ms(x: float) -> float | None:
            return None if x != x else round(x, 3)

        return {"policy": self.policy, "full_ms": ms(self.full_ms), "frozen_full_ms": ms(self.frozen_full_ms),
                "slack_collections": list(self.collections)}
