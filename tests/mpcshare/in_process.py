"""`mpcshare train`'s closed-loop rule choice in the test's process, for tests of the commands (not of the pool)."""

from __future__ import annotations

import pytest


def choose_rules_in_process(monkeypatch: pytest.MonkeyPatch) -> None:
    """The rule choice's default pool gets one worker, this process: no worker processes started (each imports the
    simulator and torch, ~5 CPU s) for a few seconds of episodes. The choice is the same with any number of workers
    (tests/mpcshare/evaluation/test_episode_pool.py); `demo`'s test and the README's `train` keep the workers."""
    from mpcshare.calibration import rule_choice
    from mpcshare.commands import train

    monkeypatch.setattr(rule_choice, "default_workers", lambda: 1)
    monkeypatch.setattr(train, "default_workers", lambda: 1)  # `train --workers`' default
