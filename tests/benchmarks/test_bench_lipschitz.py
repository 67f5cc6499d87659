"""The quotient benchmark's own measurements: the certification share (the part of the pairs
no group bound can rule out) on a hand-computed example, and the tuned brute force."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from learning.lipschitz import pointwise_quotients

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_lipschitz.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_lipschitz", BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_certification_share_by_hand(bench):
    # x on a line; y = 2 at x = 1, else 0.
    X = np.array([[0.0], [1.0], [3.0], [3.5]])
    Y = np.array([[0.0], [2.0], [0.0], [0.0]])
    q = pointwise_quotients(X, Y)
    np.testing.assert_allclose(q, [2.0, 2.0, 1.0, 2 / 2.5])
    # row 2: D = 2, radius D/q = 2: only x = 3.5 lies strictly closer (x = 1 is at exactly 2)
    out = bench.certification_share(X, Y, q, np.array([2]))
    assert out["certification_rows"] == 1
    assert out["certification_share_median"] == pytest.approx(1 / 3, abs=1e-4)
    # row 0: radius 2/2 = 1, nothing strictly inside
    assert bench.certification_share(X, Y, q, np.array([0]))["certification_share_mean"] == 0.0


def test_certification_share_skips_rows_without_quotient(bench):
    X = np.array([[0.0], [1.0]])
    Y = np.array([[1.0], [1.0]])  # constant output: q = 0 for both rows
    q = pointwise_quotients(X, Y)
    assert bench.certification_share(X, Y, q, np.array([0, 1])) == {"certification_rows": 0}


def test_tuned_brute_force_is_a_fastest_size_and_agrees_with_float64(bench):
    rng = np.random.default_rng(0)
    X, Y = rng.normal(size=(600, 5)), rng.normal(size=(600, 2))
    block, per_row = bench.tune_brute_block(X, Y, rng, sizes=(256, 512), rows=300)
    assert block in (256, 512) and set(per_row) == {"256", "512"}
    assert per_row[str(block)] == min(per_row.values())
    rows = np.arange(0, 600, 7)
    np.testing.assert_allclose(bench.brute_force_f32(X, Y, rows, block=block),
                               bench.reference_rows(X, Y, rows), rtol=1e-3)
