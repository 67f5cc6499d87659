"""The checks of TaskModes' settings (learning.modes._params): the first invalid setting is named with what is valid."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from learning.modes import TaskModes
from learning.modes._params import check_params

VALID = dict(n_modes=3, covariance_type="full", n_restarts=2, n_iter=50, temporal=True, sticky=0.0, tol=1e-4,
             min_covar=1e-6, n_pca=None)


def test_valid_settings_pass():
    check_params(SimpleNamespace(**VALID))
    for n_pca in (2, 0.9):
        check_params(SimpleNamespace(**{**VALID, "n_pca": n_pca}))


@pytest.mark.parametrize("name, bad, match", [
    ("n_modes", 0, "n_modes must be a positive integer"),
    ("n_modes", 2.5, "n_modes must be a positive integer"),
    ("covariance_type", "round", "covariance_type must be one of"),
    ("n_restarts", 0, "n_restarts must be a positive integer"),
    ("n_iter", 1.5, "n_iter must be a positive integer"),
    ("temporal", 1, "temporal must be True"),
    ("sticky", -1.0, "sticky must be >= 0"),
    ("tol", float("nan"), "tol must be >= 0"),
    ("min_covar", 0.0, "min_covar must be > 0"),
    ("n_pca", 1.0, "n_pca must be None"),
    ("n_pca", 0, "n_pca must be None"),
])
def test_each_invalid_setting_is_named(name, bad, match):
    with pytest.raises(ValueError, match=match) as e:
        check_params(SimpleNamespace(**{**VALID, name: bad}))
    assert repr(bad) in str(e.value)


def test_task_modes_checks_its_settings_on_fit():
    with pytest.raises(ValueError, match="n_modes"):
        TaskModes(n_modes=0).fit([[0.0, 1.0]] * 10)
