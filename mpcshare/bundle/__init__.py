"""Model bundles: everything the online controller needs, in one folder.

- :mod:`mpcshare.bundle.bundle` — :class:`ModelBundle`, :func:`save_bundle` (atomic) and
  :func:`load_bundle` (checked against the manifest);
- :mod:`mpcshare.bundle.files` — exact JSON encodings, checksums and durable writes.
"""

from mpcshare.bundle.bundle import (
                                    BUNDLE_FILES,
                                    FORMAT_VERSION,
                                    BundleError,
                                    ModelBundle,
                                    check_bundle_target,
                                    is_bundle,
                                    load_bundle,
                                    save_bundle,
)

__all__ = ["BUNDLE_FILES", "FORMAT_VERSION", "BundleError", "ModelBundle", "check_bundle_target", "is_bundle",
           "load_bundle", "save_bundle"]
