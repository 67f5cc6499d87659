"""A small data set saved once per test module, for the commands that read one (inspect, analyze, train)."""

import pytest

from learning.data import save
from sim.demonstrator import GeneratorConfig, generate_demonstrations


@pytest.fixture(scope="module")
def data_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "demos.npz"
    # 20 trials of 18 s: the segmentation test is over trials and needs >= 10 for p < 0.001
    save(generate_demonstrations(2, 3, seed=0, config=GeneratorConfig(trial_minutes=0.3)), path)
    return path
