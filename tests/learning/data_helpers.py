"""Small demonstration sets and their comparison, shared by the learning.data tests."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from learning.data import Demonstrations, Trial

OBS = ["x", "y", "z", "roll"]
ACT = ["kx", "ky", "kz"]
VOL = ["elev", "prot"]


def make_demos(n_trials: int = 3, T: int = 40, optional: bool = True, seed: int = 0) -> Demonstrations:
    rng = np.random.default_rng(seed)
    trials = []
    for i in range(n_trials):
        n = T + 5 * i
        trials.append(Trial(
            obs=rng.normal(size=(n, len(OBS))), act=rng.normal(size=(n, len(ACT))),
            t=0.5 * i + np.arange(n) / 100.0, trial_id=10 + i,
            subject=i % 2 if optional else -1,
            mode=rng.integers(-1, 4, n) if optional else None,
            voluntary=rng.normal(size=(n, len(VOL))) if optional else None))
    return Demonstrations(trials, 100.0, list(OBS), list(ACT), list(VOL) if optional else [])


def assert_same(a: Demonstrations, b: Demonstrations) -> None:
    assert a.rate_hz == pytest.approx(b.rate_hz, rel=1e-9)
    assert (a.obs_names, a.act_names, a.vol_names) == (b.obs_names, b.act_names, b.vol_names)
    sa, sb = a.stacked(), b.stacked()
    assert sa.keys() == sb.keys()
    for k in sa:
        np.testing.assert_array_equal(sa[k], sb[k], err_msg=k)


def leftovers(folder: Path) -> list[str]:
    """The hidden files (temporary files of an atomic save) left in ``folder``."""
    return sorted(n for n in os.listdir(folder) if n.startswith("."))
