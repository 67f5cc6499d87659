"""learning.modes' agreement metrics: Hungarian matching of mode labels."""

from __future__ import annotations

import numpy as np
import pytest

from learning.modes import match_modes, mode_agreement, mode_ari, relabel

# hmmlearn's reference computations here use tiny threaded BLAS calls (fixture: conftest.py)
pytestmark = pytest.mark.usefixtures("_one_blas_thread")


def test_hungarian_matching_on_hand_made_labels():
    true = np.array([0, 0, 0, 1, 1, 1, 2, 2, -1, -1])
    pred = np.array([5, 5, 3, 3, 3, 3, 7, 7, 5, 9])
    mapping = match_modes(pred, true)
    assert mapping == {3: 1, 5: 0, 7: 2, 9: -1}
    acc, m2 = mode_agreement(pred, true)
    assert m2 == mapping
    assert acc == pytest.approx(7 / 8)  # samples with true = -1 are ignored
    np.testing.assert_array_equal(relabel(pred, mapping), [0, 0, 1, 1, 1, 1, 2, 2, 0, -1])
    # fewer predicted modes than labels: each mode takes its best label
    acc, m = mode_agreement(np.array([0, 0, 1, 1, 1, 1]), np.array([0, 0, 1, 1, 2, 2]))
    assert m == {0: 0, 1: 1} or m == {0: 0, 1: 2}
    assert acc == pytest.approx(4 / 6)
    # over-segmentation: many-to-one majority mapping on request
    acc, m = mode_agreement(np.array([0, 1, 2, 2]), np.array([0, 0, 1, 1]), one_to_one=False)
    assert m == {0: 0, 1: 0, 2: 1} and acc == 1.0
    assert mode_agreement(np.array([0, 1, 2, 2]), np.array([0, 0, 1, 1]))[0] == 0.75
    # a permutation is perfect agreement; ARI ignores numbering
    t = np.array([0, 1, 2, 2, 1, 0])
    assert mode_agreement((t + 1) % 3, t)[0] == 1.0
    assert mode_ari((t + 1) % 3, t) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="no labelled"):
        mode_agreement(np.array([0, 1]), np.array([-1, -1]))
    with pytest.raises(ValueError, match="labels"):
        match_modes(np.array([0, 1]), np.array([0, 1, 2]))
