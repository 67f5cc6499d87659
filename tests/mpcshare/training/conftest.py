"""Small demonstrations shared by the training tests, made once per test module."""

import pytest

from sim.demonstrator import GeneratorConfig, generate_demonstrations


@pytest.fixture(scope="module")
def demos():
    return generate_demonstrations(2, 1.5, seed=1, config=GeneratorConfig(trial_minutes=0.5))
