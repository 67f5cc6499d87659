"""The report's colours (mpcshare.reports.style): every run shown has its own, and no near twin."""

from __future__ import annotations

import itertools

import numpy as np
from matplotlib.colors import to_rgb

from mpcshare.reports.style import strategy_colour
from mpcshare.run_table import RUN_NAMES


def _lab(colour: str) -> np.ndarray:
    """CIELAB (D65) of a matplotlib colour."""
    rgb = np.array(to_rgb(colour))
    lin = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ lin
    xyz = xyz / np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_every_run_shown_has_its_own_colour_and_no_near_twin():
    """ΔE*ab ≥ 25 between any two of the runs the comparison shows (about 2.3 is a just-noticeable difference)."""
    lab = {n: _lab(strategy_colour(n)) for n in RUN_NAMES}
    closest = min((float(np.linalg.norm(lab[a] - lab[b])), a, b) for a, b in itertools.combinations(RUN_NAMES, 2))
    assert closest[0] >= 25, closest
