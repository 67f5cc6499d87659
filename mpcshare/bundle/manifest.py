"""What a bundle folder holds in each format version, and the manifest that vouches for it.

``manifest.json`` is ``{"format_version": n, "files": {name: {"bytes": n, "sha256": hex}}}`` for every other
file of that version (:data:`FILES`); :func:`verify_manifest` checks each file's size and SHA-256 before anything
is read, and every failure is one :class:`BundleError` whose message starts with the offending file.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from mpcshare.bundle.files import file_sha256
from mpcshare.errors import MpcshareError

__all__ = ["BUNDLE_FILES", "FILES", "FORMAT_VERSION", "MANIFEST", "READ_VERSIONS", "BundleError", "read_json",
           "verify_manifest"]

#: Version of the folder layout written by :func:`~mpcshare.bundle.save_bundle`; :data:`READ_VERSIONS` are read.
FORMAT_VERSION = 3
#: versions :func:`~mpcshare.bundle.load_bundle` reads (1: before the control-rate forecast, loaded without it;
#: 1, 2: the rule in ``metrics.json``, migrated)
READ_VERSIONS = (1, 2, 3)
MANIFEST = "manifest.json"
#: Files of a version-1 bundle besides the manifest.
BUNDLE_FILES_V1: tuple[str, ...] = ("bundle.json", "metrics.json", "preprocessor.json", "predictor.pt",
                                    "modes.joblib", "gates.joblib")
#: Files of a version-2 bundle besides the manifest.
BUNDLE_FILES_V2: tuple[str, ...] = (*BUNDLE_FILES_V1, "fast.json")
#: Files of a bundle of the current version besides the manifest.
BUNDLE_FILES: tuple[str, ...] = (*BUNDLE_FILES_V2, "rule.json")
FILES = {1: BUNDLE_FILES_V1, 2: BUNDLE_FILES_V2, 3: BUNDLE_FILES}



class BundleError(MpcshareError, ValueError):
    """A bundle that cannot be used; the message starts with the file that is wrong."""

    def __init__(self, path: str | os.PathLike, message: str) -> None:
        super().__init__(f"{path}: {message}")
        self.path = str(path)


def read_json(path: Path) -> Any:
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise BundleError(path, f"not valid JSON ({exc}); the file is truncated or corrupt") from None
    except OSError as exc:
        raise BundleError(path, f"cannot read ({exc.strerror or exc})") from None


def _check_version(path: Path, version: Any) -> None:
    if version not in READ_VERSIONS:
        raise BundleError(path, f"bundle format version {version!r}; this mpcshare reads versions "
                                f"{list(READ_VERSIONS)} (retrain with `mpcshare train`)")


def verify_manifest(root: Path) -> int:
    """Check the manifest and every file it must list; return the format version."""
    mpath = root / MANIFEST
    if not mpath.is_file():
        raise BundleError(mpath, "missing: not a model bundle (or an incomplete one)")
    manifest = read_json(mpath)
    if not isinstance(manifest, dict) or "files" not in manifest or "format_version" not in manifest:
        raise BundleError(mpath, "not a bundle manifest (keys 'format_version' and 'files' expected)")
    version = manifest["format_version"]
    _check_version(mpath, version)
    files = manifest["files"]
    names = FILES[version]
    missing_entries = [n for n in names if n not in files]
    if missing_entries:
        raise BundleError(mpath, f"does not list {missing_entries[0]}")
    for name in names:
        path = root / name
        if not path.is_file():
            raise BundleError(path, "missing from the bundle")
        size, want = path.stat().st_size, files[name]
        if size != want.get("bytes"):
            raise BundleError(path, f"{size} bytes, the manifest says {want.get('bytes')}: "
                                    "truncated or replaced")
        if file_sha256(path) != want.get("sha256"):
            raise BundleError(path, "checksum differs from the manifest: the file is corrupt or was edited")
    return int(version)
