"""The checks of :class:`~learning.modes.TaskModes`'s settings (ValueError naming the setting and the valid values)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._hmm import COV_TYPES

__all__ = ["check_params"]


def check_params(est: Any) -> None:
    """ValueError naming the first invalid setting of the TaskModes ``est`` and what is valid."""
    if int(est.n_modes) != est.n_modes or est.n_modes < 1:
        raise ValueError(f"n_modes must be a positive integer, got {est.n_modes!r}")
    if est.covariance_type not in COV_TYPES:
        raise ValueError(f"covariance_type must be one of {COV_TYPES}, "
                         f"got {est.covariance_type!r}")
    if int(est.n_restarts) != est.n_restarts or est.n_restarts < 1:
        raise ValueError(f"n_restarts must be a positive integer, got {est.n_restarts!r}")
    if int(est.n_iter) != est.n_iter or est.n_iter < 1:
        raise ValueError(f"n_iter must be a positive integer, got {est.n_iter!r}")
    if not isinstance(est.temporal, (bool, np.bool_)):
        raise ValueError(f"temporal must be True (HMM) or False (Gaussian mixture), got {est.temporal!r}")
    if not est.sticky >= 0:
        raise ValueError(f"sticky must be >= 0, got {est.sticky!r}")
    if not est.tol >= 0:
        raise ValueError(f"tol must be >= 0, got {est.tol!r}")
    if not est.min_covar > 0:
        raise ValueError(f"min_covar must be > 0, got {est.min_covar!r}")
    if est.n_pca is not None:
        ok = (isinstance(est.n_pca, (int, np.integer)) and est.n_pca >= 1) or \
             (isinstance(est.n_pca, float) and 0 < est.n_pca < 1)
        if not ok:
            raise ValueError("n_pca must be None, a positive int or a float in (0, 1), "
                             f"got {est.n_pca!r}")
