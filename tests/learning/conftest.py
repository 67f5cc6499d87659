"""Fixtures of the learning.modes tests: one BLAS thread, trials from a known HMM, a TaskModes fitted to them."""

from __future__ import annotations

import pytest
from threadpoolctl import threadpool_limits

from learning.modes import TaskModes
from tests.learning.hmm_samples import sample_hmm


@pytest.fixture
def _one_blas_thread():
    """hmmlearn's reference computations use tiny threaded BLAS calls that crawl on a busy
    2-core machine; TaskModes limits threads itself, the vanilla references here do not."""
    with threadpool_limits(limits=1):
        yield


@pytest.fixture(scope="module")
def data():
    return sample_hmm(sep=1.0)


@pytest.fixture(scope="module")
def fitted(data):
    X, _, L = data
    return TaskModes(n_modes=4, n_restarts=3, seed=0).fit(X, L)
