"""Stage-level progress of training and the sweep: a tqdm bar over named stages and each stage's time [s]."""

from __future__ import annotations

import time

__all__ = ["Stages"]


class Stages:
    """Stage-level progress (tqdm) with the time of each stage [s]."""

    def __init__(self, names: list[str], enabled: bool, desc: str = "train") -> None:
        self.bar = None
        if enabled:
            from learning.progress import progress_bar
            self.bar = progress_bar(total=len(names), desc=desc, unit="stage")
            self.bar.set_postfix_str(names[0])
        self.names = names
        self.timings: dict[str, float] = {}
        self._t = time.perf_counter()

    def done(self, name: str) -> None:
        now = time.perf_counter()
        self.timings[name] = round(self.timings.get(name, 0.0) + now - self._t, 3)
        self._t = now
        if self.bar is not None:
            self.bar.update(1)
            i = self.names.index(name) + 1 if name in self.names else len(self.names)
            if i < len(self.names):
                self.bar.set_postfix_str(self.names[i])

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


