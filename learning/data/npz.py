"""NPZ format: one file of stacked arrays (fields: see :mod:`learning.data`)."""

from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np

from ..atomic import atomic_open
from .checks import DataFormatError, Origin
from .model import Demonstrations, PathLike, from_stacked_arrays

__all__ = ["NPZ_FIELDS", "load_npz", "save_npz"]

#: Every field an NPZ file may hold.
NPZ_FIELDS: tuple[str, ...] = ("obs", "act", "trial", "subject", "mode", "voluntary", "t",
                               "obs_names", "act_names", "vol_names", "rate_hz")


def load_npz(path: PathLike) -> Demonstrations:
    """Load and validate an NPZ data set (fields: see :mod:`learning.data`)."""
    p = str(path)
    if not os.path.isfile(p):
        raise DataFormatError("no such file", path=p)
    if not zipfile.is_zipfile(p):
        with open(p, "rb") as f:
            single = f.read(6) == b"\x93NUMPY"
        raise DataFormatError("not an NPZ archive (a single .npy array?)" if single else
                              "not an NPZ archive (not a zip file; expected numpy.savez output)", path=p)
    try:
        npz = np.load(p, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
        raise DataFormatError(f"the file is corrupted ({e})", path=p) from None
    if not isinstance(npz, np.lib.npyio.NpzFile):
        raise DataFormatError("not an NPZ archive (a single .npy array?)", path=p)
    with npz:
        keys = list(npz.files)
        for k in keys:
            if k not in NPZ_FIELDS:
                raise DataFormatError(f"unknown field (allowed: {', '.join(NPZ_FIELDS)})", path=p, field=k)
        for k in ("obs", "act", "trial"):
            if k not in keys:
                raise DataFormatError("required field missing", path=p, field=k)
        arrays: dict[str, np.ndarray] = {}
        for k in keys:
            try:
                arrays[k] = npz[k]
            except ValueError as e:
                if "pickle" in str(e):  # an object array: numpy refuses it without pickle
                    raise DataFormatError("holds Python objects and cannot be read without pickle",
                                          path=p, field=k) from None
                raise DataFormatError(f"the file is corrupted ({e})", path=p, field=k) from None
            except (OSError, zipfile.BadZipFile, EOFError) as e:
                raise DataFormatError(f"the file is corrupted ({e})", path=p, field=k) from None
    return from_stacked_arrays(arrays, Origin(path=p))


def npz_arrays(demos: Demonstrations) -> dict[str, np.ndarray]:
    """The arrays an NPZ file of ``demos`` holds (no object arrays: loadable without pickle)."""
    arrays = demos.stacked()
    arrays["obs_names"] = np.array(demos.obs_names, dtype=str)
    arrays["act_names"] = np.array(demos.act_names, dtype=str)
    if demos.has_voluntary:
        arrays["vol_names"] = np.array(demos.vol_names, dtype=str)
    arrays["rate_hz"] = np.array(float(demos.rate_hz))
    return arrays


def save_npz(demos: Demonstrations, path: PathLike) -> None:
    """Validate, then write an NPZ file atomically (temporary file in the same folder, then rename)."""
    demos.validate()
    arrays = npz_arrays(demos)
    with atomic_open(Path(path), "wb") as f:
        np.savez(f, **arrays)
