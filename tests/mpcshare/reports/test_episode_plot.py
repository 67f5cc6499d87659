"""The trial plot's sawing close-up is taken where the demonstration cuts, not at a repositioning jump."""

import numpy as np

from mpcshare.reports.episode_plot import _sawing_window


def test_the_sawing_window_stays_inside_the_cutting_steps():
    t = np.arange(0, 15, 0.01)
    band = np.zeros((t.size, 3))
    band[:240, 0] = 0.005 * np.sin(2 * np.pi * 2.3 * t[:240])  # 2.4 s of strokes along x
    jump = (t > 8.2) & (t < 9.0)
    band[jump, 1] = 0.03 * np.sin(2 * np.pi * 1.5 * (t[jump] - 8.2))  # a larger repositioning jump along y
    free, axis = _sawing_window(t, band)
    assert axis == 1  # scored on energy alone, the jump wins
    window, axis = _sawing_window(t, band, allowed=t < 2.4)
    assert axis == 0 and window.start >= 0 and window.stop <= 240  # the 2.4 s of cutting, shorter than 4 s
    assert _sawing_window(t, band, allowed=t < 0.5)[1] == 1  # under a second of cutting: scored as without
