"""The keep-out's zones of a trial recorded in one episode and given back in the next (docs/design.md, "What every
episode of a trial shares").

:meth:`mpcshare.control.keepout.KeepOut.update` reads only the fork sample, its Kalman velocity, the time, the
base pose (the torso's sway: the same for a trial and seed) and its own state (the last measured fork pose, when,
the marker's age). :class:`RecordedKeepOut` stands in for the controller's keep-out: recording, it runs each call
and logs its inputs and prior state as bytes with what it left (the zones handed to the QP's keep-out rows, the
faults it added, its state after); replaying, it gives a call back where the call at that place in the log has
the same inputs byte for byte, and runs it live elsewhere (another seed), so every call has the live outcome.
Everything else (``check``, ``limit``, ``settings``) is the live keep-out's.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["RecordedKeepOut", "ZoneLog", "float_bytes"]

#: per ``update`` call in order: (its inputs and prior state as bytes, (zones, faults added, state after)), or
#: None where the live call raised
ZoneLog = list[tuple[tuple[bytes | None, ...], tuple[Any, ...]] | None]


def float_bytes(x: Any) -> bytes | None:
    """``x`` as float64 bytes (a replay log's key: equal only for the same values to the bit); None for None."""
    return None if x is None else np.asarray(x, dtype=float).tobytes()


class RecordedKeepOut:
    """A :class:`mpcshare.control.keepout.KeepOut` (``live``) whose ``update`` is logged into ``log``
    (``replaying`` False: the log is emptied at each ``reset``) or given back from it (module docstring)."""

    def __init__(self, live: Any, log: ZoneLog, replaying: bool) -> None:
        self._live, self._log, self._replaying = live, log, replaying
        self._cursor = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._live, name)

    def reset(self) -> None:
        """A new episode: the live keep-out reset, the log replayed from its start (or emptied, recording)."""
        self._cursor = 0
        if not self._replaying:
            self._log.clear()
        self._live.reset()

    def _state(self) -> tuple[Any, float, float]:
        live = self._live
        return live._pose, live._t_seen, live.age_s

    def update(self, t: float, obs: Any, fork_velocity: np.ndarray, repeated: bool, base_pose: np.ndarray,
               faults: list[tuple[str, str]]) -> None:
        """:meth:`mpcshare.control.keepout.KeepOut.update`: the same zones, faults and state after it."""
        pose, t_seen, age = self._state()
        key = (np.array([t, t_seen, age, bool(repeated)], dtype=float).tobytes(), float_bytes(obs),
               float_bytes(fork_velocity), float_bytes(base_pose), float_bytes(pose))
        live, log, i = self._live, self._log, self._cursor
        self._cursor = i + 1
        if self._replaying:
            entry = log[i] if i < len(log) else None
            if entry is not None and entry[0] == key:
                zones, added, (live._pose, live._t_seen, live.age_s) = entry[1]
                faults.extend(added)
                live.limit.set_zones(zones)
                return
            live.update(t, obs, fork_velocity, repeated, base_pose, faults)
            return
        log.append(None)
        n0 = len(faults)
        live.update(t, obs, fork_velocity, repeated, base_pose, faults)
        log[-1] = (key, (tuple(live.limit.zones), tuple(faults[n0:]), self._state()))
