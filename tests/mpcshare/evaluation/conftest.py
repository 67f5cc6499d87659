"""The tune fixtures shared by test_tune.py and tuning/ (session scope: one tiny sweep for both)."""

from __future__ import annotations

import pytest

from learning.data import save
from mpcshare.cli import main
from sim.demonstrator import generate_demonstrations
from tests.mpcshare.evaluation.tune_rows import SWEEP


@pytest.fixture(scope="session")
def data(tmp_path_factory):
    path = tmp_path_factory.mktemp("tune") / "demos.npz"
    save(generate_demonstrations(3, 4.0, seed=5), path)
    return path


@pytest.fixture(scope="session")
def swept(data, tmp_path_factory):
    out = tmp_path_factory.mktemp("tune_out")
    assert main(["tune", str(data), "--out", str(out), *SWEEP]) == 0
    return out
