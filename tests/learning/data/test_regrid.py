"""Topics onto one time grid (learning.data.regrid): unwrapped angles, the common span, an empty overlap."""

import numpy as np
import pytest

from learning.data import DataFormatError
from learning.data.regrid import TopicSeries, regrid


def test_regrid_unwraps_and_finds_the_common_span():
    t1 = np.arange(0, 2.0, 0.013)
    t2 = np.arange(0.3, 2.5, 0.021)
    ang = np.angle(np.exp(1j * 4.0 * t1))  # wrapped: jumps at ±π
    segs = regrid([TopicSeries("/a", t1, ang[:, None], np.array([True])),
                   TopicSeries("/b", t2, t2[:, None] ** 2, np.array([False]))], 100.0)
    (seg,) = segs
    assert seg.t[0] == pytest.approx(0.3) and seg.t[-1] <= t1[-1]
    unwrapped = seg.columns["/a"][:, 0]
    np.testing.assert_allclose(unwrapped, 4.0 * seg.t, atol=1e-12)  # interpolated the short way round
    assert np.abs(seg.columns["/b"][:, 0] - seg.t ** 2).max() < 0.021 ** 2 / 4 + 1e-12


def test_regrid_empty_overlap():
    with pytest.raises(DataFormatError, match=r"empty overlap.*/a ends at t = 1\.000 s, /b starts at t = 2\.000 s"):
        regrid([TopicSeries("/a", np.array([0.0, 1.0]), np.zeros((2, 1)), np.array([False])),
                TopicSeries("/b", np.array([2.0, 3.0]), np.zeros((2, 1)), np.array([False]))], 100.0,
               path="bag")
