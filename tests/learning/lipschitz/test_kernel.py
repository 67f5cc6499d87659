"""The survivor search of learning.lipschitz's kernel against a dense comparison."""

from __future__ import annotations

import numpy as np

from learning.lipschitz import survivors


def test_survivors_matches_dense_compare():
    """The segmented survivor search finds exactly the entries S ≥ 0 (any width)."""
    rng = np.random.default_rng(11)
    for a, c in [(5, 64), (7, 200), (3, 10), (16, 1000)]:
        S = rng.normal(size=(a, c)).astype(np.float32) - 2.5
        S[0, -1] = 0.0
        S[-1, 0] = -0.0  # -0.0 >= 0 holds
        ri, cj = survivors(S)
        ref_r, ref_c = np.nonzero(S >= 0)
        got = sorted(zip(ri.tolist(), cj.tolist()))
        assert got == sorted(zip(ref_r.tolist(), ref_c.tolist()))
