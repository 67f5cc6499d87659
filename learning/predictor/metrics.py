"""RMSE of predicted actions in physical units, per channel and per channel group.

Groups follow the project's channel names (``docs/design.md``, "Data format"): names ending in
``_x``/``_y``/``_z`` are positions [m], ``_roll``/``_pitch``/``_yaw`` orientations
[rad], ``_fx``/``_fy``/``_fz`` forces [N]; any other name belongs to ``"other"``, so
data without physical names still gets a figure. Pass actions in physical units
(``Preprocessor.act.inverse_transform`` of the standardised prediction).

    RMSE_group = sqrt( mean over rows and the group's channels of (ŷ − y)² )
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["GROUPS", "channel_group", "rmse_by_channel", "rmse_by_group"]

#: group key → name suffixes; the key carries the unit.
GROUPS: dict[str, tuple[str, ...]] = {
    "position_m": ("_x", "_y", "_z"),
    "orientation_rad": ("_roll", "_pitch", "_yaw"),
    "force_N": ("_fx", "_fy", "_fz"),
}


def channel_group(name: str) -> str:
    """The group key of one channel name (``"other"`` when no suffix matches)."""
    for key, suffixes in GROUPS.items():
        if name.endswith(suffixes):
            return key
    return "other"


def _check(y_true: Any, y_pred: Any, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    a, b = np.asarray(y_true, dtype=float), np.asarray(y_pred, dtype=float)
    if a.ndim != 2 or a.shape != b.shape:
        raise ValueError(f"y_true and y_pred must be 2-D arrays of the same shape, got {a.shape} and {b.shape}")
    names = [str(n) for n in names]
    if len(names) != a.shape[1]:
        raise ValueError(f"{len(names)} channel names for {a.shape[1]} channels")
    if a.shape[0] == 0:
        raise ValueError("no rows: RMSE of an empty set is undefined")
    for arr, what in ((a, "y_true"), (b, "y_pred")):
        bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
        if bad.size:
            raise ValueError(f"{what} row {bad[0]} is not finite")
    return a, b, names


def rmse_by_channel(y_true: Any, y_pred: Any, names: Sequence[str]) -> dict[str, float]:
    """RMSE per channel, ``{name: rmse}`` in the channel's units."""
    a, b, names = _check(y_true, y_pred, names)
    r = np.sqrt(np.mean((b - a) ** 2, axis=0))
    return {n: float(v) for n, v in zip(names, r)}


def rmse_by_group(y_true: Any, y_pred: Any, names: Sequence[str]) -> dict[str, float]:
    """RMSE per group present: keys among ``position_m``, ``orientation_rad``, ``force_N``, ``other``."""
    a, b, names = _check(y_true, y_pred, names)
    groups = np.array([channel_group(n) for n in names])
    out: dict[str, float] = {}
    for key in (*GROUPS, "other"):
        sel = groups == key
        if sel.any():
            out[key] = float(np.sqrt(np.mean((b[:, sel] - a[:, sel]) ** 2)))
    return out
