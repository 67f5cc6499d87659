"""The bundle's pieces as files: exact JSON encodings, checksums and durable writes.

Used by :mod:`mpcshare.bundle` to write and read a model bundle: +∞ as JSON ``null``,
fitted standardizers as exact JSON numbers (no pickle), the library versions recorded
in ``bundle.json``, SHA-256 checksums of the manifest and fsync (JSON is written by
:func:`learning.atomic.write_json`).
"""

from __future__ import annotations

import hashlib
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from learning.preprocessing.preprocess import Standardizer

__all__ = ["json_number", "from_json_number", "standardizer_to_json", "standardizer_from_json",
           "library_versions", "file_sha256", "fsync_path"]


def json_number(x: float) -> float | None:
    """A float for JSON; +∞ becomes None (read back as +∞ by :func:`from_json_number`)."""
    x = float(x)
    if math.isnan(x) or x == -math.inf:
        raise ValueError(f"cannot store {x} in a bundle")
    return None if x == math.inf else x


def from_json_number(x: float | None) -> float:
    """The inverse of :func:`json_number`: None becomes +∞."""
    return math.inf if x is None else float(x)


def standardizer_to_json(s: Standardizer) -> dict[str, Any]:
    """A fitted :class:`~learning.preprocessing.preprocess.Standardizer` as exact JSON numbers."""
    if not hasattr(s, "mean_"):
        raise ValueError("the preprocessor's standardizers must be fitted")
    sensors = s.sensors if s.sensors is None or isinstance(s.sensors, (int, np.integer)) \
        else [list(map(int, g)) for g in s.sensors]
    return {"scope": s.scope, "sensors": sensors, "field": s.field,
            "mean": [float(v) for v in s.mean_], "scale": [float(v) for v in s.scale_],
            "groups": [[int(i) for i in g] for g in s.groups_]}


def standardizer_from_json(d: dict[str, Any]) -> Standardizer:
    """The fitted standardizer written by :func:`standardizer_to_json`; ValueError if invalid."""
    s = Standardizer(d["scope"], sensors=d["sensors"], field=d["field"])
    s.mean_ = np.asarray(d["mean"], dtype=float)
    s.scale_ = np.asarray(d["scale"], dtype=float)
    s.groups_ = [np.asarray(g, dtype=int) for g in d["groups"]]
    s.n_features_in_ = int(s.mean_.shape[0])
    if s.scale_.shape != s.mean_.shape or not (np.isfinite(s.mean_).all() and (s.scale_ > 0).all()):
        raise ValueError("mean and scale must be finite, of equal length, scale > 0")
    return s


def library_versions() -> dict[str, str]:
    """Versions of the libraries whose objects a bundle stores (recorded in ``bundle.json``)."""
    import hmmlearn
    import sklearn
    import torch
    return {"numpy": np.__version__, "scikit-learn": sklearn.__version__,
            "hmmlearn": hmmlearn.__version__, "torch": torch.__version__}


def file_sha256(path: Path) -> str:
    """Hex SHA-256 of a file's bytes, read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def fsync_path(path: Path) -> None:
    """fsync a file or a folder (so that a rename into it is durable)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
