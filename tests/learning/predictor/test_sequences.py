"""Tests of learning.predictor.sequences: chunking with burn-in and padding of trial sequences."""

from __future__ import annotations

import numpy as np
import pytest

from learning.predictor.sequences import check_sequence_set, chunk_sequences, pad_sequences


def test_chunks_carry_burn_in_without_loss_and_cover_every_masked_step_once():
    T = 7
    x = np.arange(T, dtype=float)[:, None]
    y = 10 + x
    m = np.array([1, 1, 0, 1, 1, 1, 1], bool)
    X, Y, W = chunk_sequences([x, x[:2]], [y, y[:2]], [m, np.zeros(2, bool)], chunk_len=3, burn_in=2)
    # chunks of trial 0 start at 0, 3, 6; trial 1 has no loss step and is dropped
    assert X.shape == (3, 5, 1)
    np.testing.assert_array_equal(X[0, :, 0], [0, 1, 2, 0, 0])     # no burn-in at the trial start
    np.testing.assert_array_equal(X[1, :, 0], [1, 2, 3, 4, 5])     # burn-in 1, 2
    np.testing.assert_array_equal(X[2, :, 0], [4, 5, 6, 0, 0])     # burn-in 4, 5; right padding
    np.testing.assert_array_equal(W, [[1, 1, 0, 0, 0], [0, 0, 1, 1, 1], [0, 0, 1, 0, 0]])
    np.testing.assert_array_equal(Y[1, :, 0], 10 + X[1, :, 0])
    # every masked step has loss weight exactly once
    assert W.sum() == m.sum()


def test_pad_sequences_weights_are_the_masks():
    xs = [np.ones((3, 2)), np.ones((1, 2))]
    ys = [np.ones((3, 1)), np.ones((1, 1))]
    X, Y, W = pad_sequences(xs, ys, [np.array([True, False, True]), np.array([True])])
    assert X.shape == (2, 3, 2) and Y.shape == (2, 3, 1)
    np.testing.assert_array_equal(W, [[1, 0, 1], [1, 0, 0]])
    assert X[1, 1:].sum() == 0


def test_check_sequence_set_names_the_problem():
    with pytest.raises(ValueError, match="sequences is empty"):
        check_sequence_set([])
    with pytest.raises(ValueError, match=r"sequences\[0\] must be 2-D"):
        check_sequence_set([np.ones(3)])
    with pytest.raises(ValueError, match="targets for sequences must be a list of 1"):
        check_sequence_set([np.ones((3, 2))], [np.ones((3, 1))] * 2)
    xs, ys, ms = check_sequence_set([np.ones((3, 2))], [np.ones((3, 1))], [np.ones(3, bool)])
    assert xs[0].dtype == float and ys[0].shape == (3, 1) and ms[0].all()
