"""Model bundles: everything the online controller needs, in one folder.

- :mod:`mpcshare.bundle.bundle` — :class:`ModelBundle`, :func:`save_bundle` (atomic) and
  :func:`load_bundle` (checked against the manifest);
- :mod:`mpcshare.bundle.manifest` — the files of each format version and the manifest's check;
- :mod:`mpcshare.bundle.rule` — :class:`CalibratedRule`, the calibrated hand-over rule (typed, versioned);
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
from mpcshare.bundle.rule import RULE_VERSION, CalibratedRule

__all__ = ["BUNDLE_FILES", "FORMAT_VERSION", "RULE_VERSION", "BundleError", "CalibratedRule", "ModelBundle",
           "check_bundle_target", "is_bundle", "load_bundle", "save_bundle"]
